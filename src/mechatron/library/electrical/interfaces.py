"""Electrical connector and the two-pin partial component."""

from mechatron.core import Across, Component, Connector, Through, Variable
from mechatron.core.domains import ELECTRICAL


class Pin(Connector, domain=ELECTRICAL):
    """Electrical pin."""

    v = Across("V", doc="Electric potential at the pin",
               hint="Is an electrical reference missing, or a pin left unconnected?")
    i = Through("A", doc="Current flowing into the pin")


class OnePort(Component, partial=True):
    """Two pins; current ``i`` enters at ``p`` and leaves at ``n``; ``v = p.v - n.v``."""

    p = Pin(doc="Positive pin")
    n = Pin(doc="Negative pin")
    v = Variable("V", doc="Voltage across, p.v - n.v")
    i = Variable("A", doc="Current from p to n through the component")

    def equations(self):
        return [self.v == self.p.v - self.n.v,
                self.p.i + self.n.i == 0,
                self.i == self.p.i]
