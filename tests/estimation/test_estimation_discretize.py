"""The sampled trajectory (3-stage Radau IIA with held inputs) against the matrix
exponential, and its forward sensitivities against CasADi's AD and finite differences."""

import casadi as ca
import numpy as np
import pytest
from scipy.linalg import expm

import mechatron as mt
from mechatron.errors import ModelError
from mechatron.estimation.discretize import Trajectory, fastest_time_constant
from mechatron.estimation.native import compiler

V, R, L, K, J, B = 19.2, 7.1, 3.408e-4, 0.151, 4.8e-6, 1.236e-4


@pytest.fixture(scope="module")
def cm():
    return mt.compile_model(mt.models.get("dc_motor").build("acausal"))


def exact(t, volts):
    """Held voltage volts[k] on [t_k, t_k+1): exact discretization by expm."""
    a = np.array([[-R / L, -K / L], [K / J, -B / J]])
    x = np.zeros(2)
    out = [x]
    for k in range(len(t) - 1):
        h = t[k + 1] - t[k]
        M = expm(np.block([[a, np.array([[1 / L], [0]])], [np.zeros((1, 3))]]) * h)
        x = M[:2, :2] @ x + M[:2, 2] * volts[k]
        out.append(x)
    return np.array(out).T


def run(cm, t, volts, m, **kw):
    tr = Trajectory(cm, t, [cm.param_names.index("source.V")],
                    [cm.names.index("inductor.i"), cm.names.index("inertia.w")],
                    substeps=m, **kw)
    Y, _ = tr(cm.p0, np.zeros(2), volts.reshape(1, -1))
    return Y


def test_order_five_convergence_on_a_held_voltage_profile(cm):
    t = np.arange(201) * 5e-5
    volts = np.where(t < 4e-3, V, 0.3 * V)
    ref = exact(t, volts)
    errs = []
    for m in (1, 2, 4):
        Y = run(cm, t, volts, m)
        errs.append(np.max(np.abs(Y - ref) / np.abs(ref).max(axis=1, keepdims=True)))
    assert errs[-1] < 1e-7
    orders = np.log2(np.array(errs[:-1]) / np.array(errs[1:]))
    assert np.all(orders > 4.5), orders


def test_step_of_one_time_constant_is_accurate_to_1e_4(cm):
    tau = fastest_time_constant(cm, cm.p0, np.zeros(2))
    assert tau == pytest.approx(1 / np.max(np.abs(np.linalg.eigvals(
        [[-R / L, -K / L], [K / J, -B / J]]))), rel=1e-9)
    t = np.arange(100) * tau
    Y = run(cm, t, np.full(t.size, V), 1)
    ref = exact(t, np.full(t.size, V))
    assert np.max(np.abs(Y - ref)) / np.abs(ref).max() < 1e-4


def test_linear_hold_matches_a_ramp_input(cm):
    """Linearly interpolated input = a ramp; compare with the ramp response by expm on
    the augmented system [x; u; 1]."""
    t = np.arange(101) * 1e-4
    volts = 2000.0 * t
    Y = run(cm, t, volts, 4, hold="linear")
    a = np.array([[-R / L, -K / L, 1 / L, 0], [K / J, -B / J, 0, 0], [0, 0, 0, 2000.0],
                  [0, 0, 0, 0]])
    ref = np.array([(expm(a * tk) @ np.array([0, 0, 0, 1.0]))[:2] for tk in t]).T
    np.testing.assert_allclose(Y, ref, atol=1e-7 * np.abs(ref).max())


def sens_setup(cm):
    t = np.arange(120) * 5e-5
    volts = np.where(t < 2e-3, V, 5.0).reshape(1, -1)
    free = ["resistor.R", "inductor.L", "emf.k", "inertia.J"]
    D = np.zeros((cm.p0.size, 5))
    for j, n in enumerate(free):
        D[cm.param_names.index(n), j] = 1.0
    S0 = np.zeros((2, 5))
    S0[1, 4] = 1.0                                   # the 5th direction: w(0)
    return t, volts, free, D, S0


def test_forward_sensitivities_equal_casadi_ad_and_finite_differences(cm):
    t, volts, free, D, S0 = sens_setup(cm)
    tr = Trajectory(cm, t, [cm.param_names.index("source.V")],
                    [cm.names.index("inductor.i"), cm.names.index("inertia.w")], substeps=2)
    x0 = np.array([0.0, 10.0])
    Y, dY = tr.sensitivity_function(D)(cm.p0, x0, volts, S0)
    Y, dY = np.array(Y), np.array(dY)
    # CasADi AD through the rootfinder
    th = ca.MX.sym("th", 5)
    p = ca.DM(cm.p0) + ca.mtimes(ca.DM(D), th)
    Ys, _ = tr.function(p, ca.DM(x0) + ca.mtimes(ca.DM(S0), th), ca.DM(volts))
    jac = np.array(ca.Function("jj", [th], [ca.jacobian(ca.vec(Ys), th)])(np.zeros(5)))
    mine = np.stack([dY[j * 2:(j + 1) * 2, :] for j in range(5)], axis=-1)  # (2, N, 5)
    ad = jac.reshape(Y.shape[1], 2, 5).transpose(1, 0, 2)
    scale = np.abs(ad).max(axis=(0, 1), keepdims=True)
    np.testing.assert_allclose(mine / scale, ad / scale, atol=1e-9)
    # central finite differences on the nominal trajectory
    for j in range(5):
        hstep = 1e-6 * (np.abs(D[:, j] @ cm.p0) or 1.0)
        pp = cm.p0 + D[:, j] * hstep
        pm = cm.p0 - D[:, j] * hstep
        yp, _ = tr(pp, x0 + S0[:, j] * hstep, volts)
        ym, _ = tr(pm, x0 - S0[:, j] * hstep, volts)
        fd = (yp - ym) / (2 * hstep)
        np.testing.assert_allclose(mine[:, :, j], fd, atol=1e-5 * np.abs(fd).max())


@pytest.mark.skipif(compiler() is None, reason="no C compiler on the PATH")
def test_native_code_gives_the_same_numbers(cm, tmp_path, monkeypatch):
    monkeypatch.setenv("MECHATRON_CACHE", str(tmp_path))
    t, volts, free, D, S0 = sens_setup(cm)
    args = (cm, t, [cm.param_names.index("source.V")], [cm.names.index("inductor.i")])
    a = Trajectory(*args, substeps=2)
    b = Trajectory(*args, substeps=2, jit=True)
    assert list((tmp_path / "jit").glob("*.so"))
    np.testing.assert_allclose(b(cm.p0, np.zeros(2), volts)[0],
                               a(cm.p0, np.zeros(2), volts)[0], rtol=1e-12, atol=1e-14)
    ya = np.array(a.sensitivity_function(D)(cm.p0, np.zeros(2), volts, S0)[1])
    yb = np.array(b.sensitivity_function(D)(cm.p0, np.zeros(2), volts, S0)[1])
    np.testing.assert_allclose(yb, ya, rtol=1e-10, atol=1e-12 * np.abs(ya).max())


@pytest.mark.skipif(compiler() is None, reason="no C compiler on the PATH")
def test_native_time_loop_gives_the_casadi_loops_numbers_bit_for_bit(cm, monkeypatch):
    """With native code the samples are stepped by a C loop (`_NativeLoop`), not by
    CasADi's ``mapaccum`` of the same compiled step: the same arithmetic, so the same
    bits, for the trajectory and its sensitivities; without a compiler the CasADi loop
    runs instead."""
    import mechatron.estimation.discretize as dz
    import mechatron.estimation.native as nat
    t, volts, free, D, S0 = sens_setup(cm)
    args = (cm, t, [cm.param_names.index("source.V")],
            [cm.names.index("inductor.i"), cm.names.index("inertia.w")])
    x0 = np.array([0.1, 5.0])
    a = Trajectory(*args, substeps=2, jit=True)
    assert a._loop is not None and a._mx is None         # no mapaccum built
    Y, X = a(cm.p0, x0, volts)
    Yc, Xc, _ = a._mx_functions()[1](cm.p0, x0, volts)
    np.testing.assert_array_equal(Y, Yc.full())
    np.testing.assert_array_equal(X, Xc.full())
    sens = a.sensitivity_function(D)
    assert isinstance(sens.fn, dz._NativeLoop)
    with monkeypatch.context() as m:
        m.setattr(dz._NativeLoop, "build", classmethod(lambda cls, *a: None))
        b = Trajectory(*args, substeps=2, jit=True)
        casadi_sens = b.sensitivity_function(D)
    assert b._loop is None and isinstance(casadi_sens.fn, ca.Function)
    for mine, theirs in zip(sens(cm.p0, x0, volts, S0), casadi_sens(cm.p0, x0, volts, S0)):
        np.testing.assert_array_equal(mine, theirs)
    monkeypatch.setattr(nat, "compiler", lambda: None)
    c = Trajectory(*args, substeps=2, jit=True)
    assert c._loop is None
    np.testing.assert_allclose(c(cm.p0, x0, volts)[0], Y, rtol=1e-12, atol=1e-14)


def test_state_events_are_refused_without_the_smooth_approximation():
    class Clamp(mt.Component):
        x = mt.Variable("1", start=0.0)

        def equations(self):
            return [mt.der(self.x) == mt.if_else(self.x < 1, 1.0, 0.0)]
    cm = mt.compile_model(Clamp())
    with pytest.raises(ModelError, match=r"switch with the continuous states \(Clamp: x < 1\)"
                                         r".*smooth approximation"):
        Trajectory(cm, np.arange(3.0), [], [0])
