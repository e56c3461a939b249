"""Rotational-translational converters: lead screw, rack and pinion, wheel and axle."""

import math

from mechatron.core import Component, Parameter, Variable, if_else
from mechatron.library.rotational.interfaces import Flange as RotationalFlange
from mechatron.library.translational.interfaces import Flange as TranslationalFlange

__all__ = ["RotTransConverter", "LeadScrew", "RackAndPinion", "WheelAndAxle"]


class RotTransConverter(Component, partial=True):
    """Grounded rotational-translational converter with direction-dependent efficiency.

    With the transmission ``m`` (m/rad) of the subclass::

        T.v = m R.w
        m T.f = -eta R.tau             while R.tau R.w >= 0 (power enters at R)
        eta_back m T.f = -R.tau        while R.tau R.w < 0  (power enters at T)
        P_loss = R.tau R.w + T.f T.v   (>= 0)

    A torque ``tau`` delivered into ``R`` therefore pushes the translational load with
    ``-T.f = eta tau / m``. The switch of direction is an event. Limitation: no
    self-locking (a screw with ``eta_back`` near 0 is nearly, not exactly, locked).
    """

    R = RotationalFlange(doc="Rotational flange (shaft, pinion, axle)")
    T = TranslationalFlange(doc="Translational flange (nut, rack, ground contact)")
    eta = Parameter("1", default=1.0, min=0, max=1,
                    doc="Efficiency, power from R to T")
    eta_back = Parameter("1", default=1.0, min=0, max=1,
                         doc="Efficiency, power from T to R")
    P_loss = Variable("W", doc="Power dissipated in the converter")

    def transmission(self):
        """The transmission ``m = T.v / R.w`` (m/rad), an expression of parameters."""
        raise NotImplementedError

    def equations(self):
        m = self.transmission()
        backward = self.R.tau * self.R.w < 0
        return [self.T.v == m * self.R.w,
                if_else(backward, self.eta_back * m * self.T.f + self.R.tau,
                        m * self.T.f + self.eta * self.R.tau) == 0,
                self.P_loss == self.R.tau * self.R.w + self.T.f * self.T.v]


class LeadScrew(RotTransConverter):
    """Lead screw (screw and nut, grounded case): ``m = lead / (2 pi)``.

    Equations: ``T.v = lead R.w / (2 pi)``; forward ``-T.f = 2 pi eta R.tau / lead``;
    backward ``R.tau = -eta_back lead T.f / (2 pi)``; ``P_loss = R.tau R.w + T.f T.v``.
    A right-hand thread (positive ``lead``) advances the nut (``T``) when the screw
    (``R``) turns positively.
    """

    lead = Parameter("m", default=5e-3, min=0, doc="Lead: nut travel per screw revolution")
    eta = Parameter("1", default=0.9, min=0, max=1, doc="Efficiency, screw driving nut")
    eta_back = Parameter("1", default=0.8, min=0, max=1,
                         doc="Efficiency, nut driving screw")

    def transmission(self):
        return self.lead / (2 * math.pi)


class RackAndPinion(RotTransConverter):
    """Rack and pinion: ``m = r`` (pinion pitch radius).

    Equations: ``T.v = r R.w``; forward ``-T.f = eta R.tau / r``; backward
    ``R.tau = -eta_back r T.f``; ``P_loss = R.tau R.w + T.f T.v``.
    """

    r = Parameter("m", default=0.02, min=0, doc="Pitch radius of the pinion")

    def transmission(self):
        return self.r


class WheelAndAxle(RotTransConverter):
    """Wheel (or pulley, drum) and axle: rolling without slip, ``m = r``.

    Equations: ``T.v = r R.w``; forward ``-T.f = eta R.tau / r``; backward
    ``R.tau = -eta_back r T.f``; ``P_loss = R.tau R.w + T.f T.v``. A positive axle
    speed moves the translational flange forward.
    """

    r = Parameter("m", default=0.3, min=0, doc="Wheel radius")

    def transmission(self):
        return self.r
