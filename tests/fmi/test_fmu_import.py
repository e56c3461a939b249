"""FMU import (``mt.FMUComponent``): FMUs as sampled blocks of a model, co-simulated.

Round trips through Mechatron's own FMU export: a DC motor with voltage and load torque
inputs is exported (FMI 2.0 and 3.0 co-simulation with RK4 inside, FMI 2.0 model
exchange), imported into a loop with a controller, and compared with

- the same loop simulated with the motor as an ordinary part: with a controller sampled at
  the communication points the motor's input is constant over each communication step
  whether the motor is an FMU or a part, so the co-simulation is exact up to the motor's
  own integration: equal to rounding when both run the same fixed-step RK4;
- the analytic sampled-data loop (matrix exponential of the motor over one step, its
  input held), for a continuous controller: a co-simulated continuous controller *is* a
  sampled one (it reads the held FMU output), so the loop is x_k+1 = Phi x_k + Gamma u_k;
- the continuous loop, from which the co-simulation deviates by O(Ts) (the hold): the
  deviation halves when the communication step halves.

An FMU built by another tool: FMPy's container FMU (FMPy writes its model description and
ships its compiled runtime, which calls the FMU it nests through the FMI 3.0 API). No
independent third-party FMU is available offline here (the Modelica Reference FMUs are a
download), so this is the closest check of an FMU whose binary Mechatron did not build.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

import mechatron as mt
from mechatron.codegen import export_fmu
from mechatron.errors import ModelError
from mechatron.fmi import describe_fmu, port_name
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import rotational as rot

pytest.importorskip("fmpy", reason="FMU import runs FMUs through FMPy (pip install fmpy)")

R, L, K, J, B = 7.1, 3.408e-4, 0.151, 4.8e-6, 1.236e-4
DT = 1e-5          # RK4 step inside the co-simulation FMUs and of the direct runs
TS = 1e-3          # communication step
T_STOP = 0.1


class Motor(mt.Component):
    """The seed's DC motor with its voltage and load torque as inputs, speed as output."""

    V = mt.Input("V", start=0.0, doc="Armature voltage")
    tau_load = mt.Input("N*m", start=0.0, doc="Load torque, opposing rotation")
    w = mt.Output("rad/s", doc="Speed")
    source = el.ControlledVoltageSource()
    resistor = el.Resistor(R=R)
    inductor = el.Inductor(L=L)
    emf = em.RotationalEMF(k=K)
    inertia = rot.Inertia(J=J)
    damper = rot.RotationalDamper(D=B)
    load = rot.IdealTorqueSource()
    ground = el.ElectricalReference()
    fixed = rot.RotationalReference()

    def equations(self):
        return [mt.connect(self.V, self.source.u),
                mt.connect(self.tau_load, self.load.tau_in),
                mt.connect(self.source.p, self.resistor.p),
                mt.connect(self.resistor.n, self.inductor.p),
                mt.connect(self.inductor.n, self.emf.p),
                mt.connect(self.emf.n, self.source.n, self.ground.port),
                mt.connect(self.emf.A, self.inertia.port, self.damper.A, self.load.B),
                mt.connect(self.emf.B, self.damper.B, self.load.A, self.fixed.port),
                self.w == self.inertia.w]


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    d = tmp_path_factory.mktemp("fmu_import")
    cm = mt.compile_model(Motor())
    out = {}
    for key, fmi, kind in (("cs2", 2, "cs"), ("cs3", 3, "cs"), ("me2", 2, "me")):
        out[key] = str(d / f"motor_{key}.fmu")
        export_fmu(cm, out[key], fmi=fmi, kind=kind, solver="rk4", dt=DT, t_stop=1.0)
    return out


def loop(plant, *, sampled=True, Kp=0.05, Ki=2.0, w_ref=100.0, tau=0.0, reference=None):
    """Speed loop: a PI controller (sampled at TS, or continuous) drives the plant to a
    constant speed ``w_ref``, or to the signal of the block ``reference``."""
    m = mt.System("loop")
    ref = m.add("ref", reference if reference is not None else
                blocks.Constant(value=w_ref))
    err = m.add("err", blocks.Add(k1=1.0, k2=-1.0))
    if sampled:
        ctrl = m.add("pid", blocks.DiscretePID(Ts=TS, Kp=Kp, Ki=Ki))
    else:
        ctrl = m.add("pid", blocks.Gain(k=Kp))
    load = m.add("load", blocks.Constant(value=tau))
    m.add("plant", plant)
    m.connect(ref.y, err.u1)
    m.connect(plant.w, err.u2)
    m.connect(err.y, ctrl.u)
    m.connect(ctrl.y, plant.V)
    m.connect(load.y, plant.tau_load)
    return m


TICKS = np.arange(int(round(T_STOP / TS)) + 1) * TS


def at_ticks(res, name):
    idx = np.searchsorted(res.t, TICKS - 1e-12)
    return res[name][idx]


def test_ports_are_named_after_the_fmu_variables(fmus):
    block = mt.FMUComponent(fmus["cs2"], Ts=TS)
    decls = type(block)._declarations
    assert isinstance(decls["V"], mt.Input) and decls["V"].unit == "V"
    assert isinstance(decls["tau_load"], mt.Input)
    assert isinstance(decls["w"], mt.Output) and decls["w"].unit == "rad/s"
    assert isinstance(decls["inertia_w"], mt.Output)           # every logged variable
    assert isinstance(decls["resistor_R"], mt.Parameter)
    assert decls["resistor_R"].default == R
    assert port_name("inertia.w") == "inertia_w" and port_name("der(x)") == "der_x_"
    assert port_name("1x") == "v_1x"
    desc = describe_fmu(fmus["cs2"])
    assert desc.kinds == ("cs",) and desc.fmi == "2.0"
    only = mt.FMUComponent(fmus["cs2"], Ts=TS, outputs=["w"])
    assert "inertia_w" not in type(only)._declarations


@pytest.mark.parametrize("key", ["cs2", "cs3"])
def test_co_simulation_round_trip_equals_the_direct_loop(fmus, key):
    """Sampled controller at the communication points, RK4 with the same step inside the
    FMU and in the direct run: the same arithmetic, so equal to rounding (1e-12 relative
    leaves room for the C compiler's and CasADi's orders of summation)."""
    ref = mt.simulate(loop(Motor()), T_STOP, solver="rk4", dt=DT)
    res = mt.simulate(loop(mt.FMUComponent(fmus[key], Ts=TS, outputs=["w"])), T_STOP,
                      solver="rk4", dt=DT)
    w_ref = at_ticks(ref, "plant.w")
    assert w_ref[-1] > 50.0
    np.testing.assert_allclose(at_ticks(res, "plant.w"), w_ref, rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(at_ticks(res, "pid.y"), at_ticks(ref, "pid.y"), rtol=1e-12,
                               atol=1e-12)
    assert res.stats.communication_steps == len(TICKS) - 1
    assert res.stats.events["plant"] == len(TICKS)


def test_variable_step_host_with_a_co_simulation_fmu(fmus):
    """The host integrated by rodas4 (the default) between communication points; the
    motor inside the FMU is RK4 as in the fixed-step reference: equal to the FMU's own
    step error, 1e-9 relative."""
    ref = mt.simulate(loop(Motor()), T_STOP, solver="rk4", dt=DT)
    res = mt.simulate(loop(mt.FMUComponent(fmus["cs2"], Ts=TS, outputs=["w"])), T_STOP,
                      t_out=TICKS, rtol=1e-10, atol=1e-10)
    assert res.stats.solver == "rodas4"
    np.testing.assert_allclose(res["plant.w"], at_ticks(ref, "plant.w"), rtol=1e-9,
                               atol=1e-9)


def test_model_exchange_fmu_is_integrated_by_cvode_between_communication_points(fmus):
    """Model exchange: FMPy's CVODE at rtol 1e-10 integrates the motor over each step;
    against the RK4 reference (its own error ~1e-9 relative at DT = 1e-5 for a 48 us
    electrical time constant) the difference is bounded by both: 1e-7 relative."""
    ref = mt.simulate(loop(Motor()), T_STOP, solver="rk4", dt=DT)
    block = mt.FMUComponent(fmus["me2"], Ts=TS, outputs=["w"])
    assert block.kind == "me"
    res = mt.simulate(loop(block), T_STOP, t_out=TICKS, rtol=1e-10, atol=1e-10)
    w = at_ticks(ref, "plant.w")
    np.testing.assert_allclose(res["plant.w"], w, rtol=0, atol=1e-7 * np.max(np.abs(w)))


def _sampled_loop_analytic(Kp, w_ref, n):
    """The motor under a proportional controller that reads the speed at the ticks and
    holds its voltage: x_k+1 = Phi x_k + Gamma V_k, V_k = Kp (w_ref - w_k), x = (i, w)."""
    A = np.array([[-R / L, -K / L], [K / J, -B / J]])
    b = np.array([1 / L, 0.0])
    aug = np.zeros((3, 3))
    aug[:2, :2], aug[:2, 2] = A, b
    E = expm(aug * TS)
    Phi, Gamma = E[:2, :2], E[:2, 2]
    x = np.zeros(2)
    w = [0.0]
    for _ in range(n):
        x = Phi @ x + Gamma * Kp * (w_ref - x[1])
        w.append(x[1])
    return np.array(w)


def test_continuous_controller_sees_the_held_fmu_output(fmus):
    """A continuous P controller reading the FMU's held speed is a sampled controller:
    the co-simulation equals the analytic sampled-data loop (to the FMU's RK4 error)."""
    Kp = 0.05
    res = mt.simulate(loop(mt.FMUComponent(fmus["cs2"], Ts=TS, outputs=["w"]),
                           sampled=False, Kp=Kp), T_STOP, t_out=TICKS)
    expect = _sampled_loop_analytic(Kp, 100.0, len(TICKS) - 1)
    np.testing.assert_allclose(res["plant.w"], expect, rtol=0,
                               atol=1e-8 * np.max(np.abs(expect)))


def test_hold_error_is_first_order_in_the_communication_step(fmus):
    """Against the continuous loop (the motor as a part), the co-simulation's error comes
    from holding the speed over a communication step: O(Ts), so halving Ts halves it."""
    Kp = 0.05
    t_cmp = np.linspace(0.0, 0.02, 11)
    ref = mt.simulate(loop(Motor(), sampled=False, Kp=Kp), 0.02, t_out=t_cmp, rtol=1e-10,
                      atol=1e-10)
    errs = []
    for ts in (4e-4, 2e-4, 1e-4):
        res = mt.simulate(loop(mt.FMUComponent(fmus["cs2"], Ts=ts, outputs=["w"]),
                               sampled=False, Kp=Kp), 0.02, t_out=t_cmp)
        # the held output lags the motor by up to Ts: compare the motor's own speed
        errs.append(np.max(np.abs(res["plant.w"] - ref["plant.w"])))
    ratios = [errs[0] / errs[1], errs[1] / errs[2]]
    assert all(1.7 < r < 2.3 for r in ratios), (errs, ratios)


def test_fmu_parameters_are_parameters_of_the_block(fmus):
    """The FMU's parameters are set from the block (constructor or params=): the open-loop
    final speed is (k V - R_new tau) / (R_new B + k^2) with the new resistance."""
    R_new, V, tau = 2 * R, 12.0, 0.005

    def open_loop(**kw):
        m = mt.System("open")
        v = m.add("v", blocks.Constant(value=V))
        t = m.add("t", blocks.Constant(value=tau))
        plant = m.add("plant", mt.FMUComponent(fmus["cs2"], Ts=TS, outputs=["w"], **kw))
        m.connect(v.y, plant.V)
        m.connect(t.y, plant.tau_load)
        return m

    expect = (K * V - R_new * tau) / (R_new * B + K * K)
    a = mt.simulate(open_loop(resistor_R=R_new), 0.1, solver="rk4", dt=DT)
    b = mt.simulate(open_loop(), 0.1, solver="rk4", dt=DT,
                    params={"plant.resistor_R": R_new})
    for res in (a, b):
        assert res.final("plant.w") == pytest.approx(expect, rel=1e-6)


def test_a_container_fmu_made_by_fmpy(fmus, tmp_path):
    """FMPy's container FMU (model description and runtime binary by FMPy, nesting the
    FMI 3.0 motor) as a block: the same loop as the motor part, to rounding."""
    import uuid
    from pathlib import Path

    from fmpy import read_model_description
    from fmpy.container_fmu.cli import create_container_fmu
    from fmpy.container_fmu.config import Component, Configuration
    from fmpy.model_description import (CoSimulation, DefaultExperiment, ModelDescription,
                                        ModelVariable, Unknown)
    inner = read_model_description(fmus["cs3"])
    comp = Component(name="motor", filename=Path(fmus["cs3"]), modelDescription=inner)
    by_name = {v.name: v for v in inner.modelVariables}
    md = ModelDescription(fmiVersion="3.0", modelName="container",
                          instantiationToken=str(uuid.uuid4()), generationTool="FMPy",
                          coSimulation=CoSimulation(modelIdentifier="container_fmu",
                                                    fixedInternalStepSize=DT))
    md.defaultExperiment = DefaultExperiment(startTime="0", stopTime="1", stepSize=str(TS))
    md.modelVariables.append(ModelVariable(name="time", type="Float64",
                                           causality="independent",
                                           variability="continuous"))
    mapping = {}
    for name, causality in (("V", "input"), ("tau_load", "input"), ("w", "output")):
        v = ModelVariable(name=name, type="Float64", causality=causality,
                          variability="continuous")
        if causality == "input":
            v.start = "0.0"
        md.modelVariables.append(v)
        mapping[v] = [(comp, by_name[name])]
    md.outputs = [Unknown(variable=md.modelVariables[-1])]
    work = tmp_path / "container"
    work.mkdir()
    path = tmp_path / "container.fmu"
    create_container_fmu(Configuration(parallelDoStep=False, modelDescription=md,
                                       components=[comp], connections=[],
                                       variableMappings=mapping), work, path)
    block = mt.FMUComponent(path)
    assert float(block._values.get("Ts", 0)) == TS       # the default experiment's step
    ref = mt.simulate(loop(Motor()), T_STOP, solver="rk4", dt=DT)
    res = mt.simulate(loop(block), T_STOP, solver="rk4", dt=DT)
    np.testing.assert_allclose(at_ticks(res, "plant.w"), at_ticks(ref, "plant.w"),
                               rtol=1e-12, atol=1e-9)


def test_errors_name_the_fmu_and_what_to_do(fmus, tmp_path):
    with pytest.raises(ModelError, match="no FMU file"):
        mt.FMUComponent(tmp_path / "missing.fmu")
    with pytest.raises(ModelError, match="no output named nope"):
        mt.FMUComponent(fmus["cs2"], outputs=["nope"])
    with pytest.raises(ModelError, match="no model exchange interface"):
        mt.FMUComponent(fmus["cs2"], kind="me")
    with pytest.raises(TypeError, match="unexpected keyword 'bogus'"):
        mt.FMUComponent(fmus["cs2"], bogus=1.0)
    with pytest.raises(mt.errors.SimulationError, match="must divide every communication"):
        mt.simulate(loop(mt.FMUComponent(fmus["cs2"], Ts=TS, outputs=["w"])), 0.01,
                    solver="rk4", dt=3e-4)


def test_import_mechatron_does_not_load_fmpy():
    import subprocess
    import sys
    code = ("import sys, mechatron as mt; assert 'fmpy' not in sys.modules; "
            "mt.FMUComponent; assert 'fmpy' not in sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True)


def test_a_model_with_an_fmu_block_is_not_turned_into_c(fmus, tmp_path):
    from mechatron.codegen import CodegenError, generate_c
    model = loop(mt.FMUComponent(fmus["cs2"], Ts=TS, outputs=["w"]))
    with pytest.raises(CodegenError, match="plant is an imported FMU"):
        generate_c(model, tmp_path / "c", solver="rk4", dt=DT)


def test_a_compiled_model_with_an_fmu_block_is_saved_and_loaded(fmus, tmp_path):
    cm = mt.compile_model(loop(mt.FMUComponent(fmus["cs2"], Ts=TS, outputs=["w"])))
    cm.save(tmp_path / "loop.mtc")
    again = type(cm).load(tmp_path / "loop.mtc")
    assert again.report["external_blocks"][0]["path"] == "plant"
    a = mt.simulate(cm, 0.01, solver="rk4", dt=DT)
    b = mt.simulate(again, 0.01, solver="rk4", dt=DT)
    np.testing.assert_array_equal(a["plant.w"], b["plant.w"])



@pytest.mark.parametrize("host", ["rosenbrock", "rk45"])
def test_an_edge_on_an_output_time_inside_a_communication_step_is_logged_after_it(fmus,
                                                                                  host):
    """The reference speed pulses on at an output time inside a communication interval
    (an edge located as an event): every host logs the loop after the edge there, as
    the compiled Rodas4 host does and as `simulate` does without an FMU."""
    t_out = np.linspace(0.0, 0.02, 81)
    t_edge = float(t_out[50])                   # inside [0.012, 0.013]

    def model():
        return loop(mt.FMUComponent(fmus["cs2"], Ts=TS, outputs=["w"]), sampled=False,
                    reference=blocks.Pulse(delay=t_edge, period=0.004, width=0.5,
                                           amplitude=100.0))

    ref = mt.simulate(model(), 0.02, solver="rodas4", t_out=t_out, rtol=1e-10, atol=1e-10)
    res = mt.simulate(model(), 0.02, solver=host, t_out=t_out, rtol=1e-10, atol=1e-10)
    assert ref["ref.y"][49] == 0.0 and ref["ref.y"][50] == 100.0
    assert res["ref.y"][50] == 100.0
    np.testing.assert_allclose(res["pid.y"], ref["pid.y"], rtol=1e-6, atol=1e-9)
