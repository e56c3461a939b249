"""Magnetic connector and the two-port partial component."""

from mechatron.core import Across, Component, Connector, Through, Variable
from mechatron.core.domains import MAGNETIC


class MagneticPort(Connector, domain=MAGNETIC):
    """Magnetic port: magnetic potential (mmf) and the flux into the component."""

    mmf = Across("A", doc="Magnetic potential (magnetomotive force) at the port",
                 hint="Is a magnetic reference missing, or a port left unconnected?")
    phi = Through("Wb", doc="Magnetic flux into the component at the port")


class TwoPort(Component, partial=True):
    """Two magnetic ports; flux ``phi`` enters at ``A`` and leaves at ``B``;
    ``mmf = A.mmf - B.mmf``."""

    A = MagneticPort(doc="Port A")
    B = MagneticPort(doc="Port B")
    mmf = Variable("A", doc="Magnetomotive force across, A.mmf - B.mmf")
    phi = Variable("Wb", doc="Flux through the component from A to B")

    def equations(self):
        return [self.mmf == self.A.mmf - self.B.mmf,
                self.A.phi + self.B.phi == 0,
                self.phi == self.A.phi]
