"""A user-written component: a DC motor written as its equations (Simscape language
equivalent), driven by an acausal source and loaded by a library inertia.

Run: python examples/user_component.py
"""

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import rotational as rot


class Motor(mt.Component):
    """Brush DC motor: electrical pins p, n and a shaft flange.

    Equations: ``v = R i + L di/dt + k w`` and ``tau = -k i`` at the shaft (torque flows
    out of the motor into the load).
    """

    p = el.Pin(doc="Positive terminal")
    n = el.Pin(doc="Negative terminal")
    shaft = rot.Flange(doc="Rotor shaft")
    R = mt.Parameter("Ohm", default=7.1, min=0, doc="Armature resistance")
    L = mt.Parameter("H", default=3.408e-4, min=0, doc="Armature inductance")
    k = mt.Parameter("V*s/rad", default=0.151, min=0, doc="Motor constant")
    i = mt.Variable("A", start=0.0, doc="Armature current")

    def equations(self):
        v = self.p.v - self.n.v
        return [self.p.i == self.i, self.n.i == -self.i,
                v == self.R * self.i + self.L * mt.der(self.i) + self.k * self.shaft.w,
                self.shaft.tau == -self.k * self.i]


def build():
    m = mt.System("user_motor")
    src = m.add("src", el.DCVoltageSource(V="19.2 V"))
    mot = m.add("motor", Motor())
    load = m.add("load", rot.Inertia(J="4.8e-6 kg*m^2"))
    fric = m.add("friction", rot.RotationalDamper(D=1.236e-4))
    fixed = m.add("fixed", rot.RotationalReference())
    gnd = m.add("gnd", el.ElectricalReference())
    m.connect(src.p, mot.p)
    m.connect(src.n, mot.n, gnd.port)
    m.connect(mot.shaft, load.port, fric.A)
    m.connect(fric.B, fixed.port)
    return m


if __name__ == "__main__":
    res = mt.simulate(build(), 0.5, rtol=1e-8)
    print(f"final speed {res.final('load.w'):.4f} rad/s, current {res.final('motor.i'):.5f} A")
