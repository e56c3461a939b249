"""DC machines built as subsystems of library parts (Modelica's
``Electrical.Machines.BasicMachines.DCMachines``, Simscape's ``DC Motor``)."""

from mechatron.core import Component, Parameter, connect
from mechatron.library import electrical as el
from mechatron.library import rotational as rot
from mechatron.library.electrical.interfaces import Pin
from mechatron.library.electromechanical import RotationalEMF
from mechatron.library.rotational.interfaces import Flange

__all__ = ["DCPermanentMagnet"]


class DCPermanentMagnet(Component):
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
