"""Gears with losses: a gear with a support flange and efficiency, and a simple gear
defined by its teeth; the ideal planetary gear set."""

from mechatron.core import Component, Parameter, Variable, if_else
from mechatron.library.rotational.interfaces import Flange

__all__ = ["LossyGear", "SimpleGear", "IdealPlanetary"]


def mesh_torque(tau_a, tau_b, w_a, ratio, eta):
    """Residual of the lossy mesh: ``tau_b = -eta ratio tau_a`` while power enters at A
    (``tau_a w_a >= 0``), ``tau_b = -ratio tau_a / eta`` while it enters at B."""
    backward = tau_a * w_a < 0
    return if_else(backward, eta * tau_b + ratio * tau_a, tau_b + eta * ratio * tau_a)


class LossyGear(Component):
    """Gear with a speed ratio, an efficiency that depends on the direction of power flow,
    and a support (housing) flange ``S``.

    Equations, with speeds relative to the support, ``w_A = A.w - S.w``,
    ``w_B = B.w - S.w``::

        w_A = ratio w_B
        B.tau = -eta ratio A.tau        while A.tau w_A >= 0 (power enters at A)
        B.tau = -ratio A.tau / eta      while A.tau w_A < 0  (power enters at B)
        A.tau + B.tau + S.tau = 0       (torque balance; the support takes the reaction)
        P_loss = A.tau w_A + B.tau w_B  (= (1 - eta) |P| or (1/eta - 1) |P|, >= 0)

    The switch of direction is an event. Limitation: no stuck mode at zero speed (the
    driving torque there is transmitted with the forward relation); with ``eta = 1`` it is
    :class:`IdealGear` with a support.
    """

    A = Flange(doc="Input flange")
    B = Flange(doc="Output flange")
    S = Flange(doc="Support (housing) flange")
    ratio = Parameter("1", default=2.0, doc="Speed ratio w_A / w_B")
    eta = Parameter("1", default=0.9, min=0, max=1, doc="Efficiency of the mesh")
    P_loss = Variable("W", doc="Power dissipated in the mesh")

    def equations(self):
        w_a = self.A.w - self.S.w
        w_b = self.B.w - self.S.w
        return [w_a == self.ratio * w_b,
                mesh_torque(self.A.tau, self.B.tau, w_a, self.ratio, self.eta) == 0,
                self.A.tau + self.B.tau + self.S.tau == 0,
                self.P_loss == self.A.tau * w_a + self.B.tau * w_b]


class SimpleGear(Component):
    """External spur-gear pair with a grounded carrier (Simscape's Simple Gear).

    The follower ``B`` turns opposite to the base ``A``: ``N_A A.w = -N_B B.w``, i.e. the
    speed ratio is ``A.w / B.w = -N_B / N_A``. Torques as in :class:`LossyGear` with this
    ratio::

        B.tau = -eta r A.tau  (power enters at A),  B.tau = -r A.tau / eta  (at B),
        r = -N_B / N_A,       P_loss = A.tau A.w + B.tau B.w >= 0
    """

    A = Flange(doc="Base gear flange")
    B = Flange(doc="Follower gear flange")
    N_A = Parameter("1", default=20, min=1, doc="Teeth of the base gear")
    N_B = Parameter("1", default=40, min=1, doc="Teeth of the follower gear")
    eta = Parameter("1", default=0.95, min=0, max=1, doc="Efficiency of the mesh")
    P_loss = Variable("W", doc="Power dissipated in the mesh")

    def equations(self):
        r = -self.N_B / self.N_A
        return [self.N_A * self.A.w == -self.N_B * self.B.w,
                mesh_torque(self.A.tau, self.B.tau, self.A.w, r, self.eta) == 0,
                self.P_loss == self.A.tau * self.A.w + self.B.tau * self.B.w]


class IdealPlanetary(Component):
    """Ideal planetary gear set without losses (MSL's ``IdealPlanetary``): sun, carrier
    and ring, with ``ratio = z_ring / z_sun`` (number of ring teeth over sun teeth).

    Equations (Willis' relation and the torque balance of a massless, lossless set)::

        (1 + ratio) carrier.w == sun.w + ratio ring.w
        ring.tau == ratio sun.tau
        carrier.tau == -(1 + ratio) sun.tau

    so ``sun.tau sun.w + ring.tau ring.w + carrier.tau carrier.w == 0`` (no power lost).
    With the ring held, ``sun.w / carrier.w = 1 + ratio``. The set has no support: the
    three shafts may all move (the housing reaction is that of whatever holds them).
    """

    sun = Flange(doc="Sun gear flange")
    carrier = Flange(doc="Carrier flange")
    ring = Flange(doc="Ring gear flange")
    ratio = Parameter("1", default=100 / 50, min=0,
                      doc="Number of ring teeth over number of sun teeth")

    def equations(self):
        return [(1 + self.ratio) * self.carrier.w == self.sun.w + self.ratio * self.ring.w,
                self.ring.tau == self.ratio * self.sun.tau,
                self.carrier.tau == -(1 + self.ratio) * self.sun.tau]
