"""Hydraulic connector, the two-port partial component and the working fluid."""

from __future__ import annotations

from dataclasses import dataclass, fields

from mechatron.core import Across, Component, Connector, Through, Variable
from mechatron.core.domains import HYDRAULIC

__all__ = ["HydraulicPort", "TwoPort", "Fluid", "ISO_VG32"]


class HydraulicPort(Connector, domain=HYDRAULIC):
    """Hydraulic port: pressure and the volumetric flow into the component."""

    p = Across("Pa", doc="Pressure at the port (gauge, relative to the atmosphere)",
               hint="Is a hydraulic reference (reservoir) missing, or a port left "
                    "unconnected?")
    q = Through("m^3/s", doc="Volumetric flow rate into the component at the port")


class TwoPort(Component, partial=True):
    """Two hydraulic ports; flow ``q`` enters at ``A`` and leaves at ``B``;
    ``dp = A.p - B.p``."""

    A = HydraulicPort(doc="Port A")
    B = HydraulicPort(doc="Port B")
    dp = Variable("Pa", doc="Pressure difference, A.p - B.p")
    q = Variable("m^3/s", doc="Volumetric flow rate from A to B through the component")

    def equations(self):
        return [self.dp == self.A.p - self.B.p,
                self.A.q + self.B.q == 0,
                self.q == self.A.q]


@dataclass(frozen=True)
class Fluid:
    """Properties of an isothermal liquid, constant over the operating range.

    Parameters
    ----------
    rho : float
        Density, kg/m^3.
    nu : float
        Kinematic viscosity, m^2/s (dynamic viscosity ``mu = rho nu``).
    beta : float
        Isothermal bulk modulus, Pa.

    Components take these as their own parameters ``rho``, ``nu``, ``beta``;
    :meth:`params_for` picks the ones a component declares::

        hy.FixedOrifice(area=1e-5, **fluid.params_for(hy.FixedOrifice))
    """

    rho: float
    nu: float
    beta: float

    def params_for(self, component: type | Component) -> dict[str, float]:
        """The fluid properties that ``component`` (a class or an instance) declares."""
        cls = component if isinstance(component, type) else type(component)
        names = cls._declarations
        return {f.name: getattr(self, f.name) for f in fields(self) if f.name in names}


#: Mineral hydraulic oil ISO VG 32 at 40 degC: 32 cSt (ISO 3448 mid-point), 860 kg/m^3,
#: isothermal secant bulk modulus 1.5 GPa without entrained air (typical data sheet
#: values). These are the defaults of every hydraulic component.
ISO_VG32 = Fluid(rho=860.0, nu=32e-6, beta=1.5e9)
