"""Penalty contact law shared by the hard stops and the backlash of both mechanical
domains (internal helper, not a component)."""

from mechatron.core import if_else

__all__ = ["penalty_force"]


def penalty_force(penetration, rate, k, d):
    """Compressive contact force of a spring-damper that only pushes.

    ``F = max(k*penetration + d*rate, 0)`` while ``penetration > 0``, else 0. Both
    switches are relations, so the solver locates contact, release and the instant the
    damper would start to pull (where ``F`` reaches 0 before the penetration does) as
    events. The force is continuous at each of them.
    """
    force = k * penetration + d * rate
    return if_else(penetration > 0, if_else(force > 0, force, 0), 0)
