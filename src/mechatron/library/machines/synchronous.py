"""Permanent-magnet synchronous machines (Modelica's
``Electrical.Machines.BasicMachines.SynchronousMachines.SM_PermanentMagnet`` without damper
cage; Simscape's ``PMSM`` and ``BLDC``)."""

from __future__ import annotations

import math

import casadi as ca

from mechatron.core import Component, Parameter, Variable, connect, der
from mechatron.library import rotational as rot
from mechatron.library.electrical.interfaces import Pin
from mechatron.library.machines.interfaces import MachineOptions, thermal_variant
from mechatron.library.rotational.interfaces import Flange, TwoFlange

__all__ = ["trapezoid", "AirGapPMSM", "AirGapTrapezoidal", "PMSM", "TrapezoidalPMSM",
           "PMSMWithHeatPort", "TrapezoidalPMSMWithHeatPort"]

TWO_PI_3 = 2 * math.pi / 3
_W_NOM = 2 * math.pi * 50.0          # MSL's fsNominal = 50 Hz, as an angular frequency


def trapezoid(x):
    """Unit trapezoidal back-EMF shape of electrical angle ``x``: 0 at ``x = 0``, rising
    linearly to 1 at 30 degrees, flat up to 150 degrees, falling to -1 at 210 degrees, flat
    to 330 degrees, periodic in 2 pi (the flat-topped ``sin x``).

    Written as a clipped triangle wave, ``clip(g(x) / (pi/6), -1, 1)`` with
    ``g(x) = pi/2 - |m - pi/2|`` and ``m = x + pi/2 mod 2 pi - pi/2`` (``g`` is
    ``asin(sin x)``, without the infinite slope of ``asin`` at the peaks, which would make
    the Jacobian NaN there). Works for numbers and CasADi expressions.
    """
    if isinstance(x, (int, float)):
        m = (x + math.pi / 2) % (2 * math.pi) - math.pi / 2
        return max(-1.0, min(1.0, (math.pi / 2 - abs(m - math.pi / 2)) / (math.pi / 6)))
    y = x + ca.pi / 2
    m = y - 2 * ca.pi * ca.floor(y / (2 * ca.pi)) - ca.pi / 2
    return ca.fmin(1, ca.fmax(-1, (ca.pi / 2 - ca.fabs(m - ca.pi / 2)) / (ca.pi / 6)))


class _ThreePhaseAirGap(TwoFlange, partial=True):
    """Three phase pins of a star winding (star point inside, no neutral wire), the rotor
    angle and the electromagnetic torque; rotor at ``A``, stator at ``B``."""

    a = Pin(doc="Phase a terminal")
    b = Pin(doc="Phase b terminal")
    c = Pin(doc="Phase c terminal")
    p = Parameter("1", default=2.0, min=1, doc="Pole pairs")
    R = Parameter("Ohm", default=0.03, min=0, doc="Stator resistance per phase")
    psi = Parameter("Wb", default=math.sqrt(2) * 112.3 / _W_NOM, min=0,
                    doc="Magnet flux linkage per phase (peak); peak phase EMF p psi w")
    phi = Variable("rad", start=0.0, doc="Rotor angle (mechanical), A relative to B")
    i_a = Variable("A", doc="Phase a current (into pin a)")
    i_b = Variable("A", doc="Phase b current (into pin b)")
    i_c = Variable("A", doc="Phase c current (into pin c)")
    T = Variable("N*m", doc="Electromagnetic torque on the rotor")

    def equations(self):
        return [der(self.phi) == self.w,
                self.a.i == self.i_a, self.b.i == self.i_b, self.c.i == self.i_c,
                self.tau == -self.T]

    def _copper_loss(self):
        return self.R * (self.i_a ** 2 + self.i_b ** 2 + self.i_c ** 2)


class AirGapPMSM(_ThreePhaseAirGap):
    """Stator winding and magnet rotor of a PMSM in the rotor (d, q) frame: the phase
    quantities Park-transformed with the electrical angle ``theta_e = p phi``.

    Angles ``theta_k = p phi - k 2 pi/3`` (k = 0, 1, 2 for phases a, b, c). The magnet's
    flux linkage with phase k is ``-psi cos(theta_k)``, so its back EMF is
    ``e_k = p psi w sin(theta_k)``: phase a's EMF crosses zero rising at ``phi = 0``, as
    the trapezoidal shape of :class:`AirGapTrapezoidal` does. The d axis (the magnet's)
    is at ``theta_e + pi``; amplitude-invariant Park transform::

        v_d == -2/3 sum_k k.v cos(theta_k),   v_q == 2/3 sum_k k.v sin(theta_k)
        i_k == -i_d cos(theta_k) + i_q sin(theta_k)     (so i_a + i_b + i_c == 0)
        L_d di_d/dt == v_d - R i_d + p w L_q i_q
        L_q di_q/dt == v_q - R i_q - p w (L_d i_d + psi)
        T == 3/2 p (psi i_q + (L_d - L_q) i_d i_q),  tau == -T,  dphi/dt == w

    The star point's potential drops out of ``v_d``, ``v_q`` (no zero-sequence current).
    Power: ``sum_k k.v i_k == 3/2 (v_d i_d + v_q i_q)``; the winding stores
    ``3/4 (L_d i_d^2 + L_q i_q^2)``. Limitations: no saturation, no cogging, no iron
    losses, no damper cage.
    """

    L_d = Parameter("H", default=0.4 / _W_NOM, min=0, doc="Direct-axis inductance")
    L_q = Parameter("H", default=0.4 / _W_NOM, min=0, doc="Quadrature-axis inductance")
    i_d = Variable("A", start=0.0, doc="Direct-axis current (amplitude-invariant)")
    i_q = Variable("A", start=0.0, doc="Quadrature-axis current (amplitude-invariant)")
    v_d = Variable("V", doc="Direct-axis voltage")
    v_q = Variable("V", doc="Quadrature-axis voltage")

    def equations(self):
        th = self.p * self.phi
        angles = [th, th - TWO_PI_3, th + TWO_PI_3]
        pins = [self.a.v, self.b.v, self.c.v]
        currents = [self.i_a, self.i_b, self.i_c]
        we = self.p * self.w
        return [self.v_d == -2 / 3 * sum(v * ca.cos(x) for v, x in zip(pins, angles)),
                self.v_q == 2 / 3 * sum(v * ca.sin(x) for v, x in zip(pins, angles)),
                *[i == -self.i_d * ca.cos(x) + self.i_q * ca.sin(x)
                  for i, x in zip(currents, angles)],
                self.L_d * der(self.i_d) == self.v_d - self.R * self.i_d
                + we * self.L_q * self.i_q,
                self.L_q * der(self.i_q) == self.v_q - self.R * self.i_q
                - we * (self.L_d * self.i_d + self.psi),
                self.T == 1.5 * self.p * (self.psi * self.i_q
                                          + (self.L_d - self.L_q) * self.i_d * self.i_q)]


class AirGapTrapezoidal(_ThreePhaseAirGap):
    """Stator winding and magnet rotor with a trapezoidal back EMF, in the phase frame (the
    electromechanical core of a BLDC motor; a dq model cannot carry the flat tops).

    Per phase ``k`` in (a, b, c), ``theta_k = p phi - k 2 pi/3``, star point at ``v_n``::

        k.v - v_n == R i_k + L di_k/dt + e_k
        e_k == p psi w f(theta_k)            f: unit trapezoid (:func:`trapezoid`)
        i_a + i_b + i_c == 0                 (star point, no neutral wire)
        T == p psi sum_k f(theta_k) i_k,  tau == -T,  dphi/dt == w

    so ``T w == sum_k e_k i_k``. Summing the phase equations gives the star point
    ``v_n == (sum_k k.v - sum_k e_k) / 3``; only ``i_a``, ``i_b`` are states. With two
    phases carrying ``+I`` and ``-I`` on the flat tops the torque is ``2 p psi I``.
    ``L`` is the phase self inductance minus the mutual one. Limitations: no saturation,
    reluctance or cogging torque.
    """

    L = Parameter("H", default=0.4 / _W_NOM, min=0, doc="Phase inductance (self - mutual)")
    e_a = Variable("V", doc="Phase a back EMF")
    e_b = Variable("V", doc="Phase b back EMF")
    e_c = Variable("V", doc="Phase c back EMF")
    v_n = Variable("V", doc="Star point potential")

    def equations(self):
        th = self.p * self.phi
        shapes = [trapezoid(th), trapezoid(th - TWO_PI_3), trapezoid(th + TWO_PI_3)]
        currents = [self.i_a, self.i_b, self.i_c]
        emfs = [self.e_a, self.e_b, self.e_c]
        k_e = self.p * self.psi
        return [self.i_c == -(self.i_a + self.i_b),
                *[e == k_e * self.w * f for e, f in zip(emfs, shapes)],
                self.v_n == (self.a.v + self.b.v + self.c.v - self.e_a - self.e_b
                             - self.e_c) / 3,
                self.L * der(self.i_a) == self.a.v - self.v_n - self.R * self.i_a - self.e_a,
                self.L * der(self.i_b) == self.b.v - self.v_n - self.R * self.i_b - self.e_b,
                self.T == k_e * sum(f * i for f, i in zip(shapes, currents))]


class _PMSMData(MachineOptions, Component, partial=True):
    """MSL's ``SM_PermanentMagnetData`` (without damper cage), the pins, shaft, support,
    rotor inertia and bearing friction."""

    _options = {"use_heat_port": False, "emf": "sinusoidal"}

    p = Parameter("1", default=2.0, min=1, doc="Pole pairs")
    f_s_nom = Parameter("Hz", default=50.0, min=0, doc="Nominal stator frequency")
    V_s_open_circuit = Parameter("V", default=112.3, min=0,
                                 doc="Open-circuit RMS phase voltage at f_s_nom")
    R_s = Parameter("Ohm", default=0.03, min=0, doc="Stator resistance per phase")
    L_s_sigma = Parameter("H", default=0.1 / _W_NOM, min=0,
                          doc="Stator stray inductance per phase")
    L_md = Parameter("H", default=0.3 / _W_NOM, min=0,
                     doc="Main-field inductance, d axis")
    L_mq = Parameter("H", default=0.3 / _W_NOM, min=0,
                     doc="Main-field inductance, q axis")
    J_r = Parameter("kg*m^2", default=0.29, min=0, doc="Rotor moment of inertia")
    B_v = Parameter("N*m*s/rad", default=0.0, min=0, doc="Viscous friction of the bearings")

    a = Pin(doc="Phase a terminal")
    b = Pin(doc="Phase b terminal")
    c = Pin(doc="Phase c terminal")
    flange = Flange(doc="Shaft")
    support = Flange(doc="Support (housing); connect it to a rotational reference")

    inertia = rot.Inertia(J=J_r)
    friction = rot.RotationalDamper(D=B_v)

    @classmethod
    def _variant(cls, options, kwargs):
        emf = options["emf"]
        if emf not in ("sinusoidal", "trapezoidal"):
            raise ValueError(f"{cls.__name__}(emf=...): the back-EMF shape must be "
                             f"'sinusoidal' or 'trapezoidal', got {emf!r}.")
        base = TrapezoidalPMSM if emf == "trapezoidal" else PMSM
        return base._thermal if options["use_heat_port"] else base

    def equations(self):
        return [connect(self.a, self.airgap.a), connect(self.b, self.airgap.b),
                connect(self.c, self.airgap.c),
                connect(self.airgap.A, self.inertia.port, self.friction.A, self.flange),
                connect(self.airgap.B, self.friction.B, self.support)]

    def _loss_power(self):
        return self.airgap._copper_loss() + self.friction.tau * self.friction.w


_D = _PMSMData
#: magnet flux linkage from the open-circuit voltage (MSL's rule)
_PSI = math.sqrt(2) * _D.V_s_open_circuit / (2 * math.pi * _D.f_s_nom)


class PMSM(_PMSMData):
    """Permanent-magnet synchronous machine (MSL's ``SM_PermanentMagnet`` without damper
    cage; Simscape's ``PMSM``): three-phase star winding (pins ``a``, ``b``, ``c``), dq
    model of :class:`AirGapPMSM`, rotor inertia and bearing friction, shaft ``flange``
    and housing ``support``.

    Parameters are MSL's ``SM_PermanentMagnetData`` (defaults: 2 pole pairs, 50 Hz,
    112.3 V open-circuit RMS phase voltage, 0.03 Ohm, 0.29 kg m^2), from which::

        psi == sqrt(2) V_s_open_circuit / (2 pi f_s_nom)
        L_d == L_s_sigma + L_md,   L_q == L_s_sigma + L_mq
        J_r dw/dt == T - B_v w - tau_load,   w = flange.w - support.w

    With ``emf="trapezoidal"`` the part is a :class:`TrapezoidalPMSM` (phase frame, the
    seed's BLDC), with ``use_heat_port=True`` the variant with a heat port taking the
    copper and friction losses. The electrical angle is ``p * airgap.phi``; the rotor
    speed ``inertia.w``. Limitations: those of :class:`AirGapPMSM`; ``support`` must be
    fixed (the rotor inertia is referenced to the ground).
    """

    airgap = AirGapPMSM(p=_D.p, R=_D.R_s, psi=_PSI, L_d=_D.L_s_sigma + _D.L_md,
                        L_q=_D.L_s_sigma + _D.L_mq)


class TrapezoidalPMSM(_PMSMData):
    """PMSM with a trapezoidal back EMF (``PMSM(emf="trapezoidal")``; Simscape's BLDC):
    as :class:`PMSM` with the phase-frame core :class:`AirGapTrapezoidal`::

        e_k == p psi w f(p phi - k 2 pi/3),   L == L_s_sigma + L_md

    (``L_mq`` is not used: the phase frame has one inductance per phase). Peak phase EMF
    ``p psi w`` as the sinusoidal machine's, so the two share their data.
    """

    _options = {"use_heat_port": False, "emf": "trapezoidal"}

    airgap = AirGapTrapezoidal(p=_D.p, R=_D.R_s, psi=_PSI, L=_D.L_s_sigma + _D.L_md)


_LOSSES = "R_s (i_a^2 + i_b^2 + i_c^2) + B_v w^2"
PMSMWithHeatPort = thermal_variant(PMSM, _LOSSES)
TrapezoidalPMSMWithHeatPort = thermal_variant(TrapezoidalPMSM, _LOSSES)
