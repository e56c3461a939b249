"""Electrical sources and the reference (ground)."""

from mechatron.core import Component, Input, Parameter
from mechatron.library.electrical.interfaces import OnePort, Pin


class ElectricalReference(Component, reference=True):
    """Electrical ground: ``port.v = 0``. Every circuit needs one."""

    port = Pin(doc="Grounded pin")

    def equations(self):
        return [self.port.v == 0]


class DCVoltageSource(OnePort):
    """Ideal constant voltage source: ``v = V`` whatever the current."""

    V = Parameter("V", default=1.0, doc="Voltage, p.v - n.v")

    def equations(self):
        return [self.v == self.V]


class ControlledVoltageSource(OnePort):
    """Ideal voltage source driven by a signal: ``v = u``."""

    u = Input("V", doc="Commanded voltage, p.v - n.v")

    def equations(self):
        return [self.v == self.u]


class DCCurrentSource(OnePort):
    """Ideal constant current source: ``i = I`` flows from p through the source to n.

    A positive ``I`` therefore pushes current out of ``n`` into the circuit.
    """

    I = Parameter("A", default=1.0, doc="Current from p to n through the source")  # noqa: E741

    def equations(self):
        return [self.i == self.I]
