"""Rotational connector and the two-flange partial component."""

from mechatron.core import Across, Component, Connector, Through, Variable
from mechatron.core.domains import ROTATIONAL


class Flange(Connector, domain=ROTATIONAL):
    """Rotational flange."""

    w = Across("rad/s", doc="Angular velocity of the flange",
               hint="Is a rotational reference missing, or a flange left unconnected?")
    tau = Through("N*m", doc="Torque flowing into the component at this flange")


class TwoFlange(Component, partial=True):
    """Flanges ``A`` and ``B``; ``w = A.w - B.w``; torque ``tau`` enters at A, leaves at B."""

    A = Flange(doc="Flange A")
    B = Flange(doc="Flange B")
    w = Variable("rad/s", doc="Relative angular velocity, A.w - B.w")
    tau = Variable("N*m", doc="Torque through the component from A to B")

    def equations(self):
        return [self.w == self.A.w - self.B.w,
                self.A.tau + self.B.tau == 0,
                self.tau == self.A.tau]
