"""Hybrid semantics at the ends of a run and at its output times: the terminal event, an
event falling on an output time, and event-loop messages.

The event iteration itself is compiled into the model (see
:mod:`mechatron.compiler.events`); here Python runs once per simulation, never per event.
"""

from __future__ import annotations

import numpy as np

from mechatron.compiler.compiled import CompiledModel

__all__ = ["terminal_event", "events_on_outputs", "loop_message", "EVENT_TOL"]

#: Tolerance in time (s) to which the CasADi integrators locate an event; an output this
#: close to an event, scaled by the run's largest time above 1 s, is at the event.
EVENT_TOL = 1e-13


def terminal_event(cm: CompiledModel, t_end: float, Xf: np.ndarray, z: np.ndarray,
                   p: np.ndarray):
    """The event at the end of the run where ``terminal()`` is true: returns the state
    after its actions and every logged variable there."""
    X = np.array(Xf, dtype=float).copy()
    for k in cm.report.get("terminal_relations", []):
        X[cm.nx + k] = 1.0
    X = np.array(cm.f_transition(-1, t_end, X, z, p)[0], dtype=float).ravel()
    for k in cm.report.get("terminal_relations", []):
        X[cm.nx + k] = -1.0
    y = np.array(cm.f_out(t_end, X, z, p), dtype=float).ravel()
    return X, y


def events_on_outputs(cm: CompiledModel, grid: np.ndarray, X: np.ndarray, Z: np.ndarray,
                      p: np.ndarray) -> None:
    """Outputs at the time of an event show the state after it.

    An edge that falls on an output time (a pulse edge, a clock tick on the output grid)
    has its indicator exactly zero there: a CasADi integrator sees the crossing only in the
    next interval and logs the output before the event. Each such output (an event of
    the next interval located within ``EVENT_TOL`` of it) is replaced in ``X`` by the state
    the compiled transition gives there, as the compiled Rodas4 logs it (the first and
    last outputs are left as they are). ``p`` is the parameter vector, or one column per
    output time."""
    nx, nr = cm.nx, cm.nr
    if not nr or grid.size < 3:
        return
    counters, last = X[nx + nr:nx + 2 * nr], X[nx + 2 * nr:nx + 3 * nr]
    tol = EVENT_TOL * max(1.0, abs(float(grid[0])), abs(float(grid[-1])))
    on_output = (counters[:, 2:] > counters[:, 1:-1]) & (
        np.abs(last[:, 2:] - grid[1:-1]) <= tol)
    for k in np.flatnonzero(on_output.any(axis=0)) + 1:
        first = int(np.argmax(on_output[:, k - 1]))    # the others follow by iteration
        pk = p[:, k] if np.ndim(p) == 2 else p
        post = cm.f_transition(first, float(grid[k]), X[:, k], Z[:, k], pk)[0]
        X[:, k] = np.asarray(post, dtype=float).ravel()


def loop_message(cm: CompiledModel, looping: list[int], where: str) -> str:
    """The error of an event iteration without a fixed point, naming the conditions."""
    from mechatron.core.events import MAX_ROUNDS
    labels = cm.report.get("relation_labels") or [op for _, op in cm.relations]
    items = [f"'{cm.relations[k][0] or cm.name}': {labels[k]}" for k in looping]
    return (f"model '{cm.name}': event iteration {where} found no consistent state after "
            f"{MAX_ROUNDS} rounds; these conditions keep changing: {'; '.join(items[:6])}"
            f"{' ...' if len(items) > 6 else ''}. Each action makes another condition true "
            "again (a cycle of when actions, or relations not gated by the mode they "
            "switch): break the cycle, e.g. with pre() and a mode variable.")
