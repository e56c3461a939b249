"""The native build of the estimation's step functions and its size guard."""

import shutil

import casadi as ca
import numpy as np
import pytest

import mechatron.estimation.native as nat


def _chain(n: int) -> ca.Function:
    """x -> n rounds of x = sin(x) * 0.5 + x * x * 1e-3: about 4 n SX instructions."""
    x = ca.SX.sym("x", 2)
    y = x
    for _ in range(n):
        y = ca.sin(y) * 0.5 + y * y * 1e-3
    return ca.Function("chain", [x], [y])


def _reference(n: int, x):
    y = np.asarray(x, dtype=float)
    for _ in range(n):
        y = np.sin(y) * 0.5 + y * y * 1e-3
    return y


def test_estimation_builds_its_c_code_for_over_60_s(monkeypatch, caplog):
    """A step function with many substeps unrolled (the fuzz case: ``substeps`` large in
    a problem file, jit "auto") is not handed to the C compiler when its build is
    estimated above the limit: it runs interpreted, with the same results, and a
    warning says why."""
    fn = _chain(60_000)                      # ~240,000 instructions: ~5 MB of C
    size, seconds = nat.build_estimate(fn)
    assert size > 4e6 and seconds > 60
    calls = []
    monkeypatch.setattr(nat, "compiler", lambda: "cc")
    monkeypatch.setattr(nat, "build_library", lambda *a, **k: calls.append(a) or 1 / 0)
    monkeypatch.delenv("MECHATRON_JIT_MAX_BUILD_S", raising=False)
    with caplog.at_level("WARNING", logger="mechatron.estimation.native"):
        out = nat.native(fn)
    assert out is fn and calls == []
    assert "runs interpreted" in caplog.text and "MECHATRON_JIT_MAX_BUILD_S" in caplog.text
    x = [0.3, -1.2]
    np.testing.assert_allclose(np.asarray(out(x)).ravel(), _reference(60_000, x),
                               rtol=1e-12, atol=1e-15)


def test_the_build_limit_can_be_lifted(monkeypatch):
    fn = _chain(60_000)
    calls = []

    def build(*args, **kwargs):
        calls.append(args)
        raise nat.BuildError("not built in this test")
    monkeypatch.setattr(nat, "compiler", lambda: "cc")
    monkeypatch.setattr(nat, "build_library", build)
    monkeypatch.setenv("MECHATRON_JIT_MAX_BUILD_S", "0")
    assert nat.native(fn) is fn and len(calls) == 1     # tried; failure falls back


def test_the_estimate_follows_the_generated_c():
    """The size estimate against the C CasADi generates, within a factor of 2."""
    for n in (100, 2000):
        fn = _chain(n)
        cg = ca.CodeGenerator("chain.c", {"with_header": False})
        cg.add(fn)
        size, _ = nat.build_estimate(fn)
        assert 0.5 < size / len(cg.dump()) < 2.0


@pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None,
                    reason="no C compiler")
def test_a_small_function_is_still_compiled(tmp_path, monkeypatch):
    monkeypatch.setenv("MECHATRON_CACHE", str(tmp_path))
    fn = _chain(50)
    out = nat.native(fn)
    assert out is not fn and out.class_name() != fn.class_name()
    x = [0.7, 0.1]
    np.testing.assert_allclose(np.asarray(out(x)).ravel(), _reference(50, x), rtol=1e-12)
