"""Flux tubes from geometry and material (Modelica's ``Magnetic.FluxTubes.Shapes`` and
``Material``): saturating soft-magnetic tubes, permanent magnets, leakage permeances and
tubes whose length or width moves (with the reluctance force).

Soft-magnetic materials follow the approximation of the relative permeability over the
flux density that MSL uses ([Ro00] in MSL's literature list)::

    B_N = |B| / B_max
    mu_r = 1 + (mu_i - 1 + c_a B_N) / (1 + c_b B_N + B_N^n)

(``mu_i`` the initial permeability, ``B_max`` the flux density of the largest
permeability), or a measured B(H) curve given as a table. :data:`SOFT_MAGNETIC` and
:data:`HARD_MAGNETIC` hold a few of MSL's material data sets.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from mechatron.core import Parameter, Variable, der
from mechatron.errors import ModelError
from mechatron.library.blocks.interfaces import piecewise_linear
from mechatron.library.magnetic.components import MU0
from mechatron.library.magnetic.interfaces import TwoPort
from mechatron.library.translational.interfaces import Flange

__all__ = ["SoftMagnetic", "HardMagnetic", "SOFT_MAGNETIC", "HARD_MAGNETIC", "FluxTube",
           "SaturatingReluctance", "Cuboid", "HollowCylinderAxialFlux",
           "HollowCylinderRadialFlux", "PermanentMagnet", "Leakage", "LEAKAGE_SHAPES",
           "CuboidParallelFluxForce", "CuboidOrthogonalFluxForce",
           "HollowCylinderAxialFluxForce"]


@dataclass(frozen=True)
class SoftMagnetic:
    """Coefficients of the permeability approximation of a soft-magnetic material."""

    name: str
    mu_i: float          # initial relative permeability at B = 0
    B_max: float         # T, flux density at the largest relative permeability
    c_a: float
    c_b: float
    n: float

    def mu_r(self, B):
        """Relative permeability at the flux density ``B`` (numbers or arrays)."""
        b_n = np.abs(np.asarray(B, dtype=float)) / self.B_max
        return 1 + (self.mu_i - 1 + self.c_a * b_n) / (1 + self.c_b * b_n + b_n ** self.n)


@dataclass(frozen=True)
class HardMagnetic:
    """Permanent-magnet material: coercivity and remanence at ``T_ref`` and the linear
    temperature coefficient of both."""

    name: str
    H_cB: float          # A/m, coercivity
    B_r: float           # T, remanence
    alpha: float = 0.0   # 1/K, temperature coefficient of B_r and H_cB
    T_ref: float = 293.15

    def at(self, T: float) -> tuple[float, float]:
        """``(H_cB, B_r)`` at the temperature ``T`` (K)."""
        f = 1 + self.alpha * (T - self.T_ref)
        return self.H_cB * f, self.B_r * f


#: Soft-magnetic materials (MSL 4's ``FluxTubes.Material.SoftMagnetic`` data).
SOFT_MAGNETIC = {m.name: m for m in (
    SoftMagnetic("M350_50A", 1210.0, 1.16, 24630.0, 2.44, 14.0),   # electric sheet
    SoftMagnetic("M330_50A", 500.0, 0.7, 24000.0, 9.38, 9.6),      # sheet, complete core
    SoftMagnetic("Steel_9SMnPb28", 400.0, 1.488, 1200.0, 3.0, 12.5),  # free-cutting steel
    SoftMagnetic("AISI_1008", 200.0, 1.17, 8100.0, 2.59, 10.0),    # low-carbon steel
    SoftMagnetic("RFe80", 123.0, 1.27, 44410.0, 6.4, 10.0),        # pure iron
    SoftMagnetic("Vacoflux50", 3850.0, 1.75, 11790.0, 2.63, 15.02),  # 50 % CoFe
    SoftMagnetic("MuMetall", 27300.0, 0.46, 1037500.0, 3.67, 10.0),  # 77 % NiFe
)}

#: Permanent-magnet materials (MSL 4's ``FluxTubes.Material.HardMagnetic``, sintered,
#: exemplary values at 20 degC).
HARD_MAGNETIC = {m.name: m for m in (
    HardMagnetic("NdFeB", 900e3, 1.2, -0.001),
    HardMagnetic("SmCo5", 720e3, 0.95, -0.0004),
    HardMagnetic("HardFerrite", 170e3, 0.38, -0.002),
)}


def _soft(material, where: str) -> SoftMagnetic:
    if isinstance(material, SoftMagnetic):
        return material
    if material in SOFT_MAGNETIC:
        return SOFT_MAGNETIC[material]
    raise ModelError(f"{where}: unknown soft-magnetic material {material!r}. Use one of "
                     f"{', '.join(SOFT_MAGNETIC)} or a SoftMagnetic(...) data set.")


def _bh_table(rows, where: str) -> tuple[np.ndarray, np.ndarray]:
    """Checked B(H) table rows ``(H, B)`` starting at (0, 0), both increasing; returned
    as the breakpoints ``(B, H)`` of H(B), extended beyond the last row with the
    vacuum's slope dB/dH = mu0 (full saturation)."""
    try:
        arr = np.asarray(rows, dtype=float)
    except (TypeError, ValueError):
        raise ModelError(f"{where}: table must be rows (H, B) of numbers, got "
                         f"{rows!r}.") from None
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 2 \
            or not np.all(np.isfinite(arr)) or np.any(arr[0] != 0) \
            or np.any(np.diff(arr, axis=0) <= 0):
        raise ModelError(f"{where}: table must be at least two rows (H, B) in A/m and T, "
                         f"the first (0, 0), both columns strictly increasing, got "
                         f"{rows!r}. Give the first-quadrant magnetization curve.")
    H, B = arr[:, 0], arr[:, 1]
    H_far = H[-1] + 1e8
    return np.append(B, B[-1] + MU0 * 1e8), np.append(H, H_far)


class FluxTube(TwoPort, partial=True):
    """A flux tube of fixed shape and a soft-magnetic material (MSL's ``FixedShape``).

    A subclass gives its cross-section ``A`` (for the flux density) and its permeance per
    unit permeability ``g = G_m / (mu0 mu_r)`` (``A / l`` for a prism). Then::

        B_flux == phi / A,   H == B_flux / (mu0 mu_r),   mmf == phi / (mu0 mu_r g)

    with ``mu_r`` from the material (constructor keyword ``material``: a name of
    :data:`SOFT_MAGNETIC` or a :class:`SoftMagnetic`; sets the defaults of ``mu_i``,
    ``B_max``, ``c_a``, ``c_b``, ``n``), or the constant ``mu_r_const`` with
    ``material=None`` (linear), or a measured curve with ``table=((H, B), ...)`` (first
    quadrant from (0, 0), mirrored for negative B; beyond its last row the slope is
    mu0): then ``mmf == H(B) A / g``.
    """

    mu0 = Parameter("H/m", default=MU0, min=0, doc="Vacuum permeability")
    mu_r_const = Parameter("1", default=1.0, min=0,
                           doc="Constant relative permeability (material=None)")
    mu_i = Parameter("1", default=1.0, min=0, doc="Initial relative permeability at B = 0")
    B_max = Parameter("T", default=1.0, min=0,
                      doc="Flux density at the largest relative permeability")
    c_a = Parameter("1", default=1.0, doc="Coefficient c_a of the approximation")
    c_b = Parameter("1", default=1.0, doc="Coefficient c_b of the approximation")
    n = Parameter("1", default=1.0, doc="Exponent n of the approximation")
    H_per_B = Parameter("A/(m*T)", default=1.0, min=0,
                        doc="Units of a table: its H (A/m) per its B (T); keep 1")
    B_flux = Variable("T", doc="Flux density B, phi / A (the port is B)")
    H = Variable("A/m", doc="Magnetic field strength")
    mu_r = Variable("1", doc="Relative permeability")

    def __init__(self, material=None, table=None, **kwargs):
        where = f"{type(self).__name__}"
        self._material = None
        self._table = None
        if material is not None and table is not None:
            raise ModelError(f"{where}: give a material or a table, not both.")
        if table is not None:
            self._table = _bh_table(table, where)
        if material is not None:
            self._material = _soft(material, where)
            m = self._material
            kwargs = {"mu_i": m.mu_i, "B_max": m.B_max, "c_a": m.c_a, "c_b": m.c_b,
                      "n": m.n, **kwargs}
        super().__init__(**kwargs)

    def _geometry(self):
        """(cross-section A, permeance per unit permeability g = G_m / (mu0 mu_r))."""
        raise NotImplementedError

    def equations(self):
        area, g = self._geometry()
        if self._table is not None:
            B_pts, H_pts = self._table
            mu_0 = float(B_pts[1] / (MU0 * H_pts[1]))      # initial slope of the curve
            eps = 1e-9 * float(B_pts[1])
            return [self.B_flux == self.phi / area,
                    self.H == ca.sign(self.B_flux) * self.H_per_B
                    * piecewise_linear(ca.fabs(self.B_flux), B_pts, H_pts),
                    self.mmf == self.H * area / g,
                    # the secant permeability B / (mu0 H), its initial value at B = 0
                    self.mu_r == (ca.fabs(self.B_flux) + eps)
                    / (self.mu0 * ca.fabs(self.H) + eps / mu_0)]
        eqs = [self.B_flux == self.phi / area, self.H == self.B_flux / (self.mu0 * self.mu_r),
               self.mmf == self.phi / (self.mu0 * self.mu_r * g)]
        if self._material is None:
            return eqs + [self.mu_r == self.mu_r_const]
        b_n = ca.fabs(self.B_flux) / self.B_max
        return eqs + [self.mu_r == 1 + (self.mu_i - 1 + self.c_a * b_n)
                      / (1 + self.c_b * b_n + b_n ** self.n)]


class SaturatingReluctance(FluxTube):
    """Flux tube of length ``l`` and uniform cross-section ``area`` of a saturating
    material (a :class:`FluxTube`)::

        mmf == H l = phi l / (mu0 mu_r(B_flux) area),   B_flux == phi / area

    Stores the magnetic energy ``integral mmf dphi`` (no hysteresis: it is returned).
    """

    l = Parameter("m", default=0.1, min=0, doc="Length in the direction of the flux")
    area = Parameter("m^2", default=1e-4, min=0, doc="Cross-section area")

    def _geometry(self):
        return self.area, self.area / self.l


class Cuboid(FluxTube):
    """Cuboid flux tube (MSL's ``Shapes.FixedShape.Cuboid``), flux along its length::

        A == a b,   G_m == mu0 mu_r a b / l,   mmf == phi / G_m
    """

    l = Parameter("m", default=0.01, min=0, doc="Length in the direction of the flux")
    a = Parameter("m", default=0.01, min=0, doc="Width of the rectangular cross-section")
    b = Parameter("m", default=0.01, min=0, doc="Height of the rectangular cross-section")

    def _geometry(self):
        return self.a * self.b, self.a * self.b / self.l


class HollowCylinderAxialFlux(FluxTube):
    """(Hollow) cylinder or sector with the flux along its axis (MSL's
    ``Shapes.FixedShape.HollowCylinderAxialFlux``; ``r_i = 0`` for a solid one)::

        A == alpha (r_o^2 - r_i^2) / 2,   G_m == mu0 mu_r A / l
    """

    l = Parameter("m", default=0.01, min=0, doc="Axial length (in the direction of the flux)")
    r_i = Parameter("m", default=0.0, min=0, doc="Inner radius")
    r_o = Parameter("m", default=0.01, min=0, doc="Outer radius")
    alpha = Parameter("rad", default=2 * math.pi, min=0, doc="Central angle")

    def _geometry(self):
        area = self.alpha * (self.r_o ** 2 - self.r_i ** 2) / 2
        return area, area / self.l


class HollowCylinderRadialFlux(FluxTube):
    """Hollow cylinder or sector with radial flux (MSL's
    ``Shapes.FixedShape.HollowCylinderRadialFlux``)::

        G_m == mu0 mu_r alpha l / ln(r_o / r_i),   A == alpha l (r_o + r_i) / 2

    ``A`` (the section at the mean radius) only sets the flux density ``B`` that the
    material sees; the permeance is exact for a linear material.
    """

    l = Parameter("m", default=0.01, min=0, doc="Width (axial, across the flux)")
    r_i = Parameter("m", default=0.01, min=0, doc="Inner radius (> 0)")
    r_o = Parameter("m", default=0.02, min=0, doc="Outer radius")
    alpha = Parameter("rad", default=2 * math.pi, min=0, doc="Central angle")

    def _geometry(self):
        return (self.alpha * self.l * (self.r_o + self.r_i) / 2,
                self.alpha * self.l / ca.log(self.r_o / self.r_i))


class PermanentMagnet(TwoPort):
    """Permanent magnet magnetized from ``A`` to ``B`` (MSL builds it from a
    ``ConstantMagneticPotentialDifference`` and a flux tube): a linear recoil line with
    remanence ``B_r`` and coercivity ``H_cB``::

        mu_r == B_r / (mu0 H_cB)
        mmf == phi l / (mu0 mu_r area) - H_cB l    (B_flux == B_r + mu0 mu_r H inside)

    Short-circuited by iron it carries the flux ``B_r area``; open (no flux) it raises
    ``B.mmf - A.mmf`` by ``H_cB l``. The constructor keyword ``material`` (a name of
    :data:`HARD_MAGNETIC` or a :class:`HardMagnetic`) and ``T_op`` (K, default 293.15)
    set ``H_cB`` and ``B_r``. Limitations: no demagnetization below the knee.
    """

    l = Parameter("m", default=0.005, min=0, doc="Length in the direction of magnetization")
    area = Parameter("m^2", default=1e-4, min=0, doc="Pole face area")
    mu0 = Parameter("H/m", default=MU0, min=0, doc="Vacuum permeability")
    H_cB = Parameter("A/m", default=900e3, min=0, doc="Coercivity")
    B_r = Parameter("T", default=1.2, min=0, doc="Remanence")
    mu_r = Variable("1", doc="Recoil permeability")
    B_flux = Variable("T", doc="Flux density B, phi / area (the port is B)")

    def __init__(self, material=None, T_op=293.15, **kwargs):
        if material is not None:
            if not isinstance(material, HardMagnetic):
                if material not in HARD_MAGNETIC:
                    raise ModelError(f"PermanentMagnet: unknown material {material!r}. Use "
                                     f"one of {', '.join(HARD_MAGNETIC)} or a "
                                     "HardMagnetic(...) data set.")
                material = HARD_MAGNETIC[material]
            H_cB, B_r = material.at(T_op)
            kwargs = {"H_cB": H_cB, "B_r": B_r, **kwargs}
        super().__init__(**kwargs)

    def equations(self):
        return [self.mu_r == self.B_r / (self.mu0 * self.H_cB),
                self.B_flux == self.phi / self.area,
                self.mmf == self.phi * self.l / (self.mu0 * self.mu_r * self.area)
                - self.H_cB * self.l]


#: Leakage permeances per unit length and mu0, of MSL's ``Shapes.Leakage`` (after
#: Roters): shape -> function of the ratio t/r_i (ignored where it does not enter).
LEAKAGE_SHAPES = {
    "quarter_cylinder": lambda ratio: 0.52,
    "half_cylinder": lambda ratio: 0.26,
    "quarter_hollow_cylinder": lambda ratio: 2 * ca.log(1 + ratio) / math.pi,
    "half_hollow_cylinder": lambda ratio: ca.log(1 + ratio) / math.pi,
    "eighth_of_sphere": lambda ratio: 0.308,        # l is the radius
    "quarter_sphere": lambda ratio: 0.154,          # l is the radius
}


class Leakage(TwoPort):
    """Leakage flux tube of a standard shape in air (MSL's ``Shapes.Leakage``)::

        G_m == mu0 k(shape, ratio) l,   mmf == phi / G_m

    ``k`` per shape (constructor keyword ``shape``, see :data:`LEAKAGE_SHAPES`):
    quarter cylinder 0.52, half cylinder 0.26, quarter hollow cylinder
    ``2 ln(1 + t/r_i)/pi``, half hollow cylinder ``ln(1 + t/r_i)/pi``, eighth of a
    sphere 0.308 and quarter sphere 0.154 (there ``l`` is the radius). Constant: a
    leakage path that moves with an armature produces a force not modelled here.
    """

    l = Parameter("m", default=0.1, min=0, doc="Length across the flux (radius for spheres)")
    ratio = Parameter("1", default=1.0, min=0,
                      doc="Ratio t / r_i of the hollow shapes (thickness over inner radius)")
    mu0 = Parameter("H/m", default=MU0, min=0, doc="Vacuum permeability")
    G_m = Variable("H", doc="Permeance")

    def __init__(self, shape="quarter_cylinder", **kwargs):
        if shape not in LEAKAGE_SHAPES:
            raise ModelError(f"Leakage: unknown shape {shape!r}. Use one of "
                             f"{', '.join(LEAKAGE_SHAPES)}.")
        self._shape = shape
        super().__init__(**kwargs)

    def equations(self):
        return [self.G_m == self.mu0 * LEAKAGE_SHAPES[self._shape](self.ratio) * self.l,
                self.mmf * self.G_m == self.phi]


class _ForceTube(TwoPort, partial=True):
    """A flux tube of constant permeability one of whose dimensions ``x`` follows the
    translational flange ``rod`` relative to ``case`` (MSL's ``Shapes.Force``)::

        dx/dt == rod.v - case.v,   mmf == phi / G_m(x)
        F == mmf^2 / 2 dG_m/dx                      (force on the rod along +x)
        rod.f == -F,   rod.f + case.f == 0

    ``F`` is the derivative of the co-energy at constant mmf, equal to
    ``-phi^2/2 dR_m/dx`` at constant flux; power balance
    ``mmf dphi/dt + rod.f (rod.v - case.v) == d/dt(phi^2 / (2 G_m))``.
    """

    rod = Flange(doc="Moving flange (armature)")
    case = Flange(doc="Fixed flange (yoke)")
    mu_r = Parameter("1", default=1.0, min=0, doc="Relative permeability")
    mu0 = Parameter("H/m", default=MU0, min=0, doc="Vacuum permeability")
    x = Variable("m", start=1e-3, doc="The moving dimension")
    G_m = Variable("H", doc="Permeance")
    F = Variable("N", doc="Reluctance force on the rod along +x")

    def _permeance(self):
        """(G_m(x), dG_m/dx), expressions of ``self.x``."""
        raise NotImplementedError

    def equations(self):
        G, dG = self._permeance()
        return [der(self.x) == self.rod.v - self.case.v,
                self.G_m == G,
                self.mmf * self.G_m == self.phi,
                self.F == self.mmf ** 2 / 2 * dG,
                self.rod.f == -self.F,
                self.rod.f + self.case.f == 0]


class CuboidParallelFluxForce(_ForceTube):
    """Cuboid air gap whose length ``x`` (along the flux) moves with the rod (MSL's
    ``Shapes.Force.CuboidParallelFlux``)::

        G_m == mu0 mu_r a b / x,   F == -mmf^2 mu0 mu_r a b / (2 x^2)   (closes the gap)
    """

    a = Parameter("m", default=0.01, min=0, doc="Width of the cross-section")
    b = Parameter("m", default=0.01, min=0, doc="Height of the cross-section")

    def _permeance(self):
        k = self.mu0 * self.mu_r * self.a * self.b
        return k / self.x, -k / self.x ** 2


class CuboidOrthogonalFluxForce(_ForceTube):
    """Cuboid air gap of fixed length ``l`` whose overlap width ``x`` (across the flux)
    moves with the rod (MSL's ``Shapes.Force.CuboidOrthogonalFlux``)::

        G_m == mu0 mu_r x b / l,   F == mmf^2 mu0 mu_r b / (2 l)   (pulls into overlap)
    """

    l = Parameter("m", default=1e-3, min=0, doc="Gap length (along the flux)")
    b = Parameter("m", default=0.01, min=0, doc="Depth of the cross-section")

    def _permeance(self):
        k = self.mu0 * self.mu_r * self.b / self.l
        return k * self.x, k


class HollowCylinderAxialFluxForce(_ForceTube):
    """(Hollow) cylindrical air gap whose axial length ``x`` moves with the rod (MSL's
    ``Shapes.Force.HollowCylinderAxialFlux``; a plunger's working gap)::

        A == pi (r_o^2 - r_i^2),   G_m == mu0 mu_r A / x,   F == -mmf^2 mu0 mu_r A / (2 x^2)
    """

    r_i = Parameter("m", default=0.0, min=0, doc="Inner radius")
    r_o = Parameter("m", default=0.01, min=0, doc="Outer radius")

    def _permeance(self):
        k = self.mu0 * self.mu_r * math.pi * (self.r_o ** 2 - self.r_i ** 2)
        return k / self.x, -k / self.x ** 2
