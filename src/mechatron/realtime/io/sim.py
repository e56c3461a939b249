"""``sim``: the controller is a function in the plant's process."""

from __future__ import annotations

import random
from typing import Callable, Sequence

from mechatron.realtime.io.base import Command, PlantIO

__all__ = ["SimIO"]


class SimIO(PlantIO):
    """The controller as a function ``controller(seq, t, sensors) -> values`` (a tuple
    of floats, the duty first) called on each :meth:`write`.

    ``loss`` drops each sample and each command with that probability (seeded), to test
    the plant's and the controller's handling of lost samples without a network.
    """

    kind = "sim"

    def __init__(self, controller: Callable[[int, float, Sequence[float]], Sequence[float]],
                 *, loss: float = 0.0, seed: int = 1) -> None:
        super().__init__()
        self.controller = controller
        self.loss = float(loss)
        self._rng = random.Random(seed)
        self._pending: Command | None = None

    def write(self, seq, t, sensors) -> None:
        self.stats.sent += 1
        self._pending = None
        if self.loss and self._rng.random() < self.loss:
            self.stats.dropped_on_purpose += 1
            return
        values = tuple(float(v) for v in self.controller(seq, t, sensors))
        if self.loss and self._rng.random() < self.loss:
            self.stats.dropped_on_purpose += 1
            return
        self._pending = Command(seq, values)

    def read(self, seq, deadline) -> Command | None:
        cmd, self._pending = self._pending, None
        if cmd is None or cmd.seq != seq:
            self.stats.lost += 1
            return None
        self.stats.received += 1
        return cmd
