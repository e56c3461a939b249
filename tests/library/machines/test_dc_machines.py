"""Machines built as subsystems: the permanent-magnet DC motor as one part against the
seed motor's network (the database's dc_motor) and the analytic final speed, used twice
with different parameters."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import machines
from mechatron.library import rotational as rot


class TwoMotors(mt.Component):
    s1 = el.DCVoltageSource(V=19.2)
    s2 = el.DCVoltageSource(V=12.0)
    m1 = machines.DCPermanentMagnet()
    m2 = machines.DCPermanentMagnet(R=3.0, k=0.1)
    g = el.ElectricalReference()
    f = rot.RotationalReference()

    def equations(self):
        return [mt.connect(self.s1.p, self.m1.p), mt.connect(self.s2.p, self.m2.p),
                mt.connect(self.s1.n, self.s2.n, self.m1.n, self.m2.n, self.g.port),
                mt.connect(self.m1.support, self.m2.support, self.f.port)]


def test_the_motor_part_equals_the_seed_network_and_its_final_speed():
    t = np.linspace(0, 0.3, 61)
    res = mt.simulate(TwoMotors(), 0.3, t_out=t, rtol=1e-11, atol=1e-13)
    seed = mt.models.get("dc_motor")
    ref = mt.simulate(seed.build("acausal"), 0.3, t_out=t, rtol=1e-11, atol=1e-13)
    np.testing.assert_allclose(res["m1.inertia.w"], ref["inertia.w"], atol=1e-9)
    np.testing.assert_allclose(res["m1.inductor.i"], ref["inductor.i"], atol=1e-9)
    B = 1.236e-4
    assert res.final("m2.inertia.w") == pytest.approx(0.1 * 12.0 / (3.0 * B + 0.1 ** 2),
                                                      rel=1e-8)
    # the open shaft carries no torque out; the armature current enters at p
    np.testing.assert_allclose(res["m1.flange.tau"], 0.0, atol=1e-12)
    np.testing.assert_allclose(res["m1.p.i"], res["m1.inductor.i"], atol=1e-12)


def test_the_motor_part_conserves_energy():
    res = mt.simulate(TwoMotors(), 0.05, t_out=np.linspace(0, 0.05, 50001), rtol=1e-11,
                      atol=1e-13)
    t, i, w = res.t, res["m1.inductor.i"], res["m1.inertia.w"]
    supplied = np.trapezoid(19.2 * i, t)
    lost = np.trapezoid(7.1 * i ** 2 + 1.236e-4 * w ** 2, t)
    stored = 0.5 * 3.408e-4 * i[-1] ** 2 + 0.5 * 4.8e-6 * w[-1] ** 2
    assert supplied == pytest.approx(lost + stored, rel=1e-5)
