"""Transport delays (:class:`~mechatron.library.blocks.Delay`) in estimation.

A delay is a shift register of sampled states, a hybrid element that the smooth
discretization of :mod:`.discretize` does not take. When its input is a measured input
(a command that reaches the plant ``T`` later), the delay can be applied to the data
instead, exactly: each experiment's input samples are shifted by ``T / h`` samples of its
own grid ``h`` (the first ones take the registers' start value, 0), and the block becomes
``y = u`` in the model that is fitted. With a held input (``hold = "zoh"``) this is the
block's own behaviour on that grid; with ``hold = "linear"`` it is the continuous
transport delay of the interpolated input.

The conditions, checked on the model with and without its delays: the delay's input
depends on one measured input and nothing else (no state), and that input acts on the
model only through the delay. Anything else (a delay inside a feedback loop, on an
output, or ``T`` not a whole number of sample periods) is refused with a message.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

import mechatron as mt
from mechatron.errors import DataError, ModelError

__all__ = ["prepare_delays", "shift"]


def _delays(model) -> list:
    from mechatron.library.blocks.discrete import Delay
    out, stack = [], [model]
    while stack:
        c = stack.pop()
        if isinstance(c, Delay):
            out.append(c)
        stack.extend(c.components.values())
    return out


def prepare_delays(model, inputs: dict):
    """``(compiled model, {input label: delay T})``: the model with its input delays made
    ``y = u`` (see the module docstring); the model compiled as it is when it has no
    :class:`~mechatron.library.blocks.Delay`."""
    if isinstance(model, mt.CompiledModel):
        return model, {}
    delays = _delays(model)
    if not delays:
        return mt.compile_model(model), {}
    original = mt.compile_model(model)
    for d in delays:
        d.continuous = True
    try:
        cm = mt.compile_model(model)
    finally:
        for d in delays:
            d.continuous = False
    pindex = {n: i for i, n in enumerate(cm.param_names)}
    by_param = {path: lab for lab, path in inputs.items()}
    X = ca.SX.sym("X", cm.f_out.size1_in(1))
    z = ca.SX.sym("z", cm.f_out.size1_in(2))
    p = ca.SX.sym("p", cm.p0.size)
    out = cm.f_out(0.0, X, z, p)
    shifts = {}
    problems = []
    for d in delays:
        path = d.path
        where = f"Delay '{path}'"
        uname = f"{path}.u"
        if uname not in cm.names:
            problems.append(f"{where}: its input is not a logged variable of the model.")
            continue
        expr = out[cm.names.index(uname)]
        used = [k for k in range(cm.p0.size) if ca.depends_on(expr, p[k])]
        driven = [cm.param_names[k] for k in used if cm.param_names[k] in by_param]
        if ca.depends_on(expr, ca.vertcat(X, z)) or len(driven) != 1:
            problems.append(f"{where}: in estimation a delay must act on a measured input "
                            "(its input a function of one parameter driven by the data, "
                            "no state); it reads "
                            + (", ".join(cm.param_names[k] for k in used) or "no input")
                            + (" and the state" if ca.depends_on(expr, ca.vertcat(X, z))
                               else "") + ". A delay inside a loop or on an output needs the hybrid "
                              "simulation; shift the data by T, or move the delay to the "
                              "input.")
            continue
        if original.param_names != cm.param_names:
            problems.append(f"{where}: the parameters differ with the delay made "
                            "continuous; cannot check it.")
            continue
        k = pindex[driven[0]]
        if _acts_elsewhere(original, k):
            problems.append(f"{where}: the input '{by_param[driven[0]]}' ({driven[0]}) "
                            "also acts on the model without passing the delay; a delay of "
                            "the data would delay that path too. Drive the two paths from "
                            "different inputs.")
            continue
        lab = by_param[driven[0]]
        if lab in shifts:
            problems.append(f"{where}: input '{lab}' passes through two delays.")
            continue
        shifts[lab] = d.T
    if problems:
        raise ModelError(" ".join(problems), problems=problems, path=cm.name)
    return cm, shifts


def _acts_elsewhere(cm, k: int) -> bool:
    """Whether parameter ``k`` acts on the hybrid model ``cm`` other than through the
    registers of its delays: in a state derivative, or in a logged variable that also
    depends on the state (the signals upstream of a delay are functions of the
    parameters alone; a variable mixing ``k`` with the state is a second path)."""
    t = ca.SX.sym("t")
    X = ca.SX.sym("X", cm.f_ode.size1_in(1))
    z = ca.SX.sym("z", cm.f_ode.size1_in(2))
    p = ca.SX.sym("p", cm.p0.size)
    if ca.depends_on(cm.f_ode(t, X, z, p), p[k]):
        return True
    xz = ca.vertcat(X, z)
    return any(ca.depends_on(e, p[k]) and ca.depends_on(e, xz)
               for e in ca.vertsplit(cm.f_out(t, X, z, p)))


def shift(U: np.ndarray, t: np.ndarray, T: float, where: str) -> np.ndarray:
    """The input samples ``U`` (on the grid ``t``) delayed by ``T``: exact when ``T`` is a
    whole number of sample periods; the first samples take the value 0."""
    if T == 0:
        return U
    h = np.diff(t)
    n = T / float(np.median(h))
    if abs(n - round(n)) > 1e-6 * max(n, 1.0) or np.ptp(h) > 1e-6 * np.median(h):
        raise DataError(f"{where}: a delay of {T:g} s is not a whole number of sample "
                        f"periods ({float(np.median(h)):g} s, {n:.6g} of them) on an "
                        "even grid; a delay is exact on the sample grid only. Resample "
                        "the data or choose T as a multiple of the period.", path=where)
    n = int(round(n))
    out = np.zeros_like(U)
    out[..., n:] = U[..., :U.shape[-1] - n] if n < U.shape[-1] else 0.0
    return out
