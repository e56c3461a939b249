"""The squirrel-cage induction machine: the nominal point of MSL's data record (IMC_DOL:
161.4 N*m at 1440.45 rpm on 100 V, 50 Hz) from the steady-state equivalent circuit, and the
direct-on-line start-up against an independent SciPy model in the synchronous frame."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import machines
from mechatron.library import rotational as rot

# MSL's IM_SquirrelCageData
P, F, R_S, R_R, J_R = 2, 50.0, 0.03, 0.04, 0.29
W_S = 2 * math.pi * F
K = math.sqrt(1 - 0.0667)
X_SIG, X_M = 3 * (1 - K), 3 * K              # stray and main reactances at 50 Hz, Ohm
V_RMS = 100.0                                # per phase winding (IMC_DOL)
T_NOM, N_NOM = 161.4, 1440.45                # IMC_DOL's nominal load, N*m and rpm
TWO_PI_3 = 2 * math.pi / 3


def torque_of_slip(s):
    """Steady torque of the T-equivalent circuit at slip s (RMS phasors, 3 phases)."""
    z_r = R_R / s + 1j * X_SIG
    z_m = 1j * X_M
    z = R_S + 1j * X_SIG + z_m * z_r / (z_m + z_r)
    i_s = V_RMS / z
    i_r = i_s * z_m / (z_m + z_r)
    return 3 * abs(i_r) ** 2 * R_R / s / (W_S / P), i_s


def driven(T_load=None, fan=None, J_load=0.0, w0=0.0):
    """The machine on a three-phase 50 Hz supply (star, grounded neutral; 100 V RMS per
    winding, as MSL's delta-connected example gives each winding), loaded."""
    m = mt.System("aimc")
    m.add("ground", el.ElectricalReference())
    m.add("fixed", rot.RotationalReference())
    im = m.add("im", machines.InductionMachine())
    for k, name in enumerate("abc"):
        src = m.add(f"v_{name}", el.ACVoltageSource(V_amp=math.sqrt(2) * V_RMS, f=F,
                                                    phase=math.pi / 2 - k * TWO_PI_3))
        m.connect(src.p, getattr(im, name))
        m.connect(src.n, m.ground.port)
    load = m.add("load", rot.Inertia(J=J_load if J_load else 1e-9, w=w0))
    m.connect(im.flange, load.port)
    m.connect(im.support, m.fixed.port)
    if T_load is not None:
        torque = m.add("torque", rot.ConstantTorque(T=-T_load))
    else:
        torque = m.add("torque", rot.FanLoad(T_nom=fan[0], w_nom=fan[1]))
    m.connect(torque.A, load.port)
    m.connect(torque.B, m.fixed.port)
    return m


def test_the_equivalent_circuit_gives_msls_nominal_point():
    # the data record's nominal point, from the steady-state equivalent circuit alone
    s = brentq(lambda s: torque_of_slip(s)[0] - T_NOM, 1e-5, 0.1)
    n = (1 - s) * 60 * F / P
    assert n == pytest.approx(N_NOM, abs=0.05)         # MSL gives 1440.45 rpm


def test_nominal_operating_point_in_steady_state():
    # constant nominal load, started near its speed: the machine settles at the
    # equivalent circuit's slip and stator current
    s = brentq(lambda s: torque_of_slip(s)[0] - T_NOM, 1e-5, 0.1)
    w_nom = (1 - s) * W_S / P
    t = np.linspace(1.9, 2.0, 201)
    res = mt.simulate(driven(T_load=T_NOM, w0=w_nom), 2.0, t_out=t, rtol=1e-9,
                      atol=1e-9)
    assert res.final("im.inertia.w") == pytest.approx(w_nom, rel=1e-7)
    assert res.final("im.inertia.w") * 60 / (2 * math.pi) == pytest.approx(N_NOM, abs=0.05)
    i_a = res["im.a.i"][:-1]                 # 200 samples = 5 periods exactly
    assert np.sqrt(np.mean(i_a ** 2)) == pytest.approx(abs(torque_of_slip(s)[1]),
                                                       rel=1e-6)
    assert np.mean(res["im.airgap.T"]) == pytest.approx(T_NOM, rel=1e-7)


def synchronous_frame_reference(t_eval, J_load, fan):
    """Independent model: dq frame turning with the supply (v_d = sqrt(2) V, v_q = 0),
    the four currents as states through the inductance matrix, mechanical speed w.
    The supply's phase a is sqrt(2) V cos(w_s t), so phase a's current is
    i_d cos(w_s t) - i_q sin(w_s t)."""
    L_sig, L_m = X_SIG / W_S, X_M / W_S
    Ls, Lr = L_sig + L_m, L_sig + L_m
    M = np.array([[Ls, 0, L_m, 0], [0, Ls, 0, L_m], [L_m, 0, Lr, 0], [0, L_m, 0, Lr]])
    Minv = np.linalg.inv(M)
    v = np.array([math.sqrt(2) * V_RMS, 0.0, 0.0, 0.0])

    def rhs(t, x):
        i, w = x[:4], x[4]
        psi = M @ i
        w_slip = W_S - P * w
        # stator turns at w_s relative to the frame's view, rotor at the slip frequency
        rot_terms = np.array([-W_S * psi[1], W_S * psi[0],
                              -w_slip * psi[3], w_slip * psi[2]])
        R = np.array([R_S, R_S, R_R, R_R])
        di = Minv @ (v - R * i - rot_terms)
        T = 1.5 * P * (psi[0] * i[1] - psi[1] * i[0])
        T_fan = fan[0] * (w / fan[1]) * abs(w / fan[1])
        return [*di, (T - T_fan) / (J_R + J_load)]

    sol = solve_ivp(rhs, (0, t_eval[-1]), np.zeros(5), t_eval=t_eval, method="DOP853",
                    rtol=1e-11, atol=1e-9)
    i_d, i_q, w = sol.y[0], sol.y[1], sol.y[4]
    return w, i_d * np.cos(W_S * t_eval) - i_q * np.sin(W_S * t_eval)


def test_direct_on_line_start_against_an_independent_synchronous_frame_model():
    # MSL's IMC_DOL: from standstill, load inertia 0.29 and a quadratic (fan) load of
    # 161.4 N*m at 1440.45 rpm; 1.0 s covers the start and the settling
    fan = (T_NOM, N_NOM * 2 * math.pi / 60)
    t = np.linspace(0.0, 1.0, 1001)
    res = mt.simulate(driven(fan=fan, J_load=0.29), 1.0, t_out=t, rtol=1e-9, atol=1e-9)
    w_ref, i_a_ref = synchronous_frame_reference(t, 0.29, fan)
    assert w_ref[-1] == pytest.approx(fan[1], rel=2e-3)       # it reaches its nominal point
    assert np.abs(i_a_ref).max() > 5 * 100                     # the start-up current peak
    np.testing.assert_allclose(res["im.inertia.w"], w_ref, rtol=0, atol=1e-5 * fan[1])
    np.testing.assert_allclose(res["im.a.i"], i_a_ref, rtol=0,
                               atol=1e-5 * np.abs(i_a_ref).max())
