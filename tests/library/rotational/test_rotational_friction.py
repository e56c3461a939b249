"""Rotational friction elements with a true stuck mode (clutch, brake, one-way clutch,
bearing friction) against analytic answers: lock and opening times of a clutch between
two inertias, the stopping time of a brake, a freewheel, and the energy balance."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import rotational as rot
from mechatron.library.rotational.interfaces import TwoFlange
from mechatron.solvers.native import compiler

TOL = dict(rtol=1e-10, atol=1e-12)
#: models here have no algebraic unknowns, so the compiled rodas4 runs them too
SOLVERS = ["auto", pytest.param("rodas4", marks=pytest.mark.skipif(
    compiler() is None, reason="no C compiler for rodas4"))]


class RampDown(mt.Component):
    """Normal force signal ``y = F0 - k t``."""

    y = mt.Output("N", doc="Normal force")
    F0 = mt.Parameter("N", default=100.0, doc="Value at t = 0")
    k = mt.Parameter("N/s", default=20.0, doc="Rate of decrease")

    def equations(self):
        return [self.y == self.F0 - self.k * self.time]


class StepTorque(TwoFlange):
    """Torque ``T1`` at A before ``t_r``, ``T2`` from then on (``tau = -T``)."""

    T1 = mt.Parameter("N*m", default=1.0, doc="Torque before t_r")
    T2 = mt.Parameter("N*m", default=-1.0, doc="Torque from t_r on")
    t_r = mt.Parameter("s", default=1.0, doc="Switching time")

    def equations(self):
        return [self.tau == -mt.if_else(self.time < self.t_r, self.T1, self.T2)]


# ------------------------------------------------------------------------------- clutch
J1, J2, T1, T2, W0 = 0.2, 0.5, 3.0, -1.0, 50.0
MU, PEAK, R, N, F0, KF = 0.4, 1.25, 0.1, 2, 100.0, 20.0


class ClutchDrive(mt.Component):
    """Two inertias under constant torques, coupled by a clutch whose normal force
    decreases linearly; ``E_f``, ``W1``, ``W2`` integrate the friction power and the work
    of the two torques (for the energy balance)."""

    j1 = rot.Inertia(J=J1, w=W0)
    j2 = rot.Inertia(J=J2, w=0.0)
    t1 = rot.ConstantTorque(T=T1)
    t2 = rot.ConstantTorque(T=T2)
    c = rot.Clutch(mu=MU, peak=PEAK, R=R, n=N)
    fn = RampDown(F0=F0, k=KF)
    g = rot.RotationalReference()
    E_f = mt.Variable("J", start=0.0, doc="Friction work, integral of tau w")
    W1 = mt.Variable("J", start=0.0, doc="Work of T1")
    W2 = mt.Variable("J", start=0.0, doc="Work of T2")

    def equations(self):
        return [mt.connect(self.j1.port, self.c.A, self.t1.A),
                mt.connect(self.j2.port, self.c.B, self.t2.A),
                mt.connect(self.t1.B, self.t2.B, self.g.port),
                mt.connect(self.fn.y, self.c.f_n),
                mt.der(self.E_f) == self.c.tau * self.c.w,
                mt.der(self.W1) == -self.t1.tau * self.j1.w,    # t1.tau = -T1
                mt.der(self.W2) == -self.t2.tau * self.j2.w]


def clutch_times():
    """Lock: the slip ``W0 + (T1/J1 - T2/J2) t - (1/J1 + 1/J2) cgeo mu (F0 t - KF t^2/2)``
    reaches zero. Open: the stuck torque ``(J2 T1 - J1 T2) / (J1 + J2)`` reaches the
    static limit ``peak cgeo mu (F0 - KF t)``."""
    cgeo, c = N * R, 1 / J1 + 1 / J2
    # slip(t) = a2 t^2 + a1 t + W0
    a2, a1 = c * cgeo * MU * KF / 2, T1 / J1 - T2 / J2 - c * cgeo * MU * F0
    t_lock = (-a1 - np.sqrt(a1 ** 2 - 4 * a2 * W0)) / (2 * a2)
    tau_stuck = (J2 * T1 - J1 * T2) / (J1 + J2)
    t_open = (F0 - tau_stuck / (PEAK * cgeo * MU)) / KF
    return t_lock, t_open, tau_stuck


@pytest.fixture(scope="module")
def clutch_model():
    return mt.compile_model(ClutchDrive())


@pytest.mark.parametrize("solver", SOLVERS)
def test_clutch_locks_when_the_speeds_meet_and_opens_at_its_torque_limit(clutch_model,
                                                                       solver):
    t_lock, t_open, tau_stuck = clutch_times()
    assert 0 < t_lock < t_open < 5
    # between lock and opening: one body, the clutch carries the analytic torque
    mid = 0.5 * (t_lock + t_open)
    res = mt.simulate(clutch_model, mid, solver=solver, **TOL)
    assert res.event_times["c"] == pytest.approx(t_lock, abs=1e-9)
    assert res.stats.events["c"] == 1                     # the lock, nothing else
    assert res.final("c.mode") == 0
    assert res.final("c.tau") == pytest.approx(tau_stuck, rel=1e-9)
    assert abs(res.final("c.w")) < 1e-10
    w_lock = W0 + (T1 - N * R * MU * (F0 - KF * t_lock / 2)) * t_lock / J1  # j1 at lock
    w_mid = w_lock + (T1 + T2) / (J1 + J2) * (mid - t_lock)
    assert res.final("j1.w") == pytest.approx(w_mid, rel=1e-8)
    # it opens when the torque it must carry exceeds peak cgeo mu fn(t)
    res = mt.simulate(clutch_model, t_open + 0.5, solver=solver, **TOL)
    assert res.event_times["c"] == pytest.approx(t_open, abs=1e-9)
    assert res.stats.events["c"] == 2                     # lock, break-away
    assert res.final("c.mode") == 1                       # j1 overtakes j2 again
    fn_end = F0 - KF * (t_open + 0.5)
    assert res.final("c.tau") == pytest.approx(N * R * MU * fn_end, rel=1e-9)


@pytest.mark.parametrize("solver", SOLVERS)
def test_clutch_friction_work_equals_the_energy_lost(clutch_model, solver):
    res = mt.simulate(clutch_model, 4.5, solver=solver, **TOL)
    ke0 = 0.5 * J1 * W0 ** 2
    ke = 0.5 * J1 * res["j1.w"] ** 2 + 0.5 * J2 * res["j2.w"] ** 2
    lost = ke0 + res["W1"] + res["W2"] - ke
    np.testing.assert_allclose(res["E_f"], lost, rtol=1e-8, atol=1e-8 * ke0)
    assert res["E_f"][-1] > 0.1 * ke0                     # it did dissipate
    # no work while stuck: E_f is flat between lock and opening
    t_lock, t_open, _ = clutch_times()
    stuck = (res.t > t_lock + 1e-6) & (res.t < t_open - 1e-6)
    assert np.ptp(res["E_f"][stuck]) < 1e-9 * ke0


# -------------------------------------------------------------------------------- brake
JB, WB0, FN, MUB, RB, NB, TL = 0.05, 30.0, 200.0, 0.25, 0.08, 2, 1.5


def braked(name, n=1):
    """``n`` identical inertias, each stopped by its own brake under a load torque TL."""
    m = mt.System(name)
    g = m.add("g", rot.RotationalReference())
    for k in range(n):
        j = m.add(f"j{k}", rot.Inertia(J=JB, w=WB0))
        b = m.add(f"b{k}", rot.Brake(mu=MUB, peak=1.2, R=RB, n=NB))
        load = m.add(f"load{k}", rot.ConstantTorque(T=TL))
        fn = m.add(f"fn{k}", RampDown(F0=FN, k=0.0))
        m.connect(j.port, b.A, load.A)
        m.connect(b.B, load.B, g.port)
        m.connect(fn.y, b.f_n)
    return m


@pytest.mark.parametrize("solver", SOLVERS)
def test_brake_stops_an_inertia_in_the_analytic_time_and_holds_it(solver):
    tk = NB * RB * MUB * FN                     # kinetic torque, 8 N m > TL
    t_stop = JB * WB0 / (tk - TL)
    res = mt.simulate(braked("brake"), 2 * t_stop, solver=solver, **TOL,
                      t_out=np.linspace(0, 2 * t_stop, 201))
    assert res.event_times["b0"] == pytest.approx(t_stop, abs=1e-9)
    sliding = res.t < t_stop
    np.testing.assert_allclose(res["j0.w"][sliding],
                               WB0 - (tk - TL) / JB * res.t[sliding], atol=1e-8)
    held = res.t > t_stop
    assert np.all(np.abs(res["j0.w"][held]) < 1e-10)
    assert np.all(res["b0.mode"][held] == 0)
    np.testing.assert_allclose(res["b0.tau"][held], TL, rtol=1e-12)   # holds the load
    assert res.stats.events["b0"] == 1                    # the lock, nothing while held


@pytest.mark.parametrize("solver", SOLVERS)
def test_two_identical_brakes_report_the_same_events(solver):
    res = mt.simulate(braked("two", n=2), 1.0, solver=solver, **TOL)
    np.testing.assert_array_equal(res["j0.w"], res["j1.w"])
    assert res.stats.events["b0"] == res.stats.events["b1"] == 1
    assert res.event_times["b0"] == res.event_times["b1"]


# ---------------------------------------------------------------------- one-way clutch
JO, WO0, TO = 0.1, -5.0, 2.0


@pytest.mark.parametrize("solver", SOLVERS)
def test_one_way_clutch_freewheels_one_way_and_locks_the_other(solver):
    """A at the ground, B at an inertia: ``w = -wB``. The inertia spins backwards
    (freewheeling, ``w > 0``), the torque TO slows it down; at ``wB = 0`` the clutch locks
    (it cannot turn forwards) and holds TO until the torque reverses at t_r, when it
    freewheels again backwards."""
    t_lock = -WO0 * JO / TO                    # 0.25 s
    t_r = 0.6
    m = mt.System("oneway")
    g = m.add("g", rot.RotationalReference())
    j = m.add("j", rot.Inertia(J=JO, w=WO0))
    oc = m.add("oc", rot.OneWayClutch())
    src = m.add("src", StepTorque(T1=TO, T2=-TO, t_r=t_r))
    m.connect(g.port, oc.A, src.B)
    m.connect(oc.B, j.port, src.A)
    t = np.linspace(0, 1.0, 101)
    res = mt.simulate(m, 1.0, solver=solver, t_out=t, **TOL)
    free = t < t_lock - 1e-9
    np.testing.assert_allclose(res["j.w"][free], WO0 + TO / JO * t[free], atol=1e-9)
    locked = (t > t_lock + 1e-9) & (t < t_r)
    assert np.all(np.abs(res["j.w"][locked]) < 1e-10)
    np.testing.assert_allclose(res["oc.tau"][locked], -TO, rtol=1e-12)
    after = t > t_r
    np.testing.assert_allclose(res["j.w"][after], -TO / JO * (t[after] - t_r), atol=1e-8)
    assert np.all(res["oc.tau"][after] == 0.0)


# --------------------------------------------------------------------- bearing friction
@pytest.mark.parametrize("solver", SOLVERS)
def test_bearing_friction_holds_below_break_away_and_slides_with_coulomb_above(solver):
    """An inertia at rest under a torque ramp ``k t``: stuck until ``k t = T_brk``, then
    ``J dw/dt = k t - T_C`` (Coulomb only: ``w_S`` tiny so the Stribeck part has
    decayed)."""
    J, k, T_brk, T_C = 0.02, 0.5, 0.3, 0.2

    class Ramp(TwoFlange):
        """``tau = -k t``."""

        kr = mt.Parameter("N*m/s", default=k, doc="Torque rate")

        def equations(self):
            return [self.tau == -self.kr * self.time]

    m = mt.System("bearing")
    g = m.add("g", rot.RotationalReference())
    j = m.add("j", rot.Inertia(J=J, w=0.0))
    bf = m.add("bf", rot.BearingFriction(T_brk=T_brk, T_C=T_C, w_S=1e-9,
                                         stribeck_table=[(0, 1), (1, 0)]))
    src = m.add("src", Ramp())
    m.connect(j.port, bf.A, src.A)
    m.connect(bf.B, src.B, g.port)
    t_b = T_brk / k
    res = mt.simulate(m, t_b + 0.4, solver=solver, **TOL)
    assert res.event_times["bf"] == pytest.approx(t_b, abs=1e-9)
    dt = 0.4
    w_end = (k * ((t_b + dt) ** 2 - t_b ** 2) / 2 - T_C * dt) / J
    assert res.final("j.w") == pytest.approx(w_end, rel=1e-7)


@pytest.mark.parametrize("solver", SOLVERS)
@pytest.mark.parametrize("T", [TO, -TO])
def test_one_way_clutch_started_at_rest_locks_or_freewheels_at_once(solver, T):
    """At rest at t = 0 the clutch starts stuck; a torque that turns the inertia forwards
    (T > 0: ``w = -wB < 0``) is held, one that turns it backwards breaks it free at the
    initial event."""
    m = mt.System("oneway0")
    g = m.add("g", rot.RotationalReference())
    j = m.add("j", rot.Inertia(J=JO, w=0.0))
    oc = m.add("oc", rot.OneWayClutch())
    src = m.add("src", StepTorque(T1=T, T2=T, t_r=10.0))
    m.connect(g.port, oc.A, src.B)
    m.connect(oc.B, j.port, src.A)
    res = mt.simulate(m, 0.5, solver=solver, **TOL)
    if T > 0:
        assert np.all(res["j.w"] == 0.0) and np.all(res["oc.mode"] == 0)
        np.testing.assert_allclose(res["oc.tau"], -T, rtol=1e-12)
    else:
        np.testing.assert_allclose(res["j.w"], T / JO * res.t, atol=1e-9)
        assert np.all(res["oc.mode"] == 1)


@pytest.mark.parametrize("solver", SOLVERS)
def test_brake_with_a_mu_table_in_rpm_stops_at_the_analytic_time(solver):
    """``mu(w) = mu0 + c w`` given as a table over rpm: ``J dw/dt = -k (mu0 + c w)`` with
    ``k = cgeo fn``, so ``w + mu0/c = (w0 + mu0/c) exp(-k c t / J)`` and the stop time is
    ``J / (k c) ln(1 + c w0 / mu0)``."""
    mu0, c, w0, fn = 0.2, 0.004, 40.0, 100.0        # c in s/rad
    rpm = 2 * np.pi / 60
    table = [(0.0, mu0), (1000.0, mu0 + c * 1000.0 * rpm)]      # speeds in rpm
    m = mt.System("tabled")
    g = m.add("g", rot.RotationalReference())
    j = m.add("j", rot.Inertia(J=JB, w=w0))
    b = m.add("b", rot.Brake(mu_table=table, w_ref="1 rpm", R=RB, n=NB))
    f = m.add("f", RampDown(F0=fn, k=0.0))
    m.connect(j.port, b.A)
    m.connect(b.B, g.port)
    m.connect(f.y, b.f_n)
    k = NB * RB * fn
    t_stop = JB / (k * c) * np.log(1 + c * w0 / mu0)
    res = mt.simulate(m, 1.5 * t_stop, solver=solver, **TOL)
    assert res.event_times["b"] == pytest.approx(t_stop, abs=1e-9)
    assert abs(res.final("j.w")) < 1e-10


def test_friction_tables_are_checked():
    with pytest.raises(mt.errors.DataError, match=r"Clutch: mu_table must start at speed 0"):
        rot.Clutch(mu_table=[(1.0, 0.3), (2.0, 0.2)])
    with pytest.raises(mt.errors.DataError, match=r"BearingFriction: stribeck_table "
                                                  r"speeds must be strictly increasing"):
        rot.BearingFriction(stribeck_table=[(0.0, 1.0), (0.0, 0.5)])
