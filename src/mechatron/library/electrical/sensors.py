"""Electrical sensors: ideal, they draw no current (voltage) or drop no voltage (current)."""

from mechatron.core import Output
from mechatron.library.electrical.interfaces import OnePort


class CurrentSensor(OnePort):
    """Ideal ammeter in series: ``v = 0``, output ``I = i`` (from p to n)."""

    I = Output("A", doc="Measured current from p to n")  # noqa: E741

    def equations(self):
        return [self.v == 0, self.I == self.i]


class VoltageSensor(OnePort):
    """Ideal voltmeter across p and n: ``i = 0``, output ``V = p.v - n.v``."""

    V = Output("V", doc="Measured voltage p.v - n.v")

    def equations(self):
        return [self.i == 0, self.V == self.v]
