"""Linearization and trim against analytic results: the DC motor's voltage-to-speed
transfer function, the double pendulum's small-oscillation frequencies, a DAE whose
algebraic variable is eliminated, the steady state that trim finds."""

import subprocess
import sys

import numpy as np
import pytest

import mechatron as mt
from mechatron.errors import SimulationError

R, L, K, J, B = 7.1, 3.408e-4, 0.151, 4.8e-6, 1.236e-4
MOTOR = mt.models.get("dc_motor")


def motor_tf(s):
    return K / ((L * s + R) * (J * s + B) + K * K)


@pytest.mark.parametrize("variant,inp,out", [("acausal", "source.V", "inertia.w"),
                                            ("ode", "V", "w"), ("blocks", "supply.value",
                                                                "speed.y")])
def test_the_dc_motor_speed_over_voltage_is_the_analytic_transfer_function(variant, inp, out):
    sys_ = mt.linearize(MOTOR.build(variant), inputs=[inp], outputs=[out])
    for w in np.logspace(0, 6, 13):
        assert complex(sys_(1j * w)) == pytest.approx(motor_tf(1j * w), rel=1e-9)
    assert sys_.input_paths == [inp] and sys_.output_paths == [out]


def test_the_double_pendulum_oscillates_at_its_analytic_frequencies():
    m1, m2, l1, l2, g = 1.0, 2.0, 1.0, 0.5, 9.81
    M = np.array([[(m1 + m2) * l1 ** 2, m2 * l1 * l2], [m2 * l1 * l2, m2 * l2 ** 2]])
    Kmat = np.diag([(m1 + m2) * g * l1, m2 * g * l2])
    omega = np.sqrt(np.sort(np.linalg.eigvals(np.linalg.solve(M, Kmat)).real))
    entry = mt.models.get("double_pendulum")
    for variant in entry.variants:
        model = entry.build(variant, m1=m1, m2=m2, l1=l1, l2=l2, alpha1_0=0.0, alpha2_0=0.0)
        A, *_ = mt.analysis.linear_matrices(model)
        ev = np.linalg.eigvals(A)
        assert np.max(np.abs(ev.real)) < 1e-9 * np.max(np.abs(ev))     # undamped
        assert np.sort(np.abs(ev.imag))[::2] == pytest.approx(omega, rel=1e-9), variant


def test_an_algebraic_variable_is_eliminated_exactly():
    class Loop(mt.Component):
        """x' = -x + z, 0 = z^3 + z - u: at u = 2, z = 1; dz/du = 1/(3z^2 + 1)."""
        u = mt.Parameter("1", default=2.0, doc="Input")
        x = mt.Variable("1", start=1.0, doc="State")
        z = mt.Variable("1", start=0.5, doc="Algebraic")

        def equations(self):
            return [mt.der(self.x) == -self.x + self.z, self.z ** 3 + self.z == self.u]

    A, Bm, C, D, op = mt.analysis.linear_matrices(Loop(), inputs=["u"], outputs=["z", "x"])
    assert op.values["z"] == pytest.approx(1.0, rel=1e-10)
    assert A[0, 0] == pytest.approx(-1.0) and Bm[0, 0] == pytest.approx(0.25, rel=1e-12)
    assert C[:, 0] == pytest.approx([0.0, 1.0]) and D[:, 0] == pytest.approx([0.25, 0.0])


def test_trim_finds_the_voltage_for_a_speed_and_linearizes_there():
    op = mt.trim(MOTOR.build("acausal"), targets={"inertia.w": 100.0}, free=["source.V"])
    V = 100.0 * (R * B + K * K) / K
    cm = mt.compile_model(MOTOR.build("acausal"))
    assert op.p[cm.param_names.index("source.V")] == pytest.approx(V, rel=1e-12)
    assert op["inductor.i"] == pytest.approx(B * 100.0 / K, rel=1e-12)
    A, Bm, *_ = mt.analysis.linear_matrices(cm, op, inputs=["source.V"])
    # at rest: A x + B u is the (zero) derivative for this linear model
    u = op.p[cm.param_names.index("source.V")]
    assert np.max(np.abs(A @ op.x[:2] + Bm[:, 0] * u)) < 1e-6 * np.max(np.abs(A @ op.x[:2]))


def test_linearizing_at_a_time_uses_the_state_reached_then():
    model = MOTOR.build("acausal")
    op = mt.analysis.linear.operating_point(model, 0.05)
    res = mt.simulate(MOTOR.build("acausal"), 0.05)
    assert op["inertia.w"] == pytest.approx(res.final("inertia.w"), rel=1e-12)


def test_bad_requests_are_named():
    with pytest.raises(SimulationError, match=r"cannot use source\.U as input.*did you mean "
                                              r"source\.V"):
        mt.linearize(MOTOR.build("acausal"), inputs=["source.U"])
    with pytest.raises(SimulationError, match=r"one free input per target"):
        mt.trim(MOTOR.build("acausal"), targets={"inertia.w": 1.0})

    class Square(mt.Component):
        u = mt.Parameter("1", default=1.0, doc="Input")
        x = mt.Variable("1", start=1.0, doc="State")
        y = mt.Variable("1", doc="Output, never negative")

        def equations(self):
            return [mt.der(self.x) == self.u - self.x, self.y == self.x ** 2]

    with pytest.raises(SimulationError, match=r"trim did not converge.*largest residual"):
        mt.trim(Square(), targets={"y": -1.0}, free=["u"])


def test_the_command_line_prints_the_matrices_and_draws_a_bode_plot(tmp_path):
    out = tmp_path / "bode.png"
    run = subprocess.run([sys.executable, "-m", "mechatron", "linearize", "dc_motor",
                          "--input", "source.V", "--output", "inertia.w", "--trim",
                          "inertia.w=100", "--free", "source.V", "--bode", str(out),
                          "--json"], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    import json
    doc = json.loads(run.stdout)
    assert doc["dc_gain"][0][0] == pytest.approx(motor_tf(0.0), rel=1e-9)
    assert doc["operating_point"]["inputs"]["source.V"] == pytest.approx(
        100.0 * (R * B + K * K) / K, rel=1e-9)
    assert out.stat().st_size > 10_000


def test_linearizing_a_hybrid_model_at_a_time_is_refused_not_guessed():
    class Switched(mt.Component):
        x = mt.Variable("1", start=0.0, doc="Rises, then holds")

        def equations(self):
            return [mt.der(self.x) == mt.if_else(self.x < 1.0, 1.0, 0.0)]

    with pytest.raises(SimulationError, match=r"linearizing at a time needs the event "
                                              r"modes"):
        mt.linearize(Switched(), at=2.0)
    A, *_ = mt.analysis.linear_matrices(Switched(), at={"x": 0.5})
    assert A.shape == (1, 1)
