"""Discrete blocks: updates exactly at the sample instants (multi-rate, offsets), checked
against hand-written difference equations and scipy.signal."""

import numpy as np
import pytest
from scipy import signal
from scipy.linalg import expm

import mechatron as mt
from mechatron.library import blocks

V, R, L, K, J, B = 19.2, 7.1, 3.408e-4, 0.151, 4.8e-6, 1.236e-4
TS, KP, KI, W_REF = 1e-3, 0.05, 2.0, 100.0


class MotorPlant(mt.Component):
    """The seed's DC motor (table 6-1) as ODEs, driven by the voltage signal ``u``."""

    u = mt.Input("V", doc="Armature voltage")
    w = mt.Output("rad/s", start=0.0, doc="Speed")
    i = mt.Variable("A", start=0.0, doc="Current")
    R_a = mt.Parameter("Ohm", default=R, doc="Armature resistance")
    L_a = mt.Parameter("H", default=L, doc="Armature inductance")
    k = mt.Parameter("V*s/rad", default=K, doc="Motor constant")
    J_r = mt.Parameter("kg*m^2", default=J, doc="Rotor inertia")
    B_v = mt.Parameter("N*m*s/rad", default=B, doc="Viscous friction")

    def equations(self):
        return [self.L_a * mt.der(self.i) == self.u - self.R_a * self.i - self.k * self.w,
                self.J_r * mt.der(self.w) == self.k * self.i - self.B_v * self.w]


def pi_loop():
    m = mt.System("dpi")
    ref = m.add("ref", blocks.Constant(value=W_REF))
    err = m.add("err", blocks.Subtract())
    pi = m.add("pi", blocks.DiscretePID(Kp=KP, Ki=KI, Ts=TS))
    mot = m.add("motor", MotorPlant())
    m.connect(ref.y, err.u1)
    m.connect(mot.w, err.u2)
    m.connect(err.y, pi.u)
    m.connect(pi.y, mot.u)
    return m


def hand_loop(n):
    """The same loop by hand: exact ZOH discretisation of the motor (matrix exponential)
    and the PI difference equation u_k = Kp e_k + I_k, I_k+1 = I_k + Ki Ts e_k."""
    a = np.array([[-R / L, -K / L], [K / J, -B / J]])
    b = np.array([1 / L, 0.0])
    m = expm(np.block([[a, b[:, None]], [np.zeros((1, 3))]]) * TS)
    ad, bd = m[:2, :2], m[:2, 2]
    x, integral, us = np.zeros(2), 0.0, []
    for _ in range(n):
        e = W_REF - x[1]
        u = KP * e + integral
        integral += KI * TS * e
        us.append(u)
        x = ad @ x + bd * u
    return np.array(us)


def test_discrete_pi_at_1khz_matches_hand_written_loop_step_for_step():
    n = 300
    t_out = np.concatenate([[0.0], (np.arange(n) + 0.5) * TS])   # mid-sample: held values
    res = mt.simulate(pi_loop(), t_out[-1], rtol=1e-11, atol=1e-12, t_out=t_out)
    expected = hand_loop(n)
    np.testing.assert_allclose(res["pi.y"][1:], expected, rtol=0, atol=1e-9)
    assert res.stats.events == {"pi": n}        # ticks at 0, Ts, ..., (n - 1) Ts
    assert abs(expected[-1] - expected[0]) > 1.0     # a real transient, not a constant


def test_discrete_pi_in_fixed_step_updates_at_the_sample_instants():
    # the plant is integrated by RK4 (dt = Ts/50, h/tau = 0.4); the controller's samples
    # land on step ends, so its outputs match the hand loop to the plant's accuracy
    n = 100
    res = mt.simulate(pi_loop(), n * TS, solver="rk4", dt=TS / 50)
    held = res["pi.y"][25::50][:n]        # mid-sample of each period
    np.testing.assert_allclose(held, hand_loop(n), atol=1e-5)
    # the held value changes only at the ticks: constant over each sample period
    y = res["pi.y"][:-1].reshape(-1, 50)      # [t_k, t_k+1) per row
    assert np.all(np.ptp(y, axis=1) == 0.0)


def ramp_holds(ts1, off1, ts2, off2):
    m = mt.System("holds")
    r = m.add("r", blocks.Ramp(slope=1.0))
    h1 = m.add("h1", blocks.ZeroOrderHold(Ts=ts1, offset=off1))
    h2 = m.add("h2", blocks.ZeroOrderHold(Ts=ts2, offset=off2))
    d = m.add("d", blocks.UnitDelay(Ts=ts1, offset=off1))
    m.connect(r.y, h1.u, h2.u)
    m.connect(h1.y, d.u)
    return m


def test_multirate_holds_with_offsets_sample_at_their_own_instants():
    ts1, off1, ts2, off2 = 1e-3, 0.25e-3, 2.5e-3, 0.0
    t = np.linspace(0, 0.021, 2101)[1:]
    res = mt.simulate(ramp_holds(ts1, off1, ts2, off2), 0.021, t_out=t, rtol=1e-9,
                      atol=1e-12)
    # the hold of a ramp y = t shows the last tick time t_k = offset + k Ts <= t
    last1 = np.where(t >= off1, off1 + np.floor((t - off1) / ts1 + 1e-9) * ts1, 0.0)
    last2 = off2 + np.floor((t - off2) / ts2 + 1e-9) * ts2
    away = np.minimum(np.abs((t - off1) / ts1 - np.round((t - off1) / ts1)),
                      np.abs((t - off2) / ts2 - np.round((t - off2) / ts2))) > 1e-6
    np.testing.assert_allclose(res["h1.y"][away], last1[away], atol=1e-12)
    np.testing.assert_allclose(res["h2.y"][away], last2[away], atol=1e-12)
    # the unit delay at the same rate as h1 reads h1's new output at the tick (signal-flow
    # order) and shows it one sample later
    delayed = np.where(t >= off1 + ts1, last1 - ts1, 0.0)
    np.testing.assert_allclose(res["d.y"][away], delayed[away], atol=1e-12)
    ev = res.stats.events
    assert ev["h1"] == ev["d"] == 21 and ev["h2"] == 9


def test_discrete_transfer_function_step_response_matches_scipy_dlsim():
    num, den, ts = [0.2, 0.1], [1.0, -1.3, 0.45], 0.01
    m = mt.System("dtf")
    s = m.add("s", blocks.Step(t_step=0.0))
    g = m.add("g", blocks.DiscreteTransferFunction(num=num, den=den, Ts=ts))
    m.connect(s.y, g.u)
    n = 60
    t = (np.arange(n) + 0.5) * ts
    res = mt.simulate(m, n * ts, t_out=t, rtol=1e-9, atol=1e-12)
    _, y = signal.dlsim((num, den, ts), np.ones(n))
    np.testing.assert_allclose(res["g.y"], y.ravel(), atol=1e-12)


def test_biproper_discrete_transfer_function_has_direct_feedthrough():
    num, den, ts = [0.5, -0.2, 0.1], [1.0, -0.6, 0.08], 0.1
    m = mt.System("dtf2")
    s = m.add("s", blocks.Sine(f=0.7))
    g = m.add("g", blocks.DiscreteTransferFunction(num=num, den=den, Ts=ts))
    m.connect(s.y, g.u)
    n = 40
    res = mt.simulate(m, n * ts, t_out=(np.arange(n) + 0.5) * ts, rtol=1e-9, atol=1e-12)
    u = np.sin(2 * np.pi * 0.7 * np.arange(n) * ts)
    _, y = signal.dlsim((num, den, ts), u)
    np.testing.assert_allclose(res["g.y"], y.ravel(), atol=1e-12)


def test_discrete_integrator_sums_and_clamps_at_its_limits():
    m = mt.System("dint")
    c = m.add("c", blocks.Constant(value=2.0))
    di = m.add("di", blocks.DiscreteIntegrator(K=1.5, Ts=0.1, y_max=1.0))
    m.connect(c.y, di.u)
    t = np.array([0.05, 0.15, 0.25, 0.35, 0.45, 0.55])
    res = mt.simulate(m, 0.6, t_out=t)
    # y_k = x_k, x_k+1 = min(x_k + K Ts u, 1): 0, 0.3, 0.6, 0.9, 1.0, 1.0
    np.testing.assert_allclose(res["di.y"], [0.0, 0.3, 0.6, 0.9, 1.0, 1.0], atol=1e-12)


def test_algebraic_loop_of_sampled_blocks_names_the_blocks():
    m = mt.System("dloop")
    r = m.add("r", blocks.Constant(value=1.0))
    s = m.add("s", blocks.Subtract())
    h1 = m.add("hold_a", blocks.ZeroOrderHold(Ts=0.1))
    h2 = m.add("hold_b", blocks.ZeroOrderHold(Ts=0.1))
    m.connect(r.y, s.u1)
    m.connect(s.y, h1.u)
    m.connect(h1.y, h2.u)
    m.connect(h2.y, s.u2)
    with pytest.raises(mt.errors.StructuralError, match=r"algebraic loop among sampled "
                                                        r"blocks .*hold_[ab].*hold_[ab]"):
        mt.compile_model(m)


def test_unit_delay_breaks_a_sampled_feedback_loop():
    # y_k = 1 - d_k with d_k = y_k-1: 1, 0, 1, 0 ... (the loop is causal through the delay)
    m = mt.System("dloop2")
    r = m.add("r", blocks.Constant(value=1.0))
    s = m.add("s", blocks.Subtract())
    h = m.add("h", blocks.ZeroOrderHold(Ts=0.1))
    d = m.add("d", blocks.UnitDelay(Ts=0.1))
    m.connect(r.y, s.u1)
    m.connect(s.y, h.u)
    m.connect(h.y, d.u)
    m.connect(d.y, s.u2)
    res = mt.simulate(m, 0.6, t_out=np.arange(6) * 0.1 + 0.05)
    np.testing.assert_allclose(res["h.y"], [1, 0, 1, 0, 1, 0], atol=1e-12)


def test_delay_is_a_ramp_shifted_by_T_on_its_grid():
    """Delay(T = 4 Ts) of a ramp: between ticks the output is the ramp's value at the
    tick 4 samples earlier (0 before the input has travelled through), the same as four
    unit delays in series."""
    ts, T = 1e-3, 4e-3
    m = mt.System("delayed")
    r = m.add("r", blocks.Ramp(slope=1.0))
    d = m.add("d", blocks.Delay(T=T, Ts=ts))
    chain = [m.add(f"u{k}", blocks.UnitDelay(Ts=ts)) for k in range(4)]
    m.connect(r.y, d.u, chain[0].u)
    for a, b in zip(chain, chain[1:]):
        m.connect(a.y, b.u)
    t = (np.arange(20) + 0.5) * ts
    res = mt.simulate(m, 0.02, t_out=t, rtol=1e-9, atol=1e-12)
    last = np.floor(t / ts) * ts
    np.testing.assert_allclose(res["d.y"], np.maximum(last - T, 0.0), atol=1e-12)
    np.testing.assert_allclose(res["d.y"], res["u3.y"], atol=1e-12)
    assert res.stats.events["d"] == 20


def test_delay_needs_a_whole_number_of_sample_times():
    with pytest.raises(mt.errors.ModelError, match=r"T = 0.0025 s is not a whole number of "
                                                    r"sample times Ts = 0.001 s"):
        blocks.Delay(T="2.5 ms", Ts=1e-3)
    assert blocks.Delay(T="3 ms", Ts="1 ms").n == 3
    with pytest.raises(mt.errors.ModelError, match="T >= 0"):
        blocks.Delay(T=-1e-3)
