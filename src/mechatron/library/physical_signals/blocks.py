"""Physical-signal math and the converters between causal and physical signals."""

import casadi as ca

from mechatron.core import Input, Output, Parameter, der
from mechatron.library.physical_signals.interfaces import UnitBlock, si_factor, unit_expr

__all__ = ["SignalToPhysical", "PhysicalToSignal", "PSConstant", "PSGain", "PSAdd",
           "PSSubtract", "PSProduct", "PSSaturation", "PSIntegrator"]


class SignalToPhysical(UnitBlock):
    """Causal signal to physical signal (Simscape: Simulink-PS Converter).

    The input ``u`` is a plain number read in ``unit``; the output is the SI value
    ``y = factor u`` (``factor`` = 1 for SI units, 1e-3 for ``"mV"``, 2 pi / 60 for
    ``"rpm"``) and carries the unit, so that connecting it to an input of another
    dimension is a :class:`~mechatron.errors.UnitError` when the model compiles.

    Keywords: ``unit`` (default ``"1"``). Limitations: no offset units (degC).
    """

    unit_args = {"unit": "1"}
    u = Input("1", doc="Signal, a number in the converter's unit")
    y = Output("1", doc="Physical signal in SI")
    factor = 1.0   # SI value of one `unit`, set by the unit keyword

    @classmethod
    def declare(cls, unit):
        factor, si = si_factor(unit, f"SignalToPhysical(unit={unit!r})")
        return {"y": Output(si, doc=f"Physical signal in {si}"), "factor": factor}

    def equations(self):
        return [self.y == self.factor * self.u]


class PhysicalToSignal(UnitBlock):
    """Physical signal to causal signal (Simscape: PS-Simulink Converter).

    The input ``u`` carries ``unit`` (its dimension is checked against the physical
    signal connected to it); the output ``y = u / factor`` is a plain number in
    ``unit`` (e.g. ``unit="rpm"`` turns rad/s into rpm).

    Keywords: ``unit`` (default ``"1"``). Limitations: no offset units (degC).
    """

    unit_args = {"unit": "1"}
    u = Input("1", doc="Physical signal in SI")
    y = Output("1", doc="Signal, a number in the converter's unit")
    factor = 1.0   # SI value of one `unit`, set by the unit keyword

    @classmethod
    def declare(cls, unit):
        factor, si = si_factor(unit, f"PhysicalToSignal(unit={unit!r})")
        return {"u": Input(si, doc=f"Physical signal in {si}"), "factor": factor}

    def equations(self):
        return [self.y == self.u / self.factor]


class PSConstant(UnitBlock):
    """Constant physical signal (Simscape: PS Constant): ``y = value`` in ``unit``."""

    unit_args = {"unit": "1"}
    y = Output("1", doc="Output")
    value = Parameter("1", default=1.0, doc="Value")

    @classmethod
    def declare(cls, unit):
        return {"y": Output(unit, doc=f"Output ({unit})"),
                "value": Parameter(unit, default=1.0, doc=f"Value ({unit})")}

    def equations(self):
        return [self.y == self.value]


class PSGain(UnitBlock):
    """Gain with units (Simscape: PS Gain): ``y = K u``.

    Keywords: ``unit_in`` (default ``"1"``) and ``unit_out`` (default ``unit_in``); the
    gain ``K`` has the unit ``unit_out / unit_in`` and may be given as a quantity
    (``PSGain(unit_in="A", unit_out="N", K="2.5 N/A")``).
    """

    unit_args = {"unit_in": "1", "unit_out": ""}
    u = Input("1", doc="Input")
    y = Output("1", doc="Output")
    K = Parameter("1", default=1.0, doc="Gain")

    def __new__(cls, *args, **kwargs):
        if not kwargs.get("unit_out"):
            kwargs["unit_out"] = kwargs.get("unit_in", "1")
        return super().__new__(cls, **kwargs)

    @classmethod
    def declare(cls, unit_in, unit_out):
        unit_k = unit_expr(f"({unit_out})/({unit_in})")
        return {"u": Input(unit_in, doc=f"Input ({unit_in})"),
                "y": Output(unit_out, doc=f"Output ({unit_out})"),
                "K": Parameter(unit_k, default=1.0, doc=f"Gain ({unit_k})")}

    def equations(self):
        return [self.y == self.K * self.u]


class _TwoInputs(UnitBlock, partial=True):
    """Two inputs and an output of one unit."""

    unit_args = {"unit": "1"}
    u1 = Input("1", doc="First input")
    u2 = Input("1", doc="Second input")
    y = Output("1", doc="Output")

    @classmethod
    def declare(cls, unit):
        return {"u1": Input(unit, doc=f"First input ({unit})"),
                "u2": Input(unit, doc=f"Second input ({unit})"),
                "y": Output(unit, doc=f"Output ({unit})")}


class PSAdd(_TwoInputs):
    """Sum of two physical signals of the same unit (Simscape: PS Add): ``y = u1 + u2``.

    Keywords: ``unit`` (default ``"1"``).
    """

    def equations(self):
        return [self.y == self.u1 + self.u2]


class PSSubtract(_TwoInputs):
    """Difference of two physical signals of the same unit (Simscape: PS Subtract):
    ``y = u1 - u2``.

    Keywords: ``unit`` (default ``"1"``).
    """

    def equations(self):
        return [self.y == self.u1 - self.u2]


class PSProduct(UnitBlock):
    """Product of two physical signals (Simscape: PS Product): ``y = u1 u2`` in
    ``unit1 * unit2``."""

    unit_args = {"unit1": "1", "unit2": "1"}
    u1 = Input("1", doc="First factor")
    u2 = Input("1", doc="Second factor")
    y = Output("1", doc="Product")

    @classmethod
    def declare(cls, unit1, unit2):
        unit_y = unit_expr(f"({unit1})*({unit2})")
        return {"u1": Input(unit1, doc=f"First factor ({unit1})"),
                "u2": Input(unit2, doc=f"Second factor ({unit2})"),
                "y": Output(unit_y, doc=f"Product ({unit_y})")}

    def equations(self):
        return [self.y == self.u1 * self.u2]


class PSSaturation(UnitBlock):
    """Saturation (Simscape: PS Saturation): ``y = min(max(u, lower), upper)``.

    The two corners are events located by the solver. Limitations: ``lower <= upper``
    is the user's responsibility.
    """

    unit_args = {"unit": "1"}
    u = Input("1", doc="Input")
    y = Output("1", doc="Saturated output")
    upper = Parameter("1", default=1.0, doc="Upper limit")
    lower = Parameter("1", default=-1.0, doc="Lower limit")

    @classmethod
    def declare(cls, unit):
        return {"u": Input(unit, doc=f"Input ({unit})"),
                "y": Output(unit, doc=f"Saturated output ({unit})"),
                "upper": Parameter(unit, default=1.0, doc=f"Upper limit ({unit})"),
                "lower": Parameter(unit, default=-1.0, doc=f"Lower limit ({unit})")}

    def equations(self):
        return [self.y == ca.if_else(self.u > self.upper, self.upper,
                                     ca.if_else(self.u < self.lower, self.lower, self.u))]


class PSIntegrator(UnitBlock):
    """Integrator (Simscape: PS Integrator): ``dy/dt = u``, ``y`` in ``unit * s``.

    The initial output is the start value of ``y`` (``PSIntegrator(unit="A", y=0.1)``,
    default 0).
    """

    unit_args = {"unit": "1"}
    u = Input("1", doc="Input")
    y = Output("s", start=0.0, doc="Integral of the input")

    @classmethod
    def declare(cls, unit):
        unit_y = unit_expr(f"({unit})*(s)")
        return {"u": Input(unit, doc=f"Input ({unit})"),
                "y": Output(unit_y, start=0.0, doc=f"Integral of the input ({unit_y})")}

    def equations(self):
        return [der(self.y) == self.u]
