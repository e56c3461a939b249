"""Hybrid semantics at the ends of a run: the terminal event and event-loop messages.

The event iteration itself is compiled into the model (see
:mod:`mechatron.compiler.events`); here Python runs once per simulation, never per event.
"""

from __future__ import annotations

import numpy as np

from mechatron.compiler.compiled import CompiledModel

__all__ = ["terminal_event", "loop_message"]


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
