"""The permanent-magnet synchronous machine: MSL's nominal operating point of its data
record, a hunting transient against an independent phase-frame SciPy model, the sign
conventions of the Park transform, and the trapezoidal variant's back EMF."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import machines
from mechatron.library import rotational as rot

# MSL's SM_PermanentMagnetData (no damper cage)
P, F, V_OC, R, J_R = 2, 50.0, 112.3, 0.03, 0.29
W_E = 2 * math.pi * F
L = 0.4 / W_E                          # L_s_sigma + L_md = (0.1 + 0.3) / (2 pi 50)
PSI = math.sqrt(2) * V_OC / W_E
W_NOM = W_E / P
# MSL's SMPM_VoltageSource: I_dq = (-53.5, 84.6) A RMS at 181.4 N*m, 1500 rpm, ~100 V
I_D, I_Q = math.sqrt(2) * -53.5, math.sqrt(2) * 84.6
TWO_PI_3 = 2 * math.pi / 3


def steady_voltages(i_d, i_q, w_e=W_E):
    """v_d, v_q of the steady state (d/dt = 0 in the dq equations)."""
    return R * i_d - w_e * L * i_q, R * i_q + w_e * (L * i_d + PSI)


def phase_source(v_d, v_q):
    """Amplitude and phase of v_k = -v_d cos(theta_k) + v_q sin(theta_k) written as
    V sin(theta_k + delta)."""
    return math.hypot(v_d, v_q), math.atan2(-v_d, v_q)


def supplied_machine(shaft, J_load=None, w0=None, T_load=None, **machine):
    """The PMSM fed by three 50 Hz voltage sources (star, grounded neutral) at the voltage
    of MSL's nominal point; the shaft either driven at w_nom or free with a load."""
    V, delta = phase_source(*steady_voltages(I_D, I_Q))
    m = mt.System("smpm")
    m.add("ground", el.ElectricalReference())
    m.add("fixed", rot.RotationalReference())
    pm = m.add("pm", machines.PMSM(**machine))
    for k, name in enumerate("abc"):
        src = m.add(f"v_{name}", el.ACVoltageSource(V_amp=V, f=F,
                                                    phase=delta - k * TWO_PI_3))
        m.connect(src.p, getattr(pm, name))
        m.connect(src.n, m.ground.port)
    m.connect(pm.support, m.fixed.port)
    if shaft == "speed":
        drive = m.add("drive", rot.IdealAngularVelocitySource())
        m.add("w_set", blocks.Constant(value=W_NOM))
        m.connect(m.w_set.y, drive.w_ref)
        m.connect(drive.A, pm.flange)
        m.connect(drive.B, m.fixed.port)
    else:
        load = m.add("load", rot.Inertia(J=J_load, w=w0))
        torque = m.add("torque", rot.ConstantTorque(T=-T_load))
        m.connect(pm.flange, load.port, torque.A)
        m.connect(torque.B, m.fixed.port)
    return m


def test_nominal_operating_point_of_the_data_record():
    # shaft held at 1500 rpm; after the electrical transient (L/R = 42 ms, 0.6 s run) the
    # currents are MSL's, the torque its nominal 181.4 N*m (given to 4 digits) and the
    # terminal voltage about 100 V RMS per phase
    res = mt.simulate(supplied_machine("speed"), 0.6, rtol=1e-10, atol=1e-10,
                      t_out=np.linspace(0.5, 0.6, 101))
    assert res.final("pm.airgap.i_d") == pytest.approx(I_D, rel=1e-6)
    assert res.final("pm.airgap.i_q") == pytest.approx(I_Q, rel=1e-6)
    assert res.final("pm.airgap.T") == pytest.approx(181.4, rel=5e-4)
    v_d, v_q = steady_voltages(I_D, I_Q)
    assert math.hypot(v_d, v_q) / math.sqrt(2) == pytest.approx(100.0, rel=1e-3)
    # the phase currents are the inverse Park transform: RMS = |i_dq| / sqrt(2)
    i_a = res["pm.a.i"]
    assert np.sqrt(np.mean(i_a[:-1] ** 2)) == pytest.approx(math.hypot(53.5, 84.6),
                                                            rel=1e-6)
    # torque on the shaft: the speed source holds the machine's torque
    assert res.final("drive.tau") == pytest.approx(res.final("pm.airgap.T"), rel=1e-9)


def phase_frame_reference(t_stop, t_eval, T_load, J_load):
    """Independent model: phase currents i_a, i_b as states, the star point solved from
    the three phase equations, back EMF p psi w sin(p phi - k 2pi/3), the rotor free."""
    V, delta = phase_source(*steady_voltages(I_D, I_Q))

    def rhs(t, x):
        i_a, i_b, phi, w = x
        i = np.array([i_a, i_b, -i_a - i_b])
        th = P * phi - np.arange(3) * TWO_PI_3
        e = P * PSI * w * np.sin(th)
        v = V * np.sin(W_E * t + delta - np.arange(3) * TWO_PI_3)
        v_n = (v.sum() - e.sum()) / 3
        di = (v - v_n - R * i - e) / L
        T = P * PSI * np.dot(np.sin(th), i)
        return [di[0], di[1], w, (T - T_load) / (J_R + J_load)]

    sol = solve_ivp(rhs, (0, t_stop), [0.0, 0.0, 0.0, W_NOM], t_eval=t_eval,
                    method="DOP853", rtol=1e-11, atol=1e-10)
    return sol.y


def test_hunting_transient_against_an_independent_phase_frame_model():
    # free rotor plus MSL's load inertia at 1500 rpm, nominal load torque, currents 0 at
    # t = 0: the rotor swings about its load angle (no damper cage, lightly damped by R)
    t = np.linspace(0.0, 0.3, 301)
    res = mt.simulate(supplied_machine("free", J_load=0.29, w0=W_NOM, T_load=181.4),
                      0.3, t_out=t, rtol=1e-10, atol=1e-10)
    i_a, i_b, phi, w = phase_frame_reference(0.3, t, 181.4, 0.29)
    assert np.ptp(w) > 1.0                       # it does swing
    np.testing.assert_allclose(res["load.w"], w, atol=1e-5 * W_NOM)
    np.testing.assert_allclose(res["pm.a.i"], i_a, atol=1e-5 * 150)
    np.testing.assert_allclose(res["pm.b.i"], i_b, atol=1e-5 * 150)
    np.testing.assert_allclose(res["pm.airgap.phi"], phi, atol=1e-6)


class OpenTrapezoidal(mt.Component):
    """Trapezoidal machine turned at constant speed, its phases loaded by 1 MOhm."""

    pm = machines.PMSM(emf="trapezoidal", p=4)
    drive = rot.IdealAngularVelocitySource()
    w_set = blocks.Constant(value=50.0)
    fixed = rot.RotationalReference()
    ground = el.ElectricalReference()
    ra = el.Resistor(R=1e6)
    rb = el.Resistor(R=1e6)
    rc = el.Resistor(R=1e6)

    def equations(self):
        return [mt.connect(self.w_set.y, self.drive.w_ref),
                mt.connect(self.drive.A, self.pm.flange),
                mt.connect(self.drive.B, self.pm.support, self.fixed.port),
                mt.connect(self.pm.a, self.ra.p), mt.connect(self.pm.b, self.rb.p),
                mt.connect(self.pm.c, self.rc.p),
                mt.connect(self.ra.n, self.rb.n, self.rc.n, self.ground.port)]


def test_trapezoidal_variant_has_the_flat_topped_line_voltage():
    assert type(machines.PMSM(emf="trapezoidal")) is machines.TrapezoidalPMSM
    with pytest.raises(ValueError, match="'sinusoidal' or 'trapezoidal'"):
        machines.PMSM(emf="square")
    t = np.linspace(0.0, 0.05, 2001)
    res = mt.simulate(OpenTrapezoidal(), 0.05, t_out=t, rtol=1e-10, atol=1e-12)
    th = 4 * 50.0 * t
    shape = np.array([machines.trapezoid(float(x)) - machines.trapezoid(float(x) - TWO_PI_3)
                      for x in th])
    # open circuit: line voltage = difference of the back EMFs, peak 2 p psi w on the
    # flat tops (the 1 MOhm load draws < 0.1 mA through 1.3 mH: negligible, once its
    # nanosecond time constant L/R has passed after t = 0, where the currents start at 0)
    np.testing.assert_allclose((res["pm.a.v"] - res["pm.b.v"])[1:],
                               4 * PSI * 50.0 * shape[1:], atol=1e-6 * 4 * PSI * 50.0 * 2)
    assert (res["pm.a.v"] - res["pm.b.v"]).max() == pytest.approx(2 * 4 * PSI * 50.0,
                                                                  rel=1e-6)
