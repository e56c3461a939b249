"""Power converters as subsystems of library parts: the H-bridge (a full bridge of two
legs) and the three-phase two-level bridge, each leg two ideal switches with antiparallel
(freewheeling) diodes, driven by gate signals."""

from mechatron.core import Component, Input, Parameter, connect
from mechatron.library.electrical.ideal import IdealSwitch
from mechatron.library.electrical.interfaces import Pin
from mechatron.library.electrical.passive import Diode

__all__ = ["HalfBridge", "HBridge", "ThreePhaseBridge"]


class SwitchData(Component, partial=True):
    """The switch and diode data every bridge of this module declares once and passes on
    to its legs."""

    R_on = Parameter("Ohm", default=1e-3, min=0, doc="Switch on-resistance (> 0)")
    G_off = Parameter("S", default=1e-8, min=0, doc="Switch off-conductance")
    V_f = Parameter("V", default=0.7, doc="Diode forward voltage")
    R_d = Parameter("Ohm", default=1e-3, min=0, doc="Diode on-resistance (> 0)")
    G_d = Parameter("S", default=1e-8, min=0, doc="Diode off-conductance")


def _leg():
    """A :class:`HalfBridge` whose data are the enclosing bridge's own (passed on)."""
    d = SwitchData
    return HalfBridge(R_on=d.R_on, G_off=d.G_off, V_f=d.V_f, R_d=d.R_d, G_d=d.G_d)


class HalfBridge(SwitchData):
    """One leg of a bridge: a high-side and a low-side ideal switch, each with an
    antiparallel diode (MSL's ``PowerConverters`` legs, Simscape's ``Half-Bridge``).

    Equations (through its parts, ``IdealSwitch`` and ``Diode``)::

        high side, dc_p -> out:  i == if_else(fire_p > 0.5, v / R_on, G_off v) + diode(-v)
        low side,  out -> dc_n:  i == if_else(fire_n > 0.5, v / R_on, G_off v) + diode(-v)

    with ``diode(u) = (u - V_f)/R_d + G_d V_f`` for ``u > V_f``, else ``G_d u``, the
    freewheeling current (from ``out`` to ``dc_p`` above, from ``dc_n`` to ``out`` below).
    Switching and every diode's conduction are events. Never fire both switches of a leg
    at once (a short circuit of the supply through ``2 R_on``).
    """

    dc_p = Pin(doc="Positive DC terminal")
    dc_n = Pin(doc="Negative DC terminal")
    out = Pin(doc="Output (phase) terminal")
    fire_p = Input("1", doc="Gate of the high-side switch (closed above 0.5)")
    fire_n = Input("1", doc="Gate of the low-side switch (closed above 0.5)")

    s_p = IdealSwitch(R_on=SwitchData.R_on, G_off=SwitchData.G_off)
    d_p = Diode(Vf=SwitchData.V_f, Ron=SwitchData.R_d, Goff=SwitchData.G_d)
    s_n = IdealSwitch(R_on=SwitchData.R_on, G_off=SwitchData.G_off)
    d_n = Diode(Vf=SwitchData.V_f, Ron=SwitchData.R_d, Goff=SwitchData.G_d)

    def equations(self):
        return [connect(self.dc_p, self.s_p.p, self.d_p.n),
                connect(self.out, self.s_p.n, self.d_p.p, self.s_n.p, self.d_n.n),
                connect(self.dc_n, self.s_n.n, self.d_n.p),
                connect(self.fire_p, self.s_p.control),
                connect(self.fire_n, self.s_n.control)]


class HBridge(SwitchData):
    """Full (H) bridge: two :class:`HalfBridge` legs between ``dc_p`` and ``dc_n``, the
    load between ``out_a`` and ``out_b`` (MSL's ``DCDC.HBridge``, Simscape's
    ``H-Bridge`` with ideal switches).

    Gate signals (closed above 0.5): ``fire_p`` closes the high side of leg a and the low
    side of leg b (``out_a - out_b = +V_dc``, less the drops), ``fire_n`` the other
    diagonal (``-V_dc``). With both low, an inductive load's current freewheels through
    the diodes back into the supply::

        out_a.v - out_b.v == V_dc - 2 R_on i        fire_p   (i from out_a through the load)
        out_a.v - out_b.v == -(V_dc + 2 (V_f + R_d i))   both off, i > 0 (through diodes)

    Limitations: as :class:`HalfBridge`; never fire both diagonals at once.
    """

    dc_p = Pin(doc="Positive DC terminal")
    dc_n = Pin(doc="Negative DC terminal")
    out_a = Pin(doc="Output of leg a")
    out_b = Pin(doc="Output of leg b")
    fire_p = Input("1", doc="Closes high side a and low side b (positive output)")
    fire_n = Input("1", doc="Closes high side b and low side a (negative output)")

    leg_a = _leg()
    leg_b = _leg()

    def equations(self):
        return [connect(self.dc_p, self.leg_a.dc_p, self.leg_b.dc_p),
                connect(self.dc_n, self.leg_a.dc_n, self.leg_b.dc_n),
                connect(self.out_a, self.leg_a.out),
                connect(self.out_b, self.leg_b.out),
                connect(self.fire_p, self.leg_a.fire_p, self.leg_b.fire_n),
                connect(self.fire_n, self.leg_b.fire_p, self.leg_a.fire_n)]


class ThreePhaseBridge(SwitchData):
    """Three-phase two-level bridge (inverter or rectifier): three :class:`HalfBridge`
    legs between ``dc_p`` and ``dc_n`` with phase outputs ``a``, ``b``, ``c`` (MSL's
    ``DCAC.MultiPhase2Level``, Simscape's ``Converter (Three-Phase)`` with ideal
    switches).

    Gate signals per leg, ``fire_a_p`` / ``fire_a_n`` etc. (closed above 0.5). With leg
    ``x`` high side closed, ``x.v == dc_p.v - R_on i_x``; low side closed,
    ``x.v == dc_n.v + R_on (-i_x)`` (``i_x`` out of the phase terminal); with both open
    the phase current freewheels through a diode. With all gates low it is a six-pulse
    diode rectifier.
    """

    dc_p = Pin(doc="Positive DC terminal")
    dc_n = Pin(doc="Negative DC terminal")
    a = Pin(doc="Phase a")
    b = Pin(doc="Phase b")
    c = Pin(doc="Phase c")
    fire_a_p = Input("1", doc="Gate of the high-side switch of leg a")
    fire_a_n = Input("1", doc="Gate of the low-side switch of leg a")
    fire_b_p = Input("1", doc="Gate of the high-side switch of leg b")
    fire_b_n = Input("1", doc="Gate of the low-side switch of leg b")
    fire_c_p = Input("1", doc="Gate of the high-side switch of leg c")
    fire_c_n = Input("1", doc="Gate of the low-side switch of leg c")

    leg_a = _leg()
    leg_b = _leg()
    leg_c = _leg()

    def equations(self):
        return [connect(self.dc_p, self.leg_a.dc_p, self.leg_b.dc_p, self.leg_c.dc_p),
                connect(self.dc_n, self.leg_a.dc_n, self.leg_b.dc_n, self.leg_c.dc_n),
                connect(self.a, self.leg_a.out), connect(self.b, self.leg_b.out),
                connect(self.c, self.leg_c.out),
                connect(self.fire_a_p, self.leg_a.fire_p),
                connect(self.fire_a_n, self.leg_a.fire_n),
                connect(self.fire_b_p, self.leg_b.fire_p),
                connect(self.fire_b_n, self.leg_b.fire_n),
                connect(self.fire_c_p, self.leg_c.fire_p),
                connect(self.fire_c_n, self.leg_c.fire_n)]
