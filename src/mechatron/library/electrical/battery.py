"""Battery: open-circuit voltage over state of charge, internal resistance, one RC branch
(the first-order Thevenin equivalent circuit; Simscape's ``Battery (Table-Based)`` with
one time constant, MSL's ``Batteries.BatteryStacks.CellRC``)."""

import numpy as np

from mechatron.core import Parameter, Variable, der
from mechatron.errors import DataError
from mechatron.library.blocks.interfaces import piecewise_linear
from mechatron.library.electrical.interfaces import OnePort

__all__ = ["Battery"]

#: A Li-ion (NMC) cell's open-circuit voltage, (state of charge, V): a typical curve.
LI_ION_OCV = ((0.0, 3.0), (0.05, 3.3), (0.1, 3.45), (0.2, 3.55), (0.4, 3.65), (0.6, 3.8),
              (0.8, 3.95), (0.9, 4.05), (1.0, 4.2))


class Battery(OnePort):
    """Battery cell or pack: open-circuit voltage ``v_oc(SOC)`` from a table, series
    resistance ``R0`` and one RC branch ``R1 || C1``. ``p`` is the positive terminal.

    Equations, with ``i`` the current into ``p`` (charging positive, discharging
    negative)::

        der(SOC) == i / (3600 Q)                (Q in A*h)
        v_oc == interp(SOC; ocv)                (linear in the table, held outside it)
        C1 der(v1) == i - v1 / R1
        v == n_s v_oc + R0 i + v1

    The table gives one cell's voltage; ``n_s`` cells in series multiply it (``R0``,
    ``R1``, ``C1`` and ``Q`` are those of the whole battery). Stored chemical energy is
    ``n_s 3600 Q int v_oc dSOC``; ``R0 i^2 + v1^2/R1`` is dissipated.

    Limitations: no temperature, no hysteresis, no ageing; the state of charge is not
    clipped to [0, 1] (the table holds its end values beyond). The table's numbers carry
    no units, so the dimension check is off for this class.

    Parameters
    ----------
    ocv : sequence of (SOC, V)
        Open-circuit voltage of one cell over the state of charge (strictly increasing
        SOC, at least two rows); the default is a typical Li-ion curve, 3.0 V to 4.2 V.
    """

    check_dimensions = False

    Q = Parameter("A*h", default=2.5, min=0, doc="Capacity (charge from SOC 0 to 1)")
    R0 = Parameter("Ohm", default=0.02, min=0, doc="Series (ohmic) resistance")
    R1 = Parameter("Ohm", default=0.015, min=0, doc="Resistance of the RC branch (> 0)")
    C1 = Parameter("F", default=2000.0, min=0, doc="Capacitance of the RC branch")
    n_s = Parameter("1", default=1, min=1, doc="Cells in series")
    SOC = Variable("1", start=1.0, doc="State of charge (0 empty, 1 full)")
    v_oc = Variable("V", doc="Open-circuit voltage of one cell")
    v1 = Variable("V", start=0.0, doc="Voltage across the RC branch")

    def __init__(self, ocv=LI_ION_OCV, **kwargs):
        super().__init__(**kwargs)
        where = f"Battery '{self.name or '(unnamed)'}'"
        try:
            arr = np.asarray(ocv, dtype=float)
        except (TypeError, ValueError):
            raise DataError(f"{where}: ocv must be rows (SOC, V) of numbers, got "
                            f"{ocv!r}.") from None
        if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 2 \
                or not np.all(np.isfinite(arr)) or np.any(np.diff(arr[:, 0]) <= 0):
            raise DataError(f"{where}: ocv must be at least two finite rows (SOC, V) with "
                            f"SOC strictly increasing, got {ocv!r}.")
        self._ocv = (arr[:, 0], arr[:, 1])

    def equations(self):
        soc, volts = self._ocv
        return [der(self.SOC) == self.i / (3600 * self.Q),
                self.v_oc == piecewise_linear(self.SOC, soc, volts),
                self.C1 * der(self.v1) == self.i - self.v1 / self.R1,
                self.v == self.n_s * self.v_oc + self.R0 * self.i + self.v1]
