"""The interface of the plant's I/O backends (see :mod:`mechatron.realtime.io`)."""

from __future__ import annotations

import abc
import time
from dataclasses import asdict, dataclass
from typing import Sequence

__all__ = ["PlantIO", "Command", "LinkStats"]


@dataclass
class Command:
    """The controller's command for one step: ``values`` (the duty first), the step it
    answers and whether the controller filled in lost samples before it."""

    seq: int
    values: tuple[float, ...]
    filled: bool = False


@dataclass
class LinkStats:
    """Counters of one link, the same for every backend."""

    sent: int = 0              # samples written
    received: int = 0          # commands read in time for their step
    lost: int = 0              # steps whose command never came by the deadline
    late: int = 0              # commands that came after their step (dropped)
    bad_frames: int = 0        # frames with a wrong CRC, magic or length
    dropped_on_purpose: int = 0

    def as_dict(self) -> dict:
        return asdict(self)


class PlantIO(abc.ABC):
    """One end of the plant's link to its controller.

    ``write(seq, t, sensors)`` then ``read(seq, deadline)`` once per step; ``deadline``
    is an absolute ``time.monotonic()``. ``read`` returns the :class:`Command` for step
    ``seq`` or None when none came by the deadline (counted in :attr:`stats`), never
    later. Backends are context managers (``close`` on exit).
    """

    kind = "abstract"

    def __init__(self) -> None:
        self.stats = LinkStats()

    @abc.abstractmethod
    def write(self, seq: int, t: float, sensors: Sequence[float]) -> None:
        """Send the measurements of step ``seq`` (plant time ``t`` in s)."""

    @abc.abstractmethod
    def read(self, seq: int, deadline: float) -> Command | None:
        """The command for step ``seq``, or None at ``deadline`` (``time.monotonic()``)."""

    def start(self, timeout: float = 10.0) -> None:
        """Wait for the controller to say it is there (HELLO); a no-op by default."""

    def stop(self) -> None:
        """Tell the controller the run is over (STOP); a no-op by default."""

    def close(self) -> None:
        """Release the link."""

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    @staticmethod
    def now() -> float:
        return time.monotonic()
