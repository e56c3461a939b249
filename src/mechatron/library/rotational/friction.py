"""Rotational friction elements with a true stuck mode (Modelica's ``PartialFriction``):
clutch, brake, one-way clutch, bearing friction.

While stuck the relative speed is held exactly (the relative acceleration is zero) and
the friction torque is the unknown that keeps it so; the element breaks away when that
torque exceeds the static limit, and sticks again when the relative speed crosses zero.
Mode changes are events located by the solver; see
:mod:`mechatron.library.rotational.stickslip` for the mode logic. The smooth elements
(:class:`~mechatron.library.rotational.FrictionClutch`,
:class:`~mechatron.library.rotational.RotationalFriction`) stay available: they need no
events but only approximate sticking.
"""

import casadi as ca
import numpy as np

from mechatron.core import Discrete, Input, Parameter, Variable, der
from mechatron.errors import DataError
from mechatron.library.blocks.interfaces import piecewise_linear
from mechatron.library.rotational.interfaces import TwoFlange
from mechatron.library.rotational.stickslip import initial_mode, stick_slip

__all__ = ["PartialFriction", "Clutch", "Brake", "OneWayClutch", "BearingFriction",
           "speed_table", "SpeedTableOption"]


def speed_table(rows, name: str, owner: str, start_at_zero: bool = True) -> np.ndarray:
    """Rows ``(speed, value)`` of a friction table as a 2-column array (speeds >= 0,
    strictly increasing, the first at 0), or a clear error naming the element."""
    try:
        arr = np.asarray(rows, dtype=float)
    except (TypeError, ValueError):
        raise DataError(f"{owner}: {name} must be rows (speed, value) of numbers, got "
                        f"{rows!r}.") from None
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 1 \
            or not np.all(np.isfinite(arr)):
        raise DataError(f"{owner}: {name} must be rows (speed, value) of finite numbers, "
                        f"got {rows!r}.")
    if start_at_zero and arr[0, 0] != 0.0:
        raise DataError(f"{owner}: {name} must start at speed 0, got {arr[0, 0]}. Add a "
                        "row for speed 0 (the value at rest sets the static limit).")
    if np.any(np.diff(arr[:, 0]) <= 0):
        raise DataError(f"{owner}: {name} speeds must be strictly increasing, got "
                        f"{list(arr[:, 0])}.")
    if arr.shape[0] == 1:      # a constant
        arr = np.vstack([arr, [arr[0, 0] + 1.0, arr[0, 1]]])
    return arr


def table_value(x, table: np.ndarray):
    """Linear interpolation in ``table`` at ``x`` (end values held; kinks, no events)."""
    return piecewise_linear(x, table[:, 0], table[:, 1])


class SpeedTableOption:
    """Mixin for a friction element with an optional table over speed, given as the
    constructor keyword named by ``table_keyword`` (rows checked by
    :func:`speed_table`); the checked array, or None, is ``self._table``."""

    table_keyword = "stribeck_table"

    def __init__(self, **kwargs):
        rows = kwargs.pop(self.table_keyword, None)
        super().__init__(**kwargs)
        self._table = None if rows is None else \
            speed_table(rows, self.table_keyword, type(self).__name__)


class PartialFriction(TwoFlange, partial=True):
    """Stuck/sliding friction between flanges A and B (Modelica's ``PartialFriction``).

    Modes (``mode``): 1 sliding forward (``w > 0``), 0 stuck (``a = 0``, the torque is
    the unknown), -1 sliding backward. A subclass adds the torque laws with
    :func:`~mechatron.library.rotational.stickslip.stick_slip`. The start mode follows the
    start speed: ``mode = sign(w)`` at t0, and a stuck start breaks away at once if it
    must. Both flanges need inertia (or a prescribed motion) on some side: while stuck
    the two sides move as one body.
    """

    J_s = Parameter("kg*m^2", default=1.0, min=0,
                    doc="Scale of the stuck equation J_s a = 0 (any positive value)")
    a = Variable("rad/s^2", doc="Relative angular acceleration, der(w)")
    mode = Discrete("1", start=0, kind="integer",
                    doc="1 sliding forward, 0 stuck, -1 sliding backward")
    w_lock = Discrete("rad/s", start=0.0,
                      doc="Relative speed at the last lock (0 up to the event location)")

    _backward = True       # a freewheel has no backward sliding mode

    def equations(self):
        return [self.a == der(self.w)]

    def initial_equations(self):
        return [initial_mode(self.mode, self.w, self._backward)]


class _DiscFriction(SpeedTableOption, PartialFriction, partial=True):
    """Friction discs pressed together by a normal force (clutch and brake)."""

    f_n = Input("N", doc="Normal force pressing the discs together")
    mu = Parameter("1", default=0.3, min=0,
                   doc="Kinetic friction coefficient (when no mu_table is given)")
    peak = Parameter("1", default=1.0, min=1,
                     doc="Static friction coefficient / kinetic one at zero slip")
    R = Parameter("m", default=0.1, min=0, doc="Effective friction radius")
    n = Parameter("1", default=1, min=1, doc="Number of friction surfaces")
    w_ref = Parameter("rad/s", default=1.0, min=0,
                      doc="Unit of the speed column of mu_table")

    table_keyword = "mu_table"

    def _mu(self, speed):
        if self._table is None:
            return self.mu
        return table_value(speed / self.w_ref, self._table)

    def equations(self):
        fn = ca.fmax(self.f_n, 0 * self.f_n)
        cgeo = self.n * self.R
        kinetic = cgeo * fn * self._mu(ca.fabs(self.w))
        static = self.peak * cgeo * fn * self._mu(0 * self.w)
        return stick_slip(self.mode, self.w, self.w_lock, self.a, self.tau, self.J_s,
                          kinetic, -kinetic, static, static)


class Clutch(_DiscFriction):
    """Disc clutch with a true stuck mode, engaged by the normal force ``f_n``.

    With ``fn = max(f_n, 0)``, the slip speed ``w = A.w - B.w`` and ``cgeo = n R``::

        sliding:  tau = cgeo fn mu(|w|) sign(w)      (mu constant, or mu_table)
        stuck:    der(w) = 0, tau = whatever holds it, while |tau| <= peak cgeo fn mu(0)

    It locks when the slip speed crosses zero and opens (breaks away) when the torque it
    transmits exceeds ``peak cgeo fn mu(0)``. ``tau`` enters at A (the torque from the A
    side to the B side). ``mu_table``: rows ``(|w| / w_ref, mu)`` from speed 0, linear
    between them, the last value held. With ``f_n <= 0`` the clutch is open (no torque
    in either mode). Reference: Modelica.Mechanics.Rotational.Components.Clutch.
    """


class Brake(_DiscFriction):
    """Disc brake with a true stuck mode: the shaft at A, the housing at B (connect B to a
    :class:`~mechatron.library.rotational.RotationalReference` for a fixed housing).

    With ``fn = max(f_n, 0)``, ``w = A.w - B.w`` and ``cgeo = n R``::

        sliding:  tau = cgeo fn mu(|w|) sign(w)      (mu constant, or mu_table)
        stuck:    der(w) = 0 while |tau| <= peak cgeo fn mu(0)

    An inertia ``J`` spinning at ``w0`` under a constant ``f_n`` and constant ``mu``
    stops at ``t = J w0 / (cgeo fn mu)`` and stays stopped while the load torque is below
    the static limit. ``mu_table``: rows ``(|w| / w_ref, mu)``. Reference:
    Modelica.Mechanics.Rotational.Components.Brake.
    """


class OneWayClutch(PartialFriction):
    """One-way clutch (freewheel, sprag): free for ``w = A.w - B.w > 0``, locked against
    ``w < 0`` with no torque limit.

    Equations::

        freewheeling (w > 0):  tau = T_drag
        locked:                der(w) = 0, tau <= T_drag (any negative torque is held)

    It locks when ``w`` falls to zero and freewheels again as soon as the torque it holds
    turns positive (exceeds ``T_drag``). A start with ``w < 0`` starts locked at that
    speed. Reference: the freewheel of Modelica.Mechanics.Rotational.Components.OneWayClutch.
    """

    T_drag = Parameter("N*m", default=0.0, min=0, doc="Drag torque while freewheeling")
    _backward = False

    def equations(self):
        return stick_slip(self.mode, self.w, self.w_lock, self.a, self.tau, self.J_s,
                          self.T_drag, 0 * self.T_drag, self.T_drag, None)


def stribeck(speed, table, F_C, F_brk, w_S, b):
    """``F_C + (F_brk - F_C) g(speed / w_S) + b speed`` with ``g = exp(-x^2)`` or the
    table ``g`` (rows ``(x, g)``); the value at zero speed is the static limit."""
    if table is None:
        g = ca.exp(-(speed / w_S) ** 2)
    else:
        g = table_value(speed / w_S, table)
    return F_C + (F_brk - F_C) * g + b * speed


class BearingFriction(SpeedTableOption, PartialFriction):
    """Bearing friction with a true stuck mode between a shaft (A) and its support (B).

    Kinetic torque (Stribeck, Coulomb and viscous parts) for ``w = A.w - B.w``::

        tau = (T_C + (T_brk - T_C) g(|w| / w_S) + b |w|) sign(w),   g(x) = exp(-x^2)
        stuck: der(w) = 0 while |tau| <= T_brk g(0) + T_C (1 - g(0))

    so the break-away torque is ``T_brk`` (with the default ``g``). ``stribeck_table``:
    rows ``(x, g)`` from ``x = 0`` replacing ``exp(-x^2)``. Reference:
    Modelica.Mechanics.Rotational.Components.BearingFriction.
    """

    T_brk = Parameter("N*m", default=0.02, min=0, doc="Break-away (static) torque")
    T_C = Parameter("N*m", default=0.015, min=0, doc="Coulomb friction torque")
    w_S = Parameter("rad/s", default=0.1, min=0, doc="Stribeck speed")
    b = Parameter("N*m*s/rad", default=0.0, min=0, doc="Viscous friction coefficient")

    def equations(self):
        kinetic = stribeck(ca.fabs(self.w), self._table, self.T_C, self.T_brk, self.w_S,
                           self.b)
        static = stribeck(0 * self.w, self._table, self.T_C, self.T_brk, self.w_S, self.b)
        return stick_slip(self.mode, self.w, self.w_lock, self.a, self.tau, self.J_s,
                          kinetic, -kinetic, static, static)
