"""Energy balance of a rotational drive train: the energy a source puts in equals what the
dampers, the fan load and the lossy gear dissipate plus what the inertias and the spring
store (integrated by extra states, ``der(E) = P``)."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.library import blocks
from mechatron.library import rotational as rot


class EnergyMeter(mt.Component):
    """Test-only integrator of a power: ``der(E) == P``; ``P`` is set by an equation of
    the model."""

    E = mt.Variable("J", start=0.0, doc="Energy, integral of P")
    P = mt.Variable("W", doc="Power being integrated")

    def equations(self):
        return [mt.der(self.E) == self.P]


@pytest.mark.parametrize("solver", [
    "rk45",
    "rosenbrock",   # held modes exact (solvers.variable.held_states)
    "auto"])
def test_input_energy_equals_dissipated_plus_stored(solver):
    J1, J2, J3, k, D, ratio, eta = 0.01, 0.02, 0.05, 50.0, 0.05, 2.5, 0.85
    m = mt.System("train")
    g = m.add("g", rot.RotationalReference())
    s = m.add("s", blocks.Sine(amplitude=3.0, f=0.7, offset=0.5))
    src = m.add("src", rot.IdealTorqueSource())
    ps = m.add("ps", rot.PowerSensor())
    j1 = m.add("j1", rot.Inertia(J=J1))
    spring = m.add("spring", rot.RotationalSpring(k=k))
    j2 = m.add("j2", rot.Inertia(J=J2))
    fan = m.add("fan", rot.FanLoad(T_nom=0.2, w_nom=50.0))
    gear = m.add("gear", rot.LossyGear(ratio=ratio, eta=eta))
    j3 = m.add("j3", rot.Inertia(J=J3))
    dmp = m.add("dmp", rot.RotationalDamper(D=D))
    e_in = m.add("e_in", EnergyMeter())
    e_loss = m.add("e_loss", EnergyMeter())
    m.connect(s.y, src.tau_in)
    m.connect(src.A, ps.A)
    m.connect(ps.B, j1.port, spring.A, fan.A)
    m.connect(spring.B, j2.port, gear.A)
    m.connect(gear.B, j3.port, dmp.A)
    m.connect(src.B, fan.B, gear.S, dmp.B, g.port)
    m.add_equation(lambda: e_in.P == ps.P)
    m.add_equation(lambda: e_loss.P == fan.tau * fan.w + gear.P_loss + dmp.tau * dmp.w)
    res = mt.simulate(m, 5.0, rtol=1e-10, atol=1e-12, solver=solver)
    stored = (0.5 * J1 * res.final("j1.w") ** 2 + 0.5 * J2 * res.final("j2.w") ** 2
              + 0.5 * J3 * res.final("j3.w") ** 2 + 0.5 * k * res.final("spring.phi") ** 2)
    e_in_final = res.final("e_in.E")
    assert e_in_final > 1.0                                  # a non-trivial exchange
    assert res.final("e_loss.E") > 0.1 * e_in_final
    assert res.final("e_loss.E") + stored == pytest.approx(e_in_final, rel=1e-6)
    # the gear losses are never negative, whichever way the power flows
    assert res["gear.P_loss"].min() >= -1e-9
    assert res.stats.events.get("gear", 0) >= 1             # power flow reversed
