"""Translational connector and the two-flange partial component."""

from mechatron.core import Across, Component, Connector, Through, Variable
from mechatron.core.domains import TRANSLATIONAL


class Flange(Connector, domain=TRANSLATIONAL):
    """Translational flange."""

    v = Across("m/s", doc="Velocity of the flange",
               hint="Is a translational reference missing, or a flange left unconnected?")
    f = Through("N", doc="Force flowing into the component at this flange")


class TwoFlange(Component, partial=True):
    """Flanges ``A`` and ``B``; ``v = A.v - B.v``; force ``f`` enters at A, leaves at B."""

    A = Flange(doc="Flange A")
    B = Flange(doc="Flange B")
    v = Variable("m/s", doc="Relative velocity, A.v - B.v")
    f = Variable("N", doc="Force through the component from A to B")

    def equations(self):
        return [self.v == self.A.v - self.B.v,
                self.A.f + self.B.f == 0,
                self.f == self.A.f]
