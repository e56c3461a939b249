"""Thermal connector and the two-port partial component."""

from mechatron.core import Across, Component, Connector, Through, Variable
from mechatron.core.domains import THERMAL


class HeatPort(Connector, domain=THERMAL):
    """Thermal port: temperature and the heat flow into the component."""

    T = Across("K", doc="Temperature at the port",
               hint="Is a thermal reference (fixed temperature) or a heat capacitor "
                    "missing, or a port left unconnected?")
    Q = Through("W", doc="Heat flow rate into the component at the port")


class TwoPort(Component, partial=True):
    """Two heat ports; heat ``Q`` enters at ``A`` and leaves at ``B``;
    ``dT = A.T - B.T``."""

    A = HeatPort(doc="Port A")
    B = HeatPort(doc="Port B")
    dT = Variable("K", doc="Temperature difference, A.T - B.T")
    Q = Variable("W", doc="Heat flow rate from A to B through the component")

    def equations(self):
        return [self.dT == self.A.T - self.B.T,
                self.A.Q + self.B.Q == 0,
                self.Q == self.A.Q]
