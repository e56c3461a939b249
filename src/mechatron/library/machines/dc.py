"""DC machines built as subsystems of library parts (Modelica's
``Electrical.Machines.BasicMachines.DCMachines``, Simscape's ``DC Motor``)."""

from mechatron.core import Component, Parameter, Variable, connect
from mechatron.library import electrical as el
from mechatron.library import rotational as rot
from mechatron.library.electrical.interfaces import OnePort, Pin
from mechatron.library.electromechanical import RotationalEMF
from mechatron.library.machines.interfaces import MachineOptions, thermal_variant
from mechatron.library.rotational.interfaces import Flange, TwoFlange

__all__ = ["DCPermanentMagnet", "DCElectricalExcited", "DCSeries", "DCShunt", "AirGapDC",
           "DCPermanentMagnetWithHeatPort", "DCElectricalExcitedWithHeatPort",
           "DCSeriesWithHeatPort", "DCShuntWithHeatPort"]


class DCPermanentMagnet(MachineOptions, Component):
    """Permanent-magnet brush DC machine: armature resistance and inductance, EMF, rotor
    inertia and viscous friction, as one part (a subsystem of library components).

    Equations (through its parts)::

        v == R i + L di/dt + k w        (armature, v = p.v - n.v, i into p)
        J dw/dt == k i - B w - tau_L    (rotor; tau_L is the load torque taken at A)

    with ``w = flange.w - support.w``. The torque constant equals the back-EMF constant ``k`` (SI
    units). Sign convention: a positive armature current drives the shaft ``flange``
    forward relative to the ``support``.

    Limitations: the rotor inertia is referenced to the ground (library ``Inertia``), so
    connect ``support`` to a fixed reference (a housing on a moving support is not modelled); no
    brush drop, no saturation, no armature reaction; a constant field (for an
    electrically excited field use ``RotationalEMF`` with a controlled ``k``).
    ``use_heat_port=True`` builds the variant whose ``heat_port`` takes the losses.
    """

    R = Parameter("Ohm", default=7.1, min=0, doc="Armature resistance")
    L = Parameter("H", default=3.408e-4, min=0, doc="Armature inductance")
    k = Parameter("V*s/rad", default=0.151, min=0,
                  doc="Back-EMF and torque constant (V*s/rad = N*m/A)")
    J = Parameter("kg*m^2", default=4.8e-6, min=0, doc="Rotor moment of inertia")
    B_v = Parameter("N*m*s/rad", default=1.236e-4, min=0,
                    doc="Viscous friction coefficient of the bearings")

    p = Pin(doc="Positive armature terminal")
    n = Pin(doc="Negative armature terminal")
    flange = Flange(doc="Shaft")
    support = Flange(doc="Support (housing); connect it to a rotational reference")

    resistor = el.Resistor(R=R)
    inductor = el.Inductor(L=L)
    emf = RotationalEMF(k=k)
    inertia = rot.Inertia(J=J)
    friction = rot.RotationalDamper(D=B_v)

    def equations(self):
        return [connect(self.p, self.resistor.p),
                connect(self.resistor.n, self.inductor.p),
                connect(self.inductor.n, self.emf.p),
                connect(self.emf.n, self.n),
                connect(self.emf.A, self.inertia.port, self.friction.A, self.flange),
                connect(self.emf.B, self.friction.B, self.support)]

    def _loss_power(self):
        return self.resistor.v * self.resistor.i + self.friction.tau * self.friction.w


class AirGapDC(OnePort, TwoFlange):
    """Air gap of an electrically excited DC machine (MSL's ``AirGapDC``): the armature's
    EMF and torque proportional to the field current.

    Pins ``p``, ``n`` carry the armature current ``i``; the field current enters at ``fp``
    and leaves at ``fn`` with no voltage drop (the field winding's resistance and
    inductance are separate parts). Flange ``A`` is the shaft, ``B`` the support.

    Equations::

        fp.v == fn.v,  fp.i + fn.i == 0
        psi == L_me fp.i              (main-field flux linkage, linear: no saturation)
        v == psi w                    (back EMF)
        tau == -psi i                 (the shaft at A is driven by psi i)

    so ``v i + tau w == 0``: no power is lost in the gap.
    """

    fp = Pin(doc="Field current in")
    fn = Pin(doc="Field current out")
    L_me = Parameter("H", default=0.06, min=0, doc="Mutual inductance, field to armature EMF")
    psi = Variable("Wb", doc="Main-field flux linkage L_me * field current")

    def equations(self):
        return [self.fp.v == self.fn.v, self.fp.i + self.fn.i == 0,
                self.psi == self.L_me * self.fp.i,
                self.v == self.psi * self.w,
                self.tau == -self.psi * self.i]


class _DCMachine(MachineOptions, Component, partial=True):
    """Nominal data (MSL's ``DcElectricalExcitedData`` defaults), armature and rotor;
    ``use_heat_port=True`` builds the variant whose ``heat_port`` takes the copper losses
    of armature and field and the bearing friction."""

    V_a_nom = Parameter("V", default=100.0, min=0, doc="Nominal armature voltage")
    I_a_nom = Parameter("A", default=100.0, min=0, doc="Nominal armature current")
    w_nom = Parameter("rad/s", default=1425 * 2 * 3.141592653589793 / 60, min=0,
                      doc="Nominal speed (1425 rpm)")
    R_a = Parameter("Ohm", default=0.05, min=0, doc="Armature resistance")
    L_a = Parameter("H", default=0.0015, min=0, doc="Armature inductance")
    J_r = Parameter("kg*m^2", default=0.15, min=0, doc="Rotor moment of inertia")
    B_v = Parameter("N*m*s/rad", default=0.0, min=0, doc="Viscous friction of the bearings")

    p = Pin(doc="Positive armature terminal")
    n = Pin(doc="Negative armature terminal")
    flange = Flange(doc="Shaft")
    support = Flange(doc="Support (housing); connect it to a rotational reference")

    r_a = el.Resistor(R=R_a)
    l_a = el.Inductor(L=L_a)
    inertia = rot.Inertia(J=J_r)
    friction = rot.RotationalDamper(D=B_v)

    def _loss_power(self):
        return (self.r_a.v * self.r_a.i + self.r_e.v * self.r_e.i
                + self.friction.tau * self.friction.w)


# the nominal data, to pass on in the machines' class bodies
_V_A_NOM, _I_A_NOM, _W_NOM, _R_A = (_DCMachine.V_a_nom, _DCMachine.I_a_nom, _DCMachine.w_nom,
                                    _DCMachine.R_a)


class DCElectricalExcited(_DCMachine):
    """Separately excited DC machine (MSL's ``DC_ElectricalExcited``): armature (``p``,
    ``n``) and field winding (``pe``, ``ne``) apart, as one part.

    Equations (through its parts), with ``w = flange.w - support.w``::

        v_a == R_a i_a + L_a di_a/dt + psi w          (armature, v_a = p.v - n.v)
        v_e == R_e i_e + L_e di_e/dt                  (field, v_e = pe.v - ne.v)
        psi == L_me i_e,  L_me = (V_a_nom - R_a I_a_nom) / (w_nom I_e_nom)
        J_r dw/dt == psi i_a - B_v w - tau_load

    ``L_me`` follows from the nominal data (MSL's rule), so at nominal armature voltage,
    nominal field current ``I_e_nom`` (field voltage ``R_e I_e_nom``) and the load torque
    ``L_me I_e_nom I_a_nom`` (no friction) the machine runs at ``w_nom`` with ``I_a_nom``.
    Limitations: as :class:`DCPermanentMagnet`; no saturation of the field, no brush drop,
    no armature reaction.
    """

    I_e_nom = Parameter("A", default=1.0, min=0, doc="Nominal field current")
    R_e = Parameter("Ohm", default=100.0, min=0, doc="Field winding resistance")
    L_e = Parameter("H", default=1.0, min=0, doc="Field winding inductance")

    pe = Pin(doc="Positive field terminal")
    ne = Pin(doc="Negative field terminal")

    r_e = el.Resistor(R=R_e)
    l_e = el.Inductor(L=L_e)
    airgap = AirGapDC(L_me=(_V_A_NOM - _R_A * _I_A_NOM) / (_W_NOM * I_e_nom))

    def equations(self):
        return [connect(self.p, self.r_a.p), connect(self.r_a.n, self.l_a.p),
                connect(self.l_a.n, self.airgap.p), connect(self.airgap.n, self.n),
                connect(self.pe, self.r_e.p), connect(self.r_e.n, self.l_e.p),
                connect(self.l_e.n, self.airgap.fp), connect(self.airgap.fn, self.ne),
                connect(self.airgap.A, self.inertia.port, self.friction.A, self.flange),
                connect(self.airgap.B, self.friction.B, self.support)]


class DCSeries(_DCMachine):
    """Series-excited DC machine (MSL's ``DC_SeriesExcited``): the field winding in series
    with the armature between ``p`` and ``n``.

    Equations (through its parts), with ``i`` the current from ``p`` to ``n``::

        v == (R_a + R_e) i + (L_a + L_e) di/dt + psi w
        psi == L_me i,  L_me = (V_a_nom - (R_a + R_e) I_a_nom) / (w_nom I_a_nom)
        J_r dw/dt == L_me i^2 - B_v w - tau_load

    At nominal voltage and the load torque ``L_me I_a_nom^2`` it runs at ``w_nom`` with
    ``I_a_nom``. The torque grows with the square of the current (the traction motor's
    high starting torque); unloaded, the speed runs away.
    """

    R_e = Parameter("Ohm", default=0.01, min=0, doc="Series field winding resistance")
    L_e = Parameter("H", default=0.0005, min=0, doc="Series field winding inductance")

    r_e = el.Resistor(R=R_e)
    l_e = el.Inductor(L=L_e)
    airgap = AirGapDC(L_me=(_V_A_NOM - (_R_A + R_e) * _I_A_NOM) / (_W_NOM * _I_A_NOM))

    def equations(self):
        return [connect(self.p, self.r_a.p), connect(self.r_a.n, self.l_a.p),
                connect(self.l_a.n, self.airgap.p), connect(self.airgap.n, self.airgap.fp),
                connect(self.airgap.fn, self.r_e.p), connect(self.r_e.n, self.l_e.p),
                connect(self.l_e.n, self.n),
                connect(self.airgap.A, self.inertia.port, self.friction.A, self.flange),
                connect(self.airgap.B, self.friction.B, self.support)]


class DCShunt(_DCMachine):
    """Shunt-excited DC machine: the field winding in parallel with the armature across
    ``p`` and ``n``.

    Equations (through its parts), with ``v = p.v - n.v``::

        v == R_a i_a + L_a di_a/dt + psi w            (armature)
        v == R_e i_e + L_e di_e/dt                    (field)
        psi == L_me i_e,  L_me = (V_a_nom - R_a I_a_nom) R_e / (w_nom V_a_nom)
        J_r dw/dt == psi i_a - B_v w - tau_load,      p.i == i_a + i_e

    The nominal field current is ``V_a_nom / R_e``; at nominal voltage and the load
    torque ``L_me I_a_nom V_a_nom / R_e`` it runs at ``w_nom`` with armature current
    ``I_a_nom`` (terminal current ``I_a_nom + V_a_nom / R_e``).
    """

    R_e = Parameter("Ohm", default=100.0, min=0, doc="Shunt field winding resistance")
    L_e = Parameter("H", default=1.0, min=0, doc="Shunt field winding inductance")

    r_e = el.Resistor(R=R_e)
    l_e = el.Inductor(L=L_e)
    airgap = AirGapDC(L_me=(_V_A_NOM - _R_A * _I_A_NOM) * R_e / (_W_NOM * _V_A_NOM))

    def equations(self):
        return [connect(self.p, self.r_a.p, self.r_e.p), connect(self.r_a.n, self.l_a.p),
                connect(self.l_a.n, self.airgap.p), connect(self.airgap.n, self.n),
                connect(self.r_e.n, self.l_e.p), connect(self.l_e.n, self.airgap.fp),
                connect(self.airgap.fn, self.n),
                connect(self.airgap.A, self.inertia.port, self.friction.A, self.flange),
                connect(self.airgap.B, self.friction.B, self.support)]


DCPermanentMagnetWithHeatPort = thermal_variant(DCPermanentMagnet, "R i^2 + B_v w^2")
_DC_LOSSES = "R_a i_a^2 + R_e i_e^2 + B_v w^2"
DCElectricalExcitedWithHeatPort = thermal_variant(DCElectricalExcited, _DC_LOSSES)
DCSeriesWithHeatPort = thermal_variant(DCSeries, _DC_LOSSES)
DCShuntWithHeatPort = thermal_variant(DCShunt, _DC_LOSSES)
