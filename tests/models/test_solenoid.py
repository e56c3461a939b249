"""Solenoid actuator: the current rises with the open-gap inductance, the static pull at a
held gap is the co-energy force, the plunger closes onto its stop and rests there, and
the supplied energy is accounted for across the three domains."""

import numpy as np
import pytest
from scipy.integrate import trapezoid

import mechatron as mt
from mechatron.library import electrical as el
from mechatron.library import magnetic as mag
from mechatron.library import translational as tr
from mechatron.models.solenoid import final_state

ENTRY = mt.models.get("solenoid")
MU0 = 4e-7 * np.pi


def _reluctance(x, p):
    return p["R_fe"] + x / (MU0 * p["A"])


@pytest.mark.parametrize("variant", ["acausal", "equation"])
def test_initial_current_rise_is_set_by_the_open_gap_inductance(variant):
    p = ENTRY.values()
    L0 = p["N"] ** 2 / _reluctance(p["x0"], p)
    t = np.linspace(0.0, 2e-5, 21)
    res = mt.simulate(ENTRY.build(variant), 2e-5, rtol=1e-10, atol=1e-12, t_out=t)
    i = res[ENTRY.output_paths(variant)["i"]]
    # the plunger has not moved yet: an RL circuit with L = L(x0)
    expected = p["V"] / p["R"] * (1 - np.exp(-p["R"] * t / L0))
    np.testing.assert_allclose(i, expected, rtol=1e-6, atol=1e-12)
    # L(x0) di/dt = V at t = 0 (forward difference over 1 us: error R h / (2 L0))
    assert L0 * (i[1] - i[0]) / (t[1] - t[0]) == pytest.approx(p["V"], rel=2e-3)


class HeldSolenoid(mt.Component):
    """The solenoid's coil and magnetic circuit with the plunger clamped at its gap."""

    source = el.DCVoltageSource()
    winding = el.Resistor()
    coil = mag.ElectromagneticConverter()
    iron = mag.Reluctance()
    gap = mag.ReluctanceForceActuator()
    ground = el.ElectricalReference()
    mground = mag.MagneticReference()
    frame = tr.TranslationalReference()

    def equations(self):
        return [mt.connect(self.source.p, self.winding.p),
                mt.connect(self.winding.n, self.coil.p),
                mt.connect(self.coil.n, self.source.n, self.ground.port),
                mt.connect(self.coil.B, self.iron.A),
                mt.connect(self.iron.B, self.gap.A),
                mt.connect(self.gap.B, self.coil.A, self.mground.port),
                mt.connect(self.gap.rod, self.gap.case, self.frame.port)]


@pytest.mark.parametrize("gap", [0.5e-3, 1e-3, 3e-3])
def test_static_pull_at_a_held_gap_is_the_co_energy_force(gap):
    p = ENTRY.values()
    model = HeldSolenoid(doc="held solenoid")
    model._name = "held"
    model.source._values["V"] = p["V"]
    model.winding._values["R"] = p["R"]
    model.coil._values["N"] = p["N"]
    model.iron._values["R"] = p["R_fe"]
    model.gap._values["area"] = p["A"]
    model.gap._set("x", gap)
    res = mt.simulate(model, 0.1, rtol=1e-10, atol=1e-12)
    i = p["V"] / p["R"]
    assert res.final("winding.i") == pytest.approx(i, rel=1e-8)
    assert res.final("gap.x") == pytest.approx(gap, rel=1e-12)

    # co-energy W'(i, x) = (N i)^2 / (2 R_m(x)), differentiated numerically at constant i
    def coenergy(x):
        return (p["N"] * i) ** 2 / (2 * _reluctance(x, p))

    h = 1e-7 * gap
    force = (coenergy(gap + h) - coenergy(gap - h)) / (2 * h)
    assert force < 0                                   # it closes the gap
    assert res.final("gap.F") == pytest.approx(force, rel=1e-7)


@pytest.fixture(scope="module")
def closing():
    # fine where the plunger hits the stop (contact lasts ~ sqrt(m / k_stop) = 10 us)
    t = np.unique(np.concatenate([np.linspace(0.0, 0.012, 2001),
                                  np.linspace(0.012, 0.02, 40001),
                                  np.linspace(0.02, ENTRY.experiment.t_stop, 4001)]))
    return mt.simulate(ENTRY.build("acausal"), t[-1], rtol=1e-9, atol=1e-12, t_out=t)


def test_plunger_closes_and_rests_on_the_stop(closing):
    p = ENTRY.values()
    res = closing
    x, v, i = res["gap.x"], res["plunger.v"], res["winding.i"]
    rest = final_state(**p)
    assert res.final("gap.x") == pytest.approx(rest["x"], rel=1e-6)
    assert rest["x"] < p["x_min"]                       # pressed into the stop
    assert abs(res.final("plunger.v")) < 1e-9
    assert res.final("winding.i") == pytest.approx(p["V"] / p["R"], rel=1e-6)
    # it closes once, within the stroke: never past the back stop or far into the stop
    assert x.max() <= p["x0"] * (1 + 1e-9)
    assert x.min() > p["x_min"] - 1e-5
    k_close = int(np.argmax(x <= p["x_min"]))
    assert 0 < res.t[k_close] < 0.03
    # the motion induces a back-EMF: the current falls while the gap closes fast, the
    # classic dip in a solenoid's current trace
    k_peak = int(np.argmax(i[:k_close]))
    assert 0 < k_peak < k_close and i[k_close] < 0.9 * i[k_peak]
    assert np.all(v[:k_close] <= 1e-12)


def test_energy_balance_over_three_domains(closing):
    p = ENTRY.values()
    res, t = closing, closing.t
    i, v, x = res["winding.i"], res["plunger.v"], res["gap.x"]
    supplied = trapezoid(p["V"] * i, t)
    joule = trapezoid(p["R"] * i ** 2, t)
    friction = trapezoid(p["b"] * v ** 2, t)
    stop = trapezoid(res["stop.f"] * res["stop.v"], t)      # absorbed by the stop
    magnetic = 0.5 * p["N"] ** 2 / _reluctance(x[-1], p) * i[-1] ** 2
    spring = 0.5 * p["k"] * (p["x0"] - x[-1]) ** 2
    kinetic = 0.5 * p["m"] * v[-1] ** 2
    assert stop > 0 and friction > 0
    total = joule + friction + stop + magnetic + spring + kinetic
    assert supplied == pytest.approx(total, rel=1e-5)


def test_a_stop_too_soft_for_the_pull_is_a_clear_error():
    from mechatron.errors import ParameterError
    with pytest.raises(ParameterError, match="solenoid: no rest position.*k_stop"):
        final_state(**ENTRY.values(k_stop=1e6))
