"""The HIL experiments: what is controlled, the reference and the controller gains
(:mod:`mechatron.realtime.loop` builds and runs them). A module of its own, light to
import: the command line reads these to describe its ``hil`` command."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Experiment", "EXPERIMENTS"]


@dataclass(frozen=True)
class Experiment:
    """One HIL experiment: what is controlled, the reference, the controller gains.

    ``reference`` is a tuple of ``(t_start, value)`` steps (the value holds until the
    next step; 0 before the first); ``quantity`` is ``"speed"`` (rad/s) or
    ``"position"`` (rad).
    """

    name: str
    quantity: str
    reference: tuple[tuple[float, float], ...]
    Kp: float
    Ki: float
    Kd: float = 0.0
    window_s: float = 1e-3     # length of the speed estimate's window, in s
    unit: str = "rad/s"
    doc: str = ""

    @property
    def ref_scale(self) -> float:
        """The size of the reference (largest |value|), the scale of ``rms_diff_percent``."""
        return max(abs(v) for _, v in self.reference)

    def ref_at(self, t):
        """The reference at times ``t`` (NumPy)."""
        t = np.asarray(t, dtype=float)
        r = np.zeros_like(t)
        for t0, v in self.reference:
            r = np.where(t >= t0 - 1e-12, v, r)
        return r


EXPERIMENTS = {
    "speed": Experiment(
        "speed", "speed", ((0.05, 80.0), (1.0, 40.0), (1.5, 100.0)), Kp=0.05, Ki=30.0,
        unit="rad/s",
        doc="PI speed control: steps to 80, 40 and 100 rad/s (motor limit ~122 rad/s)."),
    "position": Experiment(
        "position", "position", ((0.05, 10.0), (1.0, 4.0), (1.5, 12.0)), Kp=10.0, Ki=0.0,
        Kd=0.02, unit="rad",
        doc="PD position control with saturation: angle steps to 10, 4 and 12 rad."),
}
