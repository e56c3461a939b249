"""Electrical sensors: ideal, they draw no current (voltage) or drop no voltage (current)."""

from mechatron.core import Component, Output
from mechatron.library.electrical.interfaces import OnePort, Pin


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


class PowerSensor(Component):
    """Ideal power sensor (Modelica's ``PowerSensor``): a current path ``pc`` -> ``nc``
    (an ammeter, no voltage drop) and a voltage path ``pv``, ``nv`` (a voltmeter, no
    current).

    Equations: ``pc.v == nc.v``, ``pc.i + nc.i == 0``, ``pv.i == 0``, ``nv.i == 0`` and
    ``P == (pv.v - nv.v) pc.i``. With the current path in series with a load and the
    voltage path across it, ``P`` is the power the load absorbs.
    """

    pc = Pin(doc="Current path, positive pin (current enters here)")
    nc = Pin(doc="Current path, negative pin")
    pv = Pin(doc="Voltage path, positive pin")
    nv = Pin(doc="Voltage path, negative pin")
    P = Output("W", doc="Measured power (pv.v - nv.v) * current from pc to nc")

    def equations(self):
        return [self.pc.v == self.nc.v, self.pc.i + self.nc.i == 0,
                self.pv.i == 0, self.nv.i == 0,
                self.P == (self.pv.v - self.nv.v) * self.pc.i]
