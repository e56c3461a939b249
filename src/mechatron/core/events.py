"""Discrete events of the language: sample clocks and ``when`` conditions.

A component returns, beside its equations, *event actions* from ``equations()``:

``sample(clock, output=..., update=...)``
    At every tick of ``clock`` (``t_k = offset + k * period``, ``k = 0, 1, ...``) first the
    ``output`` assignments of every block sampled at ``t_k`` are made, in the order of
    their dependencies (a block reads the *new* outputs of the blocks upstream, as in
    Simulink's output phase); then all ``update`` assignments are made at once from the
    values after the output phase (the state update of a difference equation: on the
    right-hand side a variable updated here has its value *before* the tick).
``when(condition, update=...)``
    When ``condition`` (a relation such as ``u >= u_on``) becomes true (its distance
    crosses zero upwards, located by the solver as any event), the ``update`` assignments
    are made at once (re-initialization, mode memory of a relay).

A variable assigned by an action and not differentiated anywhere is a *discrete state*:
the compiler adds ``der(v) == 0``, so it is constant between events and changed only by
actions. A continuous state (a variable whose ``der`` appears) may be re-initialized by an
action. Assignments are written as ``{self.x: expr}`` or ``[(self.x, expr), ...]``.

Actions run in native code inside the integrator's transition function (variable step)
or at the end of the step (fixed step), never in Python per event.
"""

from __future__ import annotations

import casadi as ca

from mechatron.errors import ModelError

__all__ = ["Clock", "EventAction", "sample", "when"]


class Clock:
    """A periodic sample clock: ticks at ``offset + k * period``, ``k = 0, 1, 2, ...``.

    Parameters
    ----------
    period : float or expression of parameters
        Sample time in s (> 0).
    offset : float or expression of parameters
        Time of the first tick in s (Simulink's sample-time offset), ``0 <= offset``.
    """

    __slots__ = ("period", "offset")

    def __init__(self, period, offset=0.0):
        self.period = ca.SX(period)
        self.offset = ca.SX(offset)

    def __repr__(self) -> str:
        return f"Clock(period={self.period}, offset={self.offset})"


def _pairs(assign, what: str) -> list[tuple[ca.SX, ca.SX]]:
    if assign is None:
        return []
    items = assign.items() if isinstance(assign, dict) else assign
    out = []
    for item in items:
        try:
            var, expr = item
        except (TypeError, ValueError):
            raise ModelError(f"{what}: expected pairs (variable, expression), got "
                             f"{item!r}.") from None
        out.append((ca.SX(var), ca.SX(expr)))
    return out


class EventAction:
    """Assignments made at the ticks of a clock or when a condition becomes true.

    Built by :func:`sample` and :func:`when`; the compiler reads ``trigger`` (a
    :class:`Clock` or a relation), ``outputs`` and ``updates`` (pairs of a variable
    symbol and an expression).
    """

    __slots__ = ("trigger", "outputs", "updates")

    def __init__(self, trigger, outputs, updates):
        self.trigger = trigger
        self.outputs = outputs
        self.updates = updates

    def __repr__(self) -> str:
        kind = "sample" if isinstance(self.trigger, Clock) else "when"
        return (f"<{kind}: {len(self.outputs)} output(s), {len(self.updates)} "
                f"update(s)>")


def sample(clock: Clock, *, output=None, update=None) -> EventAction:
    """Assignments made at each tick of ``clock`` (see the module docstring).

    ``output`` assignments see the new outputs of upstream blocks sampled at the same
    tick; ``update`` assignments are simultaneous and see the values after the outputs.
    """
    if not isinstance(clock, Clock):
        raise ModelError(f"sample: expected a Clock, got {clock!r}. Write "
                         "mt.sample(mt.Clock(period, offset), update={...}).")
    return EventAction(clock, _pairs(output, "sample(output=...)"),
                       _pairs(update, "sample(update=...)"))


def when(condition, *, update=None) -> EventAction:
    """Assignments made when ``condition`` (one relation: ``<``, ``<=``, ``>``, ``>=``)
    becomes true. The assignments are simultaneous (right-hand sides before the event)."""
    cond = ca.SX(condition)
    if not (cond.is_scalar() and (cond.is_op(ca.OP_LT) or cond.is_op(ca.OP_LE))):
        raise ModelError(f"when: the condition must be one relation such as u >= u_on, "
                         f"got {str(cond)[:60]}.")
    return EventAction(cond, [], _pairs(update, "when(update=...)"))
