"""State selection of whole models does not depend on rounding, scaling or the order in
which parts are added.

On some CPUs (OpenBLAS kernels) the double pendulum and the four-bar used to compile with
``der(j1.q)`` as a state instead of ``j1.w``: the pivoted QR that picks the dummy
derivatives met an exact tie and LAPACK broke it by rounding. Here the Jacobian the
compiler pivots on is moved by a few ulps, scaled and its rows shuffled (what another
BLAS kernel or another equation order does to it), the model's numbers are moved by a
few ulps, and the parts are added in other orders. The states must stay those of the
rule (docs/compiler.md), and the generated C code must stay byte for byte the same.
"""

import math

import casadi as ca
import numpy as np
import pytest

import mechatron as mt
import mechatron.compiler.structure as structure
from mechatron.core import Start
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.library import rotational as rot
from mechatron.library.multibody import joints, parts
from mechatron.library.multibody.mechanisms import four_bar_angles


# ------------------------------------------------------------------ models, any order
def assemble(name, spec, connections, order=None, rng=None):
    """A System with the parts of `spec` (name -> factory) added in `order` and the
    `connections` (tuples of "part.port") made in a shuffled order when `rng` is given."""
    m = mt.System(name)
    added = {}
    for key in order or list(spec):
        added[key] = m.add(key, spec[key]())
    links = list(connections)
    if rng is not None:
        links = [tuple(rng.permutation(c)) for c in (links[i] for i in
                                                     rng.permutation(len(links)))]
    for link in links:
        ports = []
        for ref in link:
            part, port = str(ref).split(".", 1)
            ports.append(getattr(added[part], port))
        m.connect(*ports)
    return m


def double_pendulum_spec(l1=1.0, l2=1.0, m1=1.0, m2=1.0, alpha1=math.pi / 2,
                         alpha2=0.0):
    """The double pendulum of `mechanisms.double_pendulum`, as parts and links."""
    spec = {
        "world": lambda: parts.World(),
        "j1": lambda: joints.Revolute(q=alpha1, w=0.0),
        "rod1": lambda: parts.RigidTransform(ry=-l1),
        "m1": lambda: parts.PointMass(m=m1),
        "j2": lambda: joints.Revolute(q=alpha2 - alpha1, w=0.0),
        "rod2": lambda: parts.RigidTransform(ry=-l2),
        "m2": lambda: parts.PointMass(m=m2),
    }
    links = [("world.frame", "j1.frame_a"), ("j1.frame_b", "rod1.frame_a"),
             ("rod1.frame_b", "m1.frame", "j2.frame_a"), ("j2.frame_b", "rod2.frame_a"),
             ("rod2.frame_b", "m2.frame")]
    return "double_pendulum", spec, links


def pendulum_chain_spec(n, angles=(0.3, 0.1, -0.2, 0.4)):
    """``n`` point masses on massless rods of 1 m, each hanging from the one before."""
    spec = {"world": lambda: parts.World()}
    links, prev = [], "world.frame"
    for k in range(n):
        spec[f"j{k}"] = lambda a=angles[k % len(angles)]: joints.Revolute(q=a, w=0.0)
        spec[f"rod{k}"] = lambda: parts.RigidTransform(ry=-1.0)
        spec[f"m{k}"] = lambda: parts.PointMass(m=1.0)
        links += [(prev, f"j{k}.frame_a"), (f"j{k}.frame_b", f"rod{k}.frame_a"),
                  (f"rod{k}.frame_b", f"m{k}.frame")]
        prev = f"m{k}.frame"
    return f"pendulum_chain_{n}", spec, links


def four_bar_spec(a=0.2, b=0.6, c=0.5, d=0.6, theta0=math.pi / 3):
    """The torque-driven four-bar of `mechanisms.four_bar`, as parts and links."""
    phi2, phi3 = four_bar_angles(theta0, a, b, c, d)
    spec = {
        "world": lambda: parts.World(),
        "ground_d": lambda: parts.Fixed(x0=d),
        "j1": lambda: joints.ActuatedRevolute(q=theta0, w=0.0),
        "j2": lambda: joints.Revolute(q=Start(phi2 - theta0, "low"), w=Start(0.0, "none")),
        "j3": lambda: joints.Revolute(q=Start(phi3 - phi2, "low"), w=Start(0.0, "none")),
        "j4": lambda: joints.Revolute(q=Start(-phi3, "low"), w=Start(0.0, "none")),
        "torque_cmd": lambda: blocks.Constant(value=1.0),
        "motor": lambda: rot.IdealTorqueSource(),
        "bearing": lambda: rot.RotationalDamper(D=0.1),
        "axis_ref": lambda: rot.RotationalReference(),
    }
    links = []
    for key, length in (("crank", a), ("coupler", b), ("rocker", c)):
        spec[key] = lambda length=length: parts.Rod(L=length)
        spec[f"{key}_body"] = lambda length=length: parts.Body(
            m=length, J=length ** 3 / 12, rcm_x=length / 2)
        links.append((f"{key}.frame_a", f"{key}_body.frame_a"))
    links += [("world.frame", "j1.frame_a"), ("j1.frame_b", "crank.frame_a"),
              ("crank.frame_b", "j2.frame_a"), ("j2.frame_b", "coupler.frame_a"),
              ("coupler.frame_b", "j3.frame_a"), ("j3.frame_b", "rocker.frame_a"),
              ("rocker.frame_b", "j4.frame_a"), ("j4.frame_b", "ground_d.frame"),
              ("torque_cmd.y", "motor.tau_in"), ("motor.A", "bearing.A", "j1.axis"),
              ("motor.B", "bearing.B", "axis_ref.port")]
    return "four_bar", spec, links


def geared_inertias_spec(ratio=3.0, J1=0.1, J2=0.5):
    """Two inertias rigidly coupled by an ideal gear, driven by a torque step."""
    spec = {
        "step": lambda: blocks.Step(t_step=0.0, final=2.0),
        "src": lambda: rot.IdealTorqueSource(),
        "inertia1": lambda: rot.Inertia(J=J1),
        "gear": lambda: rot.IdealGear(ratio=ratio),
        "inertia2": lambda: rot.Inertia(J=J2),
        "ref": lambda: rot.RotationalReference(),
    }
    links = [("step.y", "src.tau_in"), ("src.A", "inertia1.port", "gear.A"),
             ("gear.B", "inertia2.port"), ("src.B", "ref.port")]
    return "geared_inertias", spec, links


def capacitor_on_source_spec():
    """A capacitor directly across a voltage source (no state), beside an RC branch."""
    spec = {
        "sine": lambda: blocks.Sine(amplitude=2.0, f=50.0),
        "src": lambda: el.ControlledVoltageSource(),
        "c1": lambda: el.Capacitor(C=1e-3),
        "r": lambda: el.Resistor(R=10.0),
        "c2": lambda: el.Capacitor(C=1e-3),
        "gnd": lambda: el.ElectricalReference(),
    }
    links = [("sine.y", "src.u"), ("src.p", "c1.p", "r.p"), ("r.n", "c2.p"),
             ("src.n", "c1.n", "c2.n", "gnd.port")]
    return "capacitor_on_source", spec, links


MODELS = {
    # name: (spec, the states the rule gives)
    "double pendulum": (double_pendulum_spec(), ["j1.q", "j1.w", "j2.q", "j2.w"]),
    "four-bar": (four_bar_spec(), ["j1.q", "j1.w"]),
    "chain of four pendulums": (pendulum_chain_spec(4),
                                sorted(f"j{k}.{v}" for k in range(4) for v in "qw")),
    "geared inertias": (geared_inertias_spec(), ["inertia1.w"]),
    "capacitor on a source": (capacitor_on_source_spec(), ["c2.v"]),
}


def compile_spec(spec, order=None, rng=None):
    return mt.compile_model(assemble(*spec, order=order, rng=rng))


def c_source(cm) -> str:
    """The C code CasADi generates for the model's functions."""
    gen = ca.CodeGenerator("model.c", {"with_header": False})
    for f in (cm.f_ode, cm.f_alg, cm.f_out, cm.f_zero):
        gen.add(f)
    return gen.dump()


@pytest.fixture(scope="module")
def nominal():
    return {key: compile_spec(spec) for key, (spec, _) in MODELS.items()}


# ------------------------------------------------------------------------------ tests
@pytest.mark.parametrize("key", MODELS)
def test_the_rule_gives_these_states(key, nominal):
    assert sorted(nominal[key].state_names) == MODELS[key][1]


def perturb_the_pivoting(monkeypatch, transform):
    """Make the compiler pivot on ``transform(jacobian)``."""
    real = structure.pivot_columns

    def pivot(a, k, **options):
        return real(transform(np.asarray(a, dtype=float)), k, **options)

    monkeypatch.setattr(structure, "pivot_columns", pivot)


TRANSFORMS = {
    "ulps": lambda rng: lambda a: a + rng.integers(-4, 5, a.shape) * np.spacing(np.abs(a)),
    "scaled": lambda rng: lambda a: a * 10.0 ** rng.uniform(-5, 5),
    "rows shuffled": lambda rng: lambda a: a[rng.permutation(a.shape[0])],
}


@pytest.mark.parametrize("how", TRANSFORMS)
@pytest.mark.parametrize("key", MODELS)
def test_rounding_of_the_jacobian_changes_neither_states_nor_code(key, how, nominal,
                                                                   monkeypatch):
    spec, _ = MODELS[key]
    expected = c_source(nominal[key])
    for seed in range(3):
        perturb_the_pivoting(monkeypatch, TRANSFORMS[how](np.random.default_rng(seed)))
        cm = compile_spec(spec)
        assert cm.state_names == nominal[key].state_names
        assert c_source(cm) == expected


def nudge(x, n):
    """`x` moved by `n` units in the last place."""
    for _ in range(abs(n)):
        x = np.nextafter(x, math.copysign(math.inf, n))
    return float(x)


@pytest.mark.parametrize("seed", range(3))
def test_double_pendulum_numbers_moved_by_ulps_compile_the_same(seed, nominal):
    rng = np.random.default_rng(seed)
    n = [int(k) for k in rng.integers(-3, 4, size=6)]
    spec = double_pendulum_spec(l1=nudge(1.0, n[0]), l2=nudge(1.0, n[1]),
                                m1=nudge(1.0, n[2]), m2=nudge(1.0, n[3]),
                                alpha1=nudge(math.pi / 2, n[4]), alpha2=nudge(0.0, n[5]))
    cm = compile_spec(spec)
    assert cm.state_names == nominal["double pendulum"].state_names
    assert c_source(cm) == c_source(nominal["double pendulum"])


@pytest.mark.parametrize("scale", [1e-3, 0.37, 25.0])
def test_double_pendulum_of_another_size_keeps_the_joint_states(scale, nominal):
    # lengths and masses scaled together: the same mechanism in other units
    spec = double_pendulum_spec(l1=scale, l2=scale, m1=scale, m2=scale)
    cm = compile_spec(spec)
    assert cm.state_names == nominal["double pendulum"].state_names
    assert c_source(cm) == c_source(nominal["double pendulum"])


def test_symmetric_four_bar_keeps_the_crank():
    # a parallelogram (a = c, b = d) makes the coupler's and the rocker's columns equal
    spec = four_bar_spec(a=0.3, b=0.5, c=0.3, d=0.5, theta0=math.pi / 2.5)
    assert sorted(compile_spec(spec).state_names) == ["j1.q", "j1.w"]


def simulate_states(cm, t_stop):
    res = mt.simulate(cm, t_stop, rtol=1e-10, atol=1e-12,
                      t_out=np.linspace(0.0, t_stop, 11))
    return {n: res[n] for n in cm.state_names}


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize("key", MODELS)
def test_parts_added_in_another_order_select_the_same_states(key, seed, nominal):
    spec, _ = MODELS[key]
    rng = np.random.default_rng(seed)
    order = [str(k) for k in rng.permutation(list(spec[1]))]
    cm = compile_spec(spec, order=order, rng=rng)
    ref = nominal[key]
    assert sorted(cm.state_names) == sorted(ref.state_names)
    assert sorted(cm.report["differentiated_equations"]) == \
        sorted(ref.report["differentiated_equations"])
    # the same equations: the same trajectories of every state
    got, want = simulate_states(cm, 0.5), simulate_states(ref, 0.5)
    for name in ref.state_names:
        np.testing.assert_allclose(got[name], want[name], rtol=1e-8, atol=1e-10)


def test_an_exact_tie_goes_to_the_inertia_declared_first():
    # equal inertias on a 1:1 gear: nothing but the declaration order can choose
    spec = geared_inertias_spec(ratio=1.0, J1=0.2, J2=0.2)
    assert compile_spec(spec).state_names == ["inertia1.w"]
    order = ["step", "src", "inertia2", "gear", "inertia1", "ref"]
    assert compile_spec(spec, order=order).state_names == ["inertia2.w"]
