"""Asynchronous induction machine with squirrel cage (Modelica's
``Electrical.Machines.BasicMachines.InductionMachines.IM_SquirrelCage``, Simscape's
``Induction Machine``)."""

from __future__ import annotations

import math

from mechatron.core import Component, Parameter, Variable, connect, der
from mechatron.library import rotational as rot
from mechatron.library.electrical.interfaces import Pin
from mechatron.library.machines.interfaces import MachineOptions, thermal_variant
from mechatron.library.rotational.interfaces import Flange, TwoFlange

__all__ = ["AirGapInduction", "InductionMachine", "InductionMachineWithHeatPort"]

_W_NOM = 2 * math.pi * 50.0
_K = math.sqrt(1 - 0.0667)        # MSL's default coupling: leakage factor 0.0667
SQRT3 = math.sqrt(3)


class AirGapInduction(TwoFlange):
    """Stator and squirrel-cage rotor of an induction machine as space phasors in the
    stator-fixed (alpha, beta) frame; three phase pins of a star winding (star point
    inside), rotor at ``A``, stator at ``B``.

    Clarke transform (amplitude-invariant), fluxes as states, currents from them::

        v_alpha == 2/3 (a.v - (b.v + c.v)/2),   v_beta == (b.v - c.v)/sqrt(3)
        i_a == i_s_alpha,  i_b, i_c == -i_s_alpha/2 -+ sqrt(3)/2 i_s_beta
        psi_s == L_s i_s + L_m i_r,   psi_r == L_m i_s + L_r i_r
        dpsi_s/dt == v_s - R_s i_s
        dpsi_r/dt == -R_r i_r + j p w psi_r      (the cage short-circuited)
        T == 3/2 p (psi_s_alpha i_s_beta - psi_s_beta i_s_alpha),  tau == -T

    with ``L_s = L_s_sigma + L_m``, ``L_r = L_r_sigma + L_m`` (the T-equivalent circuit's
    per-phase values, as MSL's data give them; the rotor referred to the stator). Power:
    ``sum_k k.v i_k == 3/2 v_s . i_s``. Limitations: linear magnetics (no saturation), no
    iron, stray-load or skin-effect losses, no zero-sequence current.
    """

    a = Pin(doc="Phase a terminal")
    b = Pin(doc="Phase b terminal")
    c = Pin(doc="Phase c terminal")
    p = Parameter("1", default=2.0, min=1, doc="Pole pairs")
    R_s = Parameter("Ohm", default=0.03, min=0, doc="Stator resistance per phase")
    R_r = Parameter("Ohm", default=0.04, min=0, doc="Rotor resistance (stator side)")
    L_s_sigma = Parameter("H", default=3 * (1 - _K) / _W_NOM, min=0,
                          doc="Stator stray inductance per phase")
    L_r_sigma = Parameter("H", default=3 * (1 - _K) / _W_NOM, min=0,
                          doc="Rotor stray inductance (stator side)")
    L_m = Parameter("H", default=3 * _K / _W_NOM, min=0, doc="Main-field inductance")
    psi_s_alpha = Variable("Wb", start=0.0, doc="Stator flux linkage, alpha")
    psi_s_beta = Variable("Wb", start=0.0, doc="Stator flux linkage, beta")
    psi_r_alpha = Variable("Wb", start=0.0, doc="Rotor flux linkage, alpha (stator frame)")
    psi_r_beta = Variable("Wb", start=0.0, doc="Rotor flux linkage, beta (stator frame)")
    i_s_alpha = Variable("A", doc="Stator current, alpha")
    i_s_beta = Variable("A", doc="Stator current, beta")
    i_r_alpha = Variable("A", doc="Rotor current, alpha (stator frame, stator side)")
    i_r_beta = Variable("A", doc="Rotor current, beta (stator frame, stator side)")
    v_alpha = Variable("V", doc="Stator voltage, alpha")
    v_beta = Variable("V", doc="Stator voltage, beta")
    T = Variable("N*m", doc="Electromagnetic torque on the rotor")

    def equations(self):
        L_s, L_r, L_m = self.L_s_sigma + self.L_m, self.L_r_sigma + self.L_m, self.L_m
        det = L_s * L_r - L_m ** 2
        we = self.p * self.w
        return [self.v_alpha == 2 / 3 * (self.a.v - (self.b.v + self.c.v) / 2),
                self.v_beta == (self.b.v - self.c.v) / SQRT3,
                self.a.i == self.i_s_alpha,
                self.b.i == -self.i_s_alpha / 2 + SQRT3 / 2 * self.i_s_beta,
                self.c.i == -self.i_s_alpha / 2 - SQRT3 / 2 * self.i_s_beta,
                self.i_s_alpha == (L_r * self.psi_s_alpha - L_m * self.psi_r_alpha) / det,
                self.i_s_beta == (L_r * self.psi_s_beta - L_m * self.psi_r_beta) / det,
                self.i_r_alpha == (L_s * self.psi_r_alpha - L_m * self.psi_s_alpha) / det,
                self.i_r_beta == (L_s * self.psi_r_beta - L_m * self.psi_s_beta) / det,
                der(self.psi_s_alpha) == self.v_alpha - self.R_s * self.i_s_alpha,
                der(self.psi_s_beta) == self.v_beta - self.R_s * self.i_s_beta,
                der(self.psi_r_alpha) == -self.R_r * self.i_r_alpha - we * self.psi_r_beta,
                der(self.psi_r_beta) == -self.R_r * self.i_r_beta + we * self.psi_r_alpha,
                self.T == 1.5 * self.p * (self.psi_s_alpha * self.i_s_beta
                                          - self.psi_s_beta * self.i_s_alpha),
                self.tau == -self.T]

    def _copper_loss(self):
        return 1.5 * (self.R_s * (self.i_s_alpha ** 2 + self.i_s_beta ** 2)
                      + self.R_r * (self.i_r_alpha ** 2 + self.i_r_beta ** 2))


class InductionMachine(MachineOptions, Component):
    """Asynchronous induction machine with squirrel cage (MSL's ``IM_SquirrelCage``):
    three-phase star winding (pins ``a``, ``b``, ``c``), the space-phasor model of
    :class:`AirGapInduction`, rotor inertia and bearing friction, shaft ``flange`` and
    housing ``support``.

    Parameters are MSL's ``IM_SquirrelCageData`` (defaults for 50 Hz: 2 pole pairs,
    ``R_s = 0.03``, ``R_r = 0.04`` Ohm, leakage factor 0.0667, 0.29 kg m^2), with which
    MSL's example ``IMC_DOL`` (100 V RMS per phase winding, 50 Hz) carries its nominal
    161.4 N*m at 1440.45 rpm. Mechanics::

        J_r dw/dt == T - B_v w - tau_load,   w = flange.w - support.w

    ``use_heat_port=True`` builds the variant whose heat port takes the copper and
    friction losses. Limitations: those of :class:`AirGapInduction`; ``support`` must be
    fixed.
    """

    p = Parameter("1", default=2.0, min=1, doc="Pole pairs")
    R_s = Parameter("Ohm", default=0.03, min=0, doc="Stator resistance per phase")
    R_r = Parameter("Ohm", default=0.04, min=0, doc="Rotor resistance (stator side)")
    L_s_sigma = Parameter("H", default=3 * (1 - _K) / _W_NOM, min=0,
                          doc="Stator stray inductance per phase")
    L_r_sigma = Parameter("H", default=3 * (1 - _K) / _W_NOM, min=0,
                          doc="Rotor stray inductance (stator side)")
    L_m = Parameter("H", default=3 * _K / _W_NOM, min=0, doc="Main-field inductance")
    J_r = Parameter("kg*m^2", default=0.29, min=0, doc="Rotor moment of inertia")
    B_v = Parameter("N*m*s/rad", default=0.0, min=0, doc="Viscous friction of the bearings")

    a = Pin(doc="Phase a terminal")
    b = Pin(doc="Phase b terminal")
    c = Pin(doc="Phase c terminal")
    flange = Flange(doc="Shaft")
    support = Flange(doc="Support (housing); connect it to a rotational reference")

    airgap = AirGapInduction(p=p, R_s=R_s, R_r=R_r, L_s_sigma=L_s_sigma,
                             L_r_sigma=L_r_sigma, L_m=L_m)
    inertia = rot.Inertia(J=J_r)
    friction = rot.RotationalDamper(D=B_v)

    def equations(self):
        return [connect(self.a, self.airgap.a), connect(self.b, self.airgap.b),
                connect(self.c, self.airgap.c),
                connect(self.airgap.A, self.inertia.port, self.friction.A, self.flange),
                connect(self.airgap.B, self.friction.B, self.support)]

    def _loss_power(self):
        return self.airgap._copper_loss() + self.friction.tau * self.friction.w


InductionMachineWithHeatPort = thermal_variant(
    InductionMachine, "3/2 (R_s |i_s|^2 + R_r |i_r|^2) + B_v w^2")
