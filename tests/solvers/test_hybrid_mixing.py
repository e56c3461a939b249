"""Signal blocks mixed with physical networks: a sampled PI drives the acausal DC motor
(library parts) through a controlled voltage source and reads it through a speed sensor;
the result equals the same loop written by hand with the exact discretisation."""

import sys
from pathlib import Path

import numpy as np

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import rotational as rot

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "library" / "blocks"))
from test_blocks_discrete import KI, KP, TS, W_REF, hand_loop  # noqa: E402

V, R, L, K, J, B = 19.2, 7.1, 3.408e-4, 0.151, 4.8e-6, 1.236e-4


def acausal_pi_loop():
    m = mt.System("pi_motor")
    ref = m.add("ref", blocks.Constant(value=W_REF))
    err = m.add("err", blocks.Subtract())
    pi = m.add("pi", blocks.DiscretePID(Kp=KP, Ki=KI, Ts=TS))
    src = m.add("src", el.ControlledVoltageSource())       # signal -> volts
    r = m.add("r", el.Resistor(R=R))
    ind = m.add("l", el.Inductor(L=L))
    emf = m.add("emf", em.RotationalEMF(k=K))
    j = m.add("j", rot.Inertia(J=J))
    d = m.add("d", rot.RotationalDamper(D=B))
    speed = m.add("speed", rot.AngularVelocitySensor())     # rad/s -> signal
    g = m.add("g", el.ElectricalReference())
    f = m.add("f", rot.RotationalReference())
    m.connect(ref.y, err.u1)
    m.connect(speed.W, err.u2)
    m.connect(err.y, pi.u)
    m.connect(pi.y, src.u)
    m.connect(src.p, r.p)
    m.connect(r.n, ind.p)
    m.connect(ind.n, emf.p)
    m.connect(emf.n, src.n, g.port)
    m.connect(emf.A, j.port, d.A, speed.A)
    m.connect(emf.B, d.B, f.port, speed.B)
    return m


def test_sampled_pi_on_the_acausal_motor_matches_the_hand_written_loop():
    n = 200
    t_out = np.concatenate([[0.0], (np.arange(n) + 0.5) * TS])
    res = mt.simulate(acausal_pi_loop(), t_out[-1], rtol=1e-11, atol=1e-12, t_out=t_out)
    np.testing.assert_allclose(res["pi.y"][1:], hand_loop(n), rtol=0, atol=1e-9)
    # the physical side sees the held controller output as its voltage
    np.testing.assert_array_equal(res["src.v"], res["pi.y"])
