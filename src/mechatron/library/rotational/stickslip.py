"""Stuck/sliding mode logic shared by the friction elements of both mechanical domains
(internal helper, not a component): Modelica's ``PartialFriction`` written with
discrete variables and ``when`` actions.

The element has a relative speed ``w``, its derivative ``a`` and a friction torque (or
force) ``tau`` entering at A. A discrete ``mode`` says which equation holds:

- ``mode = 1``, sliding forward: ``tau = tau_fwd(w) >= 0``; it locks when ``w`` falls
  below ``w_lock``.
- ``mode = 0``, stuck: ``a = 0`` and ``tau`` is the unknown that holds it; it breaks away
  forward when ``tau > brk_fwd``, backward when ``tau < -brk_bwd``.
- ``mode = -1``, sliding backward: ``tau = tau_bwd(w) <= 0``; it locks when ``w`` rises
  above ``w_lock``.

Both are one equation, ``0 = if stuck: scale * a, else tau - tau_kinetic``, so the
structure does not change with the mode; ``scale`` (an inertia or a mass) only makes the
two branches of one dimension. From forward or backward sliding the element goes to
stuck when the speed crosses zero; in the same event instant (event iteration) it breaks
away again in the other direction if the torque needed to stay stuck exceeds the static
limit there (a clutch whose drive reverses slides on backwards).

``w_lock`` is the speed at the last lock or break-away (zero up to the event location
error, ~1e-14): measuring the slip from it makes a break-away start exactly on the
switching surface, where the direction of motion decides (no spurious re-lock from a
residual speed of the wrong sign, left by event location or by rounding while stuck).
Every relation is gated by the mode it belongs to, so a stuck element generates no
events and a sliding one only the crossing that matters: one event per lock and one per
break-away.

Limitation: the fixed-step solvers read relations by their sign at the step ends; a
speed that crosses zero within a step locks at the step end with the overshoot as
``w_lock``.
"""

from __future__ import annotations

from mechatron.core import if_else, logic_and, logic_not, when

__all__ = ["stick_slip", "initial_mode"]

FORWARD, STUCK, BACKWARD = 1, 0, -1


def stick_slip(mode, w, w_lock, a, tau, scale, tau_fwd, tau_bwd, brk_fwd, brk_bwd=None, *,
               blocked_fwd=None, blocked_bwd=None):
    """Equation and actions of a stuck/sliding friction element.

    Parameters
    ----------
    mode, w_lock : symbol
        The element's discrete mode (integer, -1/0/1) and the speed at the last lock.
    w, a, tau : symbol
        Relative speed, its time derivative, friction torque (or force) entering at A.
    scale : expression
        Inertia (or mass) that makes ``scale * a`` a torque (or force); any positive value.
    tau_fwd, tau_bwd : expression
        Kinetic torque while sliding forward (>= 0) and backward (<= 0).
    brk_fwd, brk_bwd : expression
        Static limits (>= 0): the stuck torque breaks away forward above ``brk_fwd``,
        backward below ``-brk_bwd``. ``brk_bwd=None``: never backward (a freewheel).
    blocked_fwd, blocked_bwd : expression, optional
        Conditions (of discrete variables) under which the stuck element cannot break
        away in that direction at all (a mass resting against an end stop).
    """
    stuck = mode == STUCK
    kinetic = if_else(mode == FORWARD, tau_fwd, tau_bwd)
    # the torque that keeps it stuck, where a break-away that way is possible
    can_fwd = stuck if blocked_fwd is None else logic_and(stuck, logic_not(blocked_fwd))
    can_bwd = stuck if blocked_bwd is None else logic_and(stuck, logic_not(blocked_bwd))
    # outside their mode the distances are constants of the sign that keeps each
    # relation false (-1 below brk_fwd >= 0, ...): no events, and no mode left on its
    # switching surface to be re-read differently at another component's event
    held_fwd = if_else(can_fwd, tau, -1.0)
    held_bwd = if_else(can_bwd, tau, 1.0)
    slip_fwd = if_else(mode == FORWARD, w - w_lock, 1.0)
    slip_bwd = if_else(mode == BACKWARD, w - w_lock, -1.0)
    out = [0 == if_else(stuck, scale * a, tau - kinetic),
           when(logic_and(can_fwd, held_fwd > brk_fwd), update={mode: FORWARD, w_lock: w}),
           when(logic_and(mode == FORWARD, slip_fwd < 0), update={mode: STUCK, w_lock: w})]
    if brk_bwd is not None:
        out += [when(logic_and(can_bwd, held_bwd < -brk_bwd),
                     update={mode: BACKWARD, w_lock: w}),
                when(logic_and(mode == BACKWARD, slip_bwd > 0),
                     update={mode: STUCK, w_lock: w})]
    return out


def initial_mode(mode, w, backward=True):
    """Initial equation: forward if ``w > 0``, backward if ``w < 0`` (``backward``), else
    stuck (a stuck element whose torque exceeds its limit breaks away at the start)."""
    neg = BACKWARD if backward else STUCK
    return mode == if_else(w > 0, FORWARD, if_else(w < 0, neg, STUCK))
