"""External inputs of a model as FMI inputs (``causality="input"``) of its FMUs.

Checked with FMPy, an independent importer: validation, the declared variables, and runs
driven by ``simulate_fmu(..., input=...)`` against Mechatron's own runs with
``inputs={...}``, against a hand-written NumPy RK4 loop with a zero-order-held input, and
against SciPy's ``solve_ivp`` of the same ODE.

Why the co-simulation runs agree to rounding: FMPy sets each input at a communication
point (linear interpolation in its table) before ``doStep``, and the FMU holds it over the
communication step; Mechatron's fixed-step run samples a ``(t, u)`` table at the start of
every solver step (``np.interp``) and holds it over that step. With the communication step
equal to the solver step both sample the same piecewise-linear table at the same times
``k*dt``, so the step functions see the same values. With a communication step of several
solver steps the FMU holds the input over all of them; Mechatron is then given the same
held signal as a function of time (the table sampled at the last communication point).
"""

from __future__ import annotations

import math
import zipfile
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import mechatron as mt
from mechatron.codegen import export_fmu
from mechatron.library import electrical as el
from mechatron.library import electromechanical as em
from mechatron.library import rotational as rot

fmpy = pytest.importorskip("fmpy", reason="FMPy is needed to check FMUs (pip install fmpy)")
from fmpy import read_model_description, simulate_fmu  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

R, C = 1e3, 1e-6
TAU = R * C
DT, T_STOP = 1e-5, 5e-3


class FmuDrivenRC(mt.Component):
    """RC low-pass whose source voltage is the external input ``u``:
    ``tau dv/dt = u - v`` with ``tau = R C``."""

    u = mt.Input("V", doc="Source voltage")
    src = el.ControlledVoltageSource()
    r = el.Resistor(R=R)
    c = el.Capacitor(C=C)
    g = el.ElectricalReference()

    def equations(self):
        return [mt.connect(self.u, self.src.u), mt.connect(self.src.p, self.r.p),
                mt.connect(self.r.n, self.c.p),
                mt.connect(self.src.n, self.c.n, self.g.port)]


# DC motor with two inputs: armature voltage v and an external torque tau on the rotor.
# L di/dt = v - Ra i - k w;  J dw/dt = k i - D w + tau.
RA, LA, KM, JM, DM = 2.0, 5e-3, 0.05, 1e-5, 1e-6
V_START = 1.5


def _motor():
    m = mt.System("io_motor")
    v = m.input("v", unit="V", start=V_START, doc="Armature voltage")
    tau = m.input("tau", unit="N*m", doc="External torque on the rotor")
    src = m.add("src", el.ControlledVoltageSource())
    res = m.add("res", el.Resistor(R=RA))
    ind = m.add("ind", el.Inductor(L=LA))
    emf = m.add("emf", em.RotationalEMF(k=KM))
    rotor = m.add("rotor", rot.Inertia(J=JM))
    damper = m.add("damper", rot.RotationalDamper(D=DM))
    load = m.add("load", rot.IdealTorqueSource())
    gnd = m.add("gnd", el.ElectricalReference())
    fixed = m.add("fixed", rot.RotationalReference())
    m.connect(v, src.u)
    m.connect(tau, load.tau_in)
    m.connect(src.p, res.p)
    m.connect(res.n, ind.p)
    m.connect(ind.n, emf.p)
    m.connect(emf.n, src.n, gnd.port)
    m.connect(emf.A, rotor.port, damper.A, load.A)
    m.connect(emf.B, damper.B, load.B, fixed.port)
    return m


@pytest.fixture(scope="module")
def rc():
    return mt.compile_model(FmuDrivenRC())


@pytest.fixture(scope="module")
def motor():
    return mt.compile_model(_motor())


def _signals(t, **columns):
    """FMPy's input: a structured array with a 'time' field and one field per input."""
    names = ["time", *columns]
    out = np.zeros(len(t), dtype=[(n, np.float64) for n in names])
    out["time"] = t
    for n, v in columns.items():
        out[n] = v
    return out


# A table with breakpoints on the solver grid: rest, a steep rise over one step, a ramp
# down through zero, a hold.
T_TAB = np.array([0.0, 1e-3, 1.01e-3, 2e-3, 3.5e-3, 5e-3])
U_TAB = np.array([0.0, 0.0, 1.0, 1.0, -0.5, -0.5])


def _rk4_zoh(t, u_held, x0=0.0):
    """Hand-written RK4 of ``tau dv/dt = u - v`` with ``u`` held over each step: for a
    linear ODE one RK4 step is ``v+ = u + (v - u) * R4(-h/tau)``."""
    z = -DT / TAU
    r4 = 1 + z + z ** 2 / 2 + z ** 3 / 6 + z ** 4 / 24
    v = np.empty(t.size)
    v[0] = x0
    for k in range(t.size - 1):
        v[k + 1] = u_held[k] + (v[k] - u_held[k]) * r4
    return v


def _variables(path):
    return {v.name: v for v in read_model_description(str(path)).modelVariables}


@pytest.mark.parametrize("fmi", [2, 3])
def test_input_is_declared_as_an_fmi_input_and_validates(rc, tmp_path, fmi):
    path = tmp_path / f"rc{fmi}.fmu"
    info = export_fmu(rc, path, fmi=fmi, kind="cs", solver="rk4", dt=DT, t_stop=T_STOP)
    assert validate_fmu(str(path)) == []
    var = _variables(path)
    u = var["u"]
    assert (u.causality, u.variability) == ("input", "continuous")
    assert float(u.start) == 0.0          # no declared start: 0, as FMI needs a start
    assert u.unit == "V" and u.description == "Source voltage"
    assert [n for n, v in var.items() if v.causality == "parameter"] == ["r.R", "c.C"]
    # one variable per name: the logged copy of u is the input itself, not an output
    xml = zipfile.ZipFile(path).read("modelDescription.xml")
    names = [e.get("name") for e in ET.fromstring(xml).iter()
             if e.get("causality") is not None]
    assert names.count("u") == 1 and len(names) == len(set(names))
    outputs = {n for n, v in var.items() if v.causality == "output"}
    assert outputs == set(rc.names) - {"u"}
    assert info["inputs"] == ["u"] and info["parameters"] == 2


@pytest.mark.parametrize("fmi", [2, 3])
def test_cosimulation_with_a_table_input_matches_mechatron_and_a_numpy_loop(rc, tmp_path,
                                                                           fmi):
    path = tmp_path / f"rc{fmi}.fmu"
    export_fmu(rc, path, fmi=fmi, kind="cs", solver="rk4", dt=DT, t_stop=T_STOP)
    fmu = simulate_fmu(str(path), stop_time=T_STOP, output_interval=DT,
                       input=_signals(T_TAB, u=U_TAB), output=["c.v", "r.i", "u"])
    desk = mt.simulate(rc, T_STOP, solver="rk4", dt=DT, inputs={"u": (T_TAB, U_TAB)})
    np.testing.assert_allclose(fmu["time"], desk.t, rtol=0, atol=1e-15)
    for name in ("c.v", "r.i", "u"):
        np.testing.assert_allclose(fmu[name], desk[name], rtol=0,
                                   atol=1e-12 * np.max(np.abs(desk[name])))
    # independent: RK4 with the table sampled at each step start and held
    held = np.interp(desk.t, T_TAB, U_TAB)
    np.testing.assert_allclose(fmu["c.v"], _rk4_zoh(desk.t, held), rtol=0, atol=1e-12)
    # the input read back after a step is the value held over that step
    np.testing.assert_allclose(fmu["u"][1:], held[:-1], rtol=0, atol=1e-15)
    # physics: the exact response of the RC to the held input, v+ = u + (v - u) e^(-h/tau)
    # (RK4's error per step is (h/tau)^5/120 = 8e-13 here)
    exact = np.empty(desk.t.size)
    exact[0] = 0.0
    for k in range(desk.t.size - 1):
        exact[k + 1] = held[k] + (exact[k] - held[k]) * math.exp(-DT / TAU)
    np.testing.assert_allclose(fmu["c.v"], exact, rtol=0, atol=1e-9)


def test_communication_step_of_several_solver_steps_holds_the_input(rc, tmp_path):
    path = tmp_path / "rc.fmu"
    export_fmu(rc, path, fmi=2, kind="cs", solver="rk4", dt=DT, t_stop=T_STOP)
    H = 5 * DT
    fmu = simulate_fmu(str(path), stop_time=T_STOP, output_interval=H,
                       input=_signals(T_TAB, u=U_TAB), output=["c.v"])

    def held(t):     # the table at the last communication point: what the FMU holds
        return np.interp(np.floor(np.asarray(t) / H + 1e-6) * H, T_TAB, U_TAB)

    desk = mt.simulate(rc, T_STOP, solver="rk4", dt=DT, inputs={"u": held})
    np.testing.assert_allclose(fmu["c.v"], desk["c.v"][::5], rtol=0, atol=1e-12)
    grid = np.arange(desk.t.size) * DT
    np.testing.assert_allclose(fmu["c.v"], _rk4_zoh(grid, held(grid))[::5], rtol=0,
                               atol=1e-12)


def test_input_start_value_comes_from_the_declaration_or_params(rc, motor, tmp_path):
    path = tmp_path / "rc2.fmu"
    export_fmu(rc, path, fmi=2, kind="cs", dt=DT, params={"u": 2.0}, t_stop=T_STOP)
    assert float(_variables(path)["u"].start) == 2.0
    # no input signal given: the start value drives the model, a 2 V step response
    res = simulate_fmu(str(path), stop_time=T_STOP, output_interval=10 * DT,
                       output=["c.v"])
    exact = 2.0 * (1 - np.exp(-res["time"] / TAU))
    np.testing.assert_allclose(res["c.v"], exact, rtol=0, atol=1e-9)   # RK4: O(h^4)
    path = tmp_path / "motor3.fmu"
    export_fmu(motor, path, fmi=3, kind="cs", dt=1e-4)
    assert validate_fmu(str(path)) == []
    var = _variables(path)
    assert float(var["v"].start) == V_START and float(var["tau"].start) == 0.0
    assert var["tau"].unit == "N*m"
    assert var["v"].causality == var["tau"].causality == "input"


M_STOP = 0.05
TM = np.array([0.0, 0.01, 0.02, 0.03, 0.05])
VM = np.array([0.0, 6.0, 6.0, -3.0, -3.0])
TAUM = np.array([0.0, 0.0, -2e-3, 1e-3, 1e-3])

# Piecewise-constant inputs for FMPy's model-exchange run: FMPy's CVode right-hand side
# does not set the inputs (it sets them at communication points and input events only),
# so the inputs must be constant between events; FMPy marks an event where a time repeats.
EVENTS = [0.01, 0.02, 0.03]
V_STEPS = [0.0, 6.0, 6.0, -3.0]
TAU_STEPS = [0.0, 0.0, -2e-3, 1e-3]


def _steps(values, width=0.0):
    """A step table at EVENTS: each jump as a repeated time (FMPy's event) or, for
    Mechatron (strictly increasing times), as a ramp of ``width`` s."""
    t, u = [0.0], [values[0]]
    for k, te in enumerate(EVENTS):
        t += [te, te + width]
        u += [values[k], values[k + 1]]
    return np.array(t + [M_STOP]), np.array(u + [values[-1]])


def _motor_matrices():
    """x = (i, w): dx/dt = A x + B (v, tau)."""
    A = np.array([[-RA / LA, -KM / LA], [KM / JM, -DM / JM]])
    B = np.array([[1 / LA, 0.0], [0.0, 1 / JM]])
    return A, B


def _motor_exact_steps(times):
    """Exact response to the step inputs: on each constant segment
    ``x(t) = x_ss + expm(A (t - t_k)) (x_k - x_ss)`` with ``x_ss = -A^-1 B u``."""
    from scipy.linalg import expm
    A, B = _motor_matrices()
    knots = [0.0, *EVENTS, np.inf]
    out = np.empty((times.size, 2))
    xk = np.zeros(2)
    for seg in range(len(knots) - 1):
        a, b = knots[seg], knots[seg + 1]
        xss = -np.linalg.solve(A, B @ np.array([V_STEPS[seg], TAU_STEPS[seg]]))
        sel = (times >= a) & (times < b)
        for j in np.flatnonzero(sel):
            out[j] = xss + expm(A * (times[j] - a)) @ (xk - xss)
        if np.isfinite(b):
            xk = xss + expm(A * (b - a)) @ (xk - xss)
    return out


def test_model_exchange_with_two_inputs_matches_variable_step_and_exact(motor, tmp_path):
    path = tmp_path / "motor_me.fmu"
    export_fmu(motor, path, fmi=2, kind="me", dt=1e-4, t_stop=M_STOP)
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert len(md.derivatives) == motor.nx == 2
    assert {v.name for v in md.modelVariables if v.causality == "input"} == {"v", "tau"}
    out = ["ind.i", "rotor.w"]
    tf, vf = _steps(V_STEPS)
    _, af = _steps(TAU_STEPS)
    fmu = simulate_fmu(str(path), stop_time=M_STOP, output_interval=1e-4, output=out,
                       input=_signals(tf, v=vf, tau=af), relative_tolerance=1e-10,
                       record_events=False)
    grid = fmu["time"]
    # Mechatron's variable-step run: the jumps as 1 ps ramps (their effect on i is
    # ~ width * jump / (2 L) = 6e-10 A)
    tm, vm = _steps(V_STEPS, 1e-12)
    _, am = _steps(TAU_STEPS, 1e-12)
    desk = mt.simulate(motor, M_STOP, rtol=1e-11, atol=1e-13, t_out=grid,
                       inputs={"v": (tm, vm), "tau": (tm, am)})
    exact = _motor_exact_steps(grid)
    for k, name in enumerate(out):
        scale = np.max(np.abs(exact[:, k]))
        assert np.max(np.abs(desk[name] - exact[:, k])) <= 1e-8 * scale, name
        assert np.max(np.abs(fmu[name] - exact[:, k])) <= 1e-7 * scale, name
        assert np.max(np.abs(fmu[name] - desk[name])) <= 1e-6 * scale, name


def test_model_exchange_derivatives_follow_a_continuously_set_input(motor, tmp_path):
    """An importer that sets the inputs at every right-hand-side evaluation (here SciPy's
    DOP853 driving the FMU through FMPy's FMI 2.0 calls) sees the piecewise-linear inputs
    as Mechatron's variable-step run does."""
    from fmpy import extract
    from fmpy.fmi2 import FMU2Model

    path = tmp_path / "motor_me.fmu"
    export_fmu(motor, path, fmi=2, kind="me", dt=1e-4, t_stop=M_STOP)
    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    unzipped = extract(str(path), unzipdir=str(tmp_path / "unzipped"))
    fmu = FMU2Model(guid=md.guid, unzipDirectory=unzipped,
                    modelIdentifier=md.modelExchange.modelIdentifier, instanceName="m")
    fmu.instantiate()
    try:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        fmu.enterEventMode()
        fmu.newDiscreteStates()
        fmu.enterContinuousTimeMode()
        x = np.zeros(2)
        dx = np.zeros(2)
        px, pdx = (np.ctypeslib.as_ctypes(a) for a in (x, dx))

        def rhs(t, state):
            x[:] = state
            fmu.setTime(t)
            fmu.setReal([vr["v"], vr["tau"]],
                        [np.interp(t, TM, VM), np.interp(t, TM, TAUM)])
            fmu.setContinuousStates(px, 2)
            fmu.getDerivatives(pdx, 2)
            return dx.copy()

        grid = np.linspace(0.0, M_STOP, 501)
        sol = solve_ivp(rhs, (0.0, M_STOP), [0.0, 0.0], t_eval=grid, method="DOP853",
                        rtol=1e-12, atol=1e-14, max_step=2e-3)
        assert sol.success
    finally:
        fmu.terminate()
        fmu.freeInstance()
    desk = mt.simulate(motor, M_STOP, rtol=1e-11, atol=1e-13, t_out=grid,
                       inputs={"v": (TM, VM), "tau": (TM, TAUM)})
    for k, name in enumerate(["ind.i", "rotor.w"]):
        scale = np.max(np.abs(desk[name]))
        assert np.max(np.abs(sol.y[k] - desk[name])) <= 1e-8 * scale, name


def test_cosimulation_with_two_inputs_matches_fixed_step(motor, tmp_path):
    path = tmp_path / "motor_cs3.fmu"
    dt = 1e-4
    export_fmu(motor, path, fmi=3, kind="cs", solver="trapezoidal", iterations=1, dt=dt,
               t_stop=M_STOP)
    out = ["ind.i", "rotor.w", "tau"]
    fmu = simulate_fmu(str(path), stop_time=M_STOP, output_interval=dt, output=out,
                       input=_signals(TM, v=VM, tau=TAUM))
    desk = mt.simulate(motor, M_STOP, solver="trapezoidal", iterations=1, dt=dt,
                       inputs={"v": (TM, VM), "tau": (TM, TAUM)})
    for name in out:
        scale = np.max(np.abs(desk[name]))
        np.testing.assert_allclose(fmu[name], desk[name], rtol=0, atol=1e-12 * scale)


def test_model_without_inputs_exports_as_before(tmp_path):
    cm = mt.compile_model(mt.models.get("dc_motor").build())
    assert cm.input_names == []
    path = tmp_path / "dc.fmu"
    info = export_fmu(cm, path, fmi=2, kind="cs", dt=1e-4)
    var = read_model_description(str(path)).modelVariables
    assert [v.name for v in var] == [*cm.param_names, *cm.names]
    assert [v.valueReference for v in var] == list(range(len(var)))
    assert all(v.causality == "parameter" for v in var[:len(cm.param_names)])
    assert all(v.causality == "output" for v in var[len(cm.param_names):])
    assert info["inputs"] == [] and info["parameters"] == len(cm.param_names)
    assert info["outputs"] == len(cm.names)


def test_generated_c_names_the_input_slots_and_a_driver_can_write_them(motor, tmp_path):
    """Generated C: ``<NAME>_INPUT_<INPUT>`` gives each input's slot of p; a hand-written
    real-time loop that writes the sampled inputs before each step reproduces
    ``mt.simulate(..., solver=, dt=, inputs=...)``."""
    import shutil
    import subprocess

    from mechatron.codegen import generate_c

    cc = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
    if cc is None:
        pytest.skip("no C compiler")
    dt, n = 1e-4, 500
    code = generate_c(motor, tmp_path / "c", solver="rk4", dt=dt, name="iom")
    header = (tmp_path / "c" / "iom.h").read_text()
    slots = dict(zip(motor.input_names, motor.input_index))
    assert f"#define IOM_INPUT_V {slots['v']} " in header
    assert f"#define IOM_INPUT_TAU {slots['tau']} " in header
    assert "#define IOM_NINPUTS 2" in header
    times = np.arange(n) * dt
    v, tau = np.interp(times, TM, VM), np.interp(times, TM, TAUM)
    array = ", ".join
    driver = f"""
#include <stdio.h>
#include "iom.h"
static const double v[{n}] = {{{array(repr(float(x)) for x in v)}}};
static const double tau[{n}] = {{{array(repr(float(x)) for x in tau)}}};
int main(void)
{{
    static iom_model m;
    int k, i = iom_output_index("ind.i"), w = iom_output_index("rotor.w");
    iom_init(&m);
    for (k = 0; k < {n}; ++k) {{
        if (iom_set_parameter(&m, IOM_INPUT_V, v[k]) != IOM_OK) return 1;
        if (iom_set_parameter(&m, IOM_INPUT_TAU, tau[k]) != IOM_OK) return 1;
        if (iom_step(&m) != IOM_OK) return 2;
        printf("%.17g %.17g\\n", iom_get_output(&m, i), iom_get_output(&m, w));
    }}
    return 0;
}}
"""
    (tmp_path / "c" / "driver.c").write_text(driver)
    exe = tmp_path / "c" / "driver"
    subprocess.run([cc, "-std=c99", "-O2", "-ffp-contract=off", "-o", str(exe),
                    str(tmp_path / "c" / "driver.c"), str(code.files["iom.c"]),
                    str(code.files["iom_casadi.c"]), "-lm"], check=True)
    run = subprocess.run([str(exe)], capture_output=True, text=True, check=True)
    got = np.loadtxt(run.stdout.splitlines())
    desk = mt.simulate(motor, n * dt, solver="rk4", dt=dt,
                       inputs={"v": (TM, VM), "tau": (TM, TAUM)})
    for k, name in enumerate(["ind.i", "rotor.w"]):
        ref = desk[name][1:]
        np.testing.assert_allclose(got[:, k], ref, rtol=0, atol=1e-12 * np.max(np.abs(ref)))


def test_the_database_motor_with_inputs_runs_as_an_fmu_against_the_analytic_load_step(
        tmp_path):
    """dc_motor's ``inputs`` variant exported as FMI 2 CS: FMPy drives its voltage and load
    torque; the final speed is (k V - R T) / (R B + k^2)."""
    path = tmp_path / "dc_motor_inputs.fmu"
    cm = mt.compile_model(mt.models.get("dc_motor").build("inputs"))
    export_fmu(cm, path, fmi=2, kind="cs", solver="rk4", dt=1e-5, t_stop=0.6)
    assert not validate_fmu(str(path))
    t = np.array([0.0, 0.2, 0.6])
    out = simulate_fmu(str(path), stop_time=0.6, output_interval=1e-3,
                       input=_signals(t, V=[19.2, 19.2, 19.2], tau_load=[0.0, 0.01, 0.01]),
                       output=["inertia.w"])
    R, k, B = 7.1, 0.151, 1.236e-4
    assert out["inertia.w"][-1] == pytest.approx((k * 19.2 - R * 0.01) / (R * B + k * k),
                                                 rel=1e-6)
