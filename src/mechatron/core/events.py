"""Discrete events of the language (Modelica 3 semantics, in Python).

A component returns, beside its equations, *event actions* from ``equations()``:

``sample(clock, output=..., update=...)``
    At every tick of ``clock`` (``t_k = offset + k * period``, ``k = 0, 1, ...``) first the
    ``output`` assignments of every block sampled at ``t_k`` are made, in the order of
    their dependencies (a block reads the *new* outputs of the blocks upstream, as in
    Simulink's output phase); then all ``update`` assignments are made at once from the
    values after the output phase (the state update of a difference equation: on the
    right-hand side a variable updated here has its value *before* the tick).
``when(condition, update=...).elsewhen(condition, update=...)``
    When ``condition`` becomes true, the ``update`` assignments are made at once (their
    right-hand sides read the values before the assignments, like a Modelica algorithm in
    a when-clause: ``n := n + 1`` and ``n := pre(n) + 1`` are the same). A condition is a
    relation (``u >= u_on``, located by the solver as any event), a Boolean expression of
    relations and discrete variables (``mt.logic_and(x > 1, self.armed)``), ``initial()``,
    ``terminal()``, ``sample(start, interval)``, or a list of these (the action runs when
    any of them becomes true). ``elsewhen`` branches run only if no earlier branch of the
    same ``when`` fires at that instant.

Event iteration: at an event every relation is re-read, the actions whose conditions
became true run, and this repeats until no relation, condition or discrete variable
changes (a ``when`` whose condition is made true by another action fires at the same
instant). More than :data:`MAX_ROUNDS` rounds is an error naming the conditions that keep
changing.

A variable assigned by an action and not differentiated anywhere is a *discrete state*:
the compiler adds ``der(v) == 0``, so it is constant between events and changed only by
actions (declare it with :class:`~mechatron.core.declarations.Discrete` to make it an
integer or a Boolean). A continuous state may be re-initialized: ``reinit(x, value)``
(or the pair ``{x: value}``).

Actions run in native code inside the integrator's transition function (variable step)
or at the end of the step (fixed step), never in Python per event.
"""

from __future__ import annotations

import casadi as ca

from mechatron.errors import ModelError

__all__ = ["Clock", "EventAction", "When", "SampleCondition", "Reinit", "sample", "when",
           "reinit", "pre", "initial", "terminal", "steady_state", "MAX_ROUNDS"]

#: Largest number of event-iteration rounds at one instant.
MAX_ROUNDS = 100


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
        if isinstance(item, Reinit):
            out.append(item)
            continue
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


def sample(clock, interval=None, *, output=None, update=None):
    """Assignments made at each tick of ``clock`` (see the module docstring), or, as
    ``sample(start, interval)``, the condition that is true at ``start + k * interval``
    (for :func:`when`, Modelica's ``sample``).

    ``output`` assignments see the new outputs of upstream blocks sampled at the same
    tick; ``update`` assignments are simultaneous and see the values after the outputs.
    """
    if interval is not None:
        if output is not None or update is not None or isinstance(clock, Clock):
            raise ModelError("sample(start, interval) is a condition for mt.when; for "
                             "assignments at the ticks of a clock write "
                             "mt.sample(mt.Clock(period, offset), update={...}).")
        return SampleCondition(clock, interval)
    if not isinstance(clock, Clock):
        raise ModelError(f"sample: expected a Clock, got {clock!r}. Write "
                         "mt.sample(mt.Clock(period, offset), update={...}).")
    return EventAction(clock, _pairs(output, "sample(output=...)"),
                       _pairs(update, "sample(update=...)"))


class Reinit(tuple):
    """``reinit(x, value)``: a continuous state set to ``value`` by an action (a pair
    ``(x, value)`` that the compiler checks is a differentiated variable)."""

    __slots__ = ()

    def __new__(cls, var, expr):
        return super().__new__(cls, (ca.SX(var), ca.SX(expr)))


def reinit(x, value) -> Reinit:
    """Re-initialize the continuous state ``x`` to ``value`` in a ``when`` action:
    ``mt.when(self.h <= 0, update=[mt.reinit(self.v, -self.e * mt.pre(self.v))])``."""
    return Reinit(x, value)


class SampleCondition:
    """The condition ``sample(start, interval)``: true at ``start + k * interval``.

    Its ticks are computed from their index (no drift) and are events of their own; a
    tick that falls on another event (within 1e-9 of the interval) is the same instant.
    """

    __slots__ = ("clock",)

    def __init__(self, start, interval):
        self.clock = Clock(interval, start)

    def __repr__(self) -> str:
        return f"sample({self.clock.offset}, {self.clock.period})"


def _context():
    from mechatron.core.context import current
    return current()


def pre(x) -> ca.SX:
    """The value of ``x`` before the current event (Modelica's ``pre``).

    In an action's right-hand side every variable is read before the assignments, so
    ``pre(x)`` states that explicitly; in an ``output`` assignment of ``sample`` it reads
    ``x`` before the tick instead of the new output of an upstream block. In equations and
    conditions ``pre(x)`` equals ``x`` (they differ only inside the event iteration).
    """
    x = ca.SX(x)
    if not (x.is_scalar() and x.is_symbolic()):
        raise ModelError(f"pre: expected a variable, got {str(x)[:60]}. Write "
                         "mt.pre(self.x) for a variable x of the component.")
    ctx = _context()
    if x.name() not in ctx.unknowns:
        return x            # a parameter or time: constant across an event
    return ctx.pre_symbol(x.name())


def initial() -> ca.SX:
    """The condition that holds during the initialization event at ``t0`` only:
    ``mt.when(mt.initial(), update={...})`` runs once, at the start."""
    return _context().special_symbol("initial")


def terminal() -> ca.SX:
    """The condition that holds at the end of the simulation only: the actions of
    ``mt.when(mt.terminal(), update={...})`` run at ``t_stop`` and show in the last
    logged point."""
    return _context().special_symbol("terminal")


def steady_state(*variables) -> list:
    """Initial equations ``der(v) == 0`` for each of ``variables`` (Modelica's
    initType=SteadyState), for ``initial_equations()``."""
    from mechatron.core.context import der
    return [der(v) == 0 for v in variables]


def _condition(cond, what: str):
    """A condition: a SampleCondition, or a scalar SX of relations / Booleans."""
    if isinstance(cond, SampleCondition):
        return cond
    if isinstance(cond, (bool, int, float)) or cond is None:
        raise ModelError(f"{what}: the condition must be one relation such as u >= u_on, a "
                         "Boolean expression of relations and discrete variables, "
                         f"mt.initial(), mt.terminal() or mt.sample(start, interval); got "
                         f"{cond!r}.")
    try:
        c = ca.SX(cond)
    except (NotImplementedError, TypeError, RuntimeError):
        raise ModelError(f"{what}: the condition must be one relation such as u >= u_on "
                         f"or a Boolean expression, got {cond!r}.") from None
    if not c.is_scalar() or c.is_constant():
        raise ModelError(f"{what}: the condition must be one relation such as u >= u_on "
                         f"or a scalar Boolean expression, got {str(c)[:60]}.")
    return c


class When(EventAction):
    """A ``when`` action with its ``elsewhen`` branches (built by :func:`when`).

    ``branches`` is a list of ``(conditions, updates)``: the conditions of a branch (any
    one becoming true fires it) and its assignments (pairs, or :class:`Reinit`).
    """

    __slots__ = ("branches",)

    def __init__(self, conditions, updates):
        super().__init__(conditions[0], [], updates)
        self.branches = [(conditions, updates)]

    def elsewhen(self, condition, *, update=None) -> "When":
        """Add a branch that fires when ``condition`` becomes true and no earlier branch
        fires at the same instant; returns the same action (chainable)."""
        self.branches.append((_conditions(condition, "elsewhen"),
                              _pairs(update, "elsewhen(update=...)")))
        # every assigned variable, for the flattener's discrete-state check
        self.updates = [pair for _, ups in self.branches for pair in ups]
        return self

    def __repr__(self) -> str:
        return (f"<when: {len(self.branches)} branch(es), {len(self.updates)} "
                "assignment(s)>")


def _conditions(condition, what):
    items = condition if isinstance(condition, (list, tuple)) else [condition]
    if not items:
        raise ModelError(f"{what}: expected at least one condition.")
    return [_condition(c, what) for c in items]


def when(condition, *, update=None) -> When:
    """Assignments made when ``condition`` becomes true (see the module docstring).

    ``condition`` is a relation, a Boolean expression, ``initial()``, ``terminal()``,
    ``sample(start, interval)`` or a list of these (fires when any becomes true). The
    assignments are simultaneous (right-hand sides before the event round). Chain
    ``.elsewhen(condition, update=...)`` for branches of lower priority.
    """
    return When(_conditions(condition, "when"), _pairs(update, "when(update=...)"))
