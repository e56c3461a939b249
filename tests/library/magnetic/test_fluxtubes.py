"""Flux tubes from geometry and material: a coil on saturating iron against an independent
SciPy model of the nonlinear inductor, a B(H) table, the shapes' permeances, the
permanent magnet's load line, leakage permeances, and the reluctance force of moving
tubes against the work-energy theorem."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

import mechatron as mt
from mechatron.errors import ModelError
from mechatron.library import electrical as el
from mechatron.library import magnetic as mag
from mechatron.library import translational as tr

MU0 = 4e-7 * math.pi
N, R_COIL, V = 200, 2.0, 12.0           # coil turns, resistance, supply
L_FE, A_FE = 0.1, 1e-4                  # iron path


def coil_on(tube):
    """A DC voltage through a resistor onto a coil of N turns around ``tube``."""
    m = mt.System("coil")
    m.add("src", el.DCVoltageSource(V=V))
    m.add("r", el.Resistor(R=R_COIL))
    m.add("coil", mag.ElectromagneticConverter(N=N))
    m.add("core", tube)
    m.add("ground", el.ElectricalReference())
    m.add("mref", mag.MagneticReference())
    m.connect(m.src.p, m.r.p)
    m.connect(m.r.n, m.coil.p)
    m.connect(m.coil.n, m.src.n, m.ground.port)
    m.connect(m.coil.B, m.core.A)
    m.connect(m.core.B, m.coil.A, m.mref.port)
    return m


def nonlinear_inductor(H_of_B, t):
    """Independent model: the flux as the state, N dphi/dt = V - R i with the current
    from Ampere's law, N i = H(phi / A) l."""
    def rhs(_, y):
        i = H_of_B(y[0] / A_FE) * L_FE / N
        return [(V - R_COIL * i) / N]
    return solve_ivp(rhs, (0, t[-1]), [0.0], t_eval=t, method="LSODA", rtol=1e-11,
                     atol=1e-14).y[0]


@pytest.mark.parametrize("name", ["M350_50A", "Steel_9SMnPb28"])
def test_a_coil_saturates_its_core_as_an_independent_model_does(name):
    mat = mag.SOFT_MAGNETIC[name]

    def H_of_B(B):
        return B / (MU0 * mat.mu_r(B))
    t = np.linspace(0.0, 0.5, 501)
    res = mt.simulate(coil_on(mag.SaturatingReluctance(material=name, l=L_FE, area=A_FE)),
                      0.5, t_out=t, rtol=1e-10, atol=1e-12)
    phi = nonlinear_inductor(H_of_B, t)
    np.testing.assert_allclose(res["core.phi"], phi, rtol=1e-6, atol=1e-12)
    # driven into saturation: the final flux density is beyond the permeability peak and
    # the current is the resistor's limit V/R
    B_end = res.final("core.B_flux")
    assert B_end > mat.B_max
    assert res.final("r.i") == pytest.approx(V / R_COIL, rel=1e-6)
    assert H_of_B(B_end) * L_FE == pytest.approx(N * V / R_COIL, rel=1e-6)
    assert res.final("core.mu_r") == pytest.approx(mat.mu_r(B_end), rel=1e-9)


def test_a_bh_table_follows_the_sampled_curve_and_saturates_with_mu0():
    mat = mag.SOFT_MAGNETIC["M350_50A"]
    B = np.linspace(0.0, 1.9, 400)
    H = B / (MU0 * mat.mu_r(B))
    table = np.column_stack([H, B])
    t = np.linspace(0.0, 0.5, 101)
    res = mt.simulate(coil_on(mag.SaturatingReluctance(table=table, l=L_FE, area=A_FE)),
                      0.5, t_out=t, rtol=1e-10, atol=1e-12)

    def H_of_B(b):          # the table's own interpolation, saturating beyond it
        b = abs(b)
        return np.interp(b, B, H) if b <= B[-1] else H[-1] + (b - B[-1]) / MU0
    phi = nonlinear_inductor(H_of_B, t)
    np.testing.assert_allclose(res["core.phi"], phi, rtol=1e-6, atol=1e-12)
    # the final point lies beyond the table's last row: the vacuum slope is used
    assert res.final("core.B_flux") > 1.9 or res.final("core.H") < H[-1]
    with pytest.raises(ModelError, match=r"first \(0, 0\)"):
        mag.SaturatingReluctance(table=[(1.0, 0.1), (2.0, 0.2)])
    with pytest.raises(ModelError, match="unknown soft-magnetic material 'Unobtainium'"):
        mag.Cuboid(material="Unobtainium")


def mmf_across(tube, F=100.0):
    m = mt.System("tube")
    m.add("src", mag.MmfSource(F=F))
    m.add("tube", tube)
    m.add("mref", mag.MagneticReference())
    m.connect(m.src.B, m.tube.A)
    m.connect(m.tube.B, m.src.A, m.mref.port)
    return m


@pytest.mark.parametrize("tube,permeance", [
    (mag.Cuboid(l=0.02, a=0.01, b=0.03, mu_r_const=500.0),
     MU0 * 500 * 0.01 * 0.03 / 0.02),
    (mag.HollowCylinderAxialFlux(l=0.02, r_i=0.004, r_o=0.01, mu_r_const=800.0),
     MU0 * 800 * math.pi * (0.01 ** 2 - 0.004 ** 2) / 0.02),
    (mag.HollowCylinderAxialFlux(l=0.02, r_o=0.01, alpha=math.pi / 2),
     MU0 * (math.pi / 4) * 0.01 ** 2 / 0.02),
    (mag.HollowCylinderRadialFlux(l=0.03, r_i=0.01, r_o=0.02, mu_r_const=2.0),
     MU0 * 2 * 2 * math.pi * 0.03 / math.log(2.0)),
    (mag.Leakage(shape="quarter_cylinder", l=0.1), MU0 * 0.52 * 0.1),
    (mag.Leakage(shape="half_hollow_cylinder", l=0.1, ratio=1.5),
     MU0 * 0.1 * math.log(2.5) / math.pi),
])
def test_permeance_from_geometry(tube, permeance):
    res = mt.simulate(mmf_across(tube), 1e-3)
    assert res.final("tube.phi") == pytest.approx(100.0 * permeance, rel=1e-12)


def test_radial_flux_tube_is_the_integral_of_thin_shells():
    # series of thin cylindrical shells: R = integral dr / (mu0 2 pi r l)
    r = np.linspace(0.01, 0.02, 20001)
    R = np.trapezoid(1 / (MU0 * 2 * math.pi * r * 0.03), r)
    res = mt.simulate(mmf_across(mag.HollowCylinderRadialFlux(l=0.03, r_i=0.01, r_o=0.02)),
                      1e-3)
    assert res.final("tube.phi") == pytest.approx(100.0 / R, rel=1e-8)


def magnet_with_gap(magnet, g):
    m = mt.System("pm")
    m.add("pm", magnet)
    m.add("gap", mag.AirGapReluctance(g=g, area=1e-4))
    m.add("mref", mag.MagneticReference())
    m.connect(m.pm.B, m.gap.A)
    m.connect(m.gap.B, m.pm.A, m.mref.port)
    return m


def test_permanent_magnet_load_line():
    l, A = 0.005, 1e-4
    H_c, B_r = 900e3, 1.2
    mu_r = B_r / (MU0 * H_c)
    for g in (1e-9, 1e-3):
        res = mt.simulate(magnet_with_gap(mag.PermanentMagnet(l=l, area=A), g), 1e-3)
        # magnet (source H_c l behind its recoil reluctance) in series with the gap
        phi = H_c * l / (l / (MU0 * mu_r * A) + g / (MU0 * A))
        assert res.final("pm.phi") == pytest.approx(phi, rel=1e-9)
    assert res.final("pm.B_flux") < B_r                    # the gap demagnetizes it
    # short circuit: the remanence; material data with its temperature coefficient
    res = mt.simulate(magnet_with_gap(mag.PermanentMagnet(material="NdFeB", T_op=373.15,
                                                          l=l, area=A), 1e-12), 1e-3)
    assert res.final("pm.B_flux") == pytest.approx(1.2 * (1 - 0.001 * 80), rel=1e-6)


def plunger(tube, F0, m_kg, x0, v0=0.0):
    """A constant mmf across a moving tube whose rod carries a free mass."""
    m = mt.System("plunger")
    m.add("src", mag.MmfSource(F=F0))
    m.add("tube", tube)
    m.add("mref", mag.MagneticReference())
    m.add("mass", tr.Mass(m=m_kg, v=v0))
    m.add("fixed", tr.TranslationalReference())
    m.connect(m.src.B, m.tube.A)
    m.connect(m.tube.B, m.src.A, m.mref.port)
    m.connect(m.tube.rod, m.mass.port)
    m.connect(m.tube.case, m.fixed.port)
    return m


def test_moving_gap_force_does_the_work_of_the_coenergy():
    # constant mmf F0: the force F = F0^2/2 dG/dx does the work of the co-energy,
    # 1/2 m v^2 = F0^2/2 (G(x) - G(x0)); the gap closes
    a = b = 0.01
    x0, F0, m_kg = 2e-3, 500.0, 0.02
    t = np.linspace(0.0, 3e-3, 201)           # it would close the gap in about 4 ms
    tube = mag.CuboidParallelFluxForce(a=a, b=b, x=x0)
    res = mt.simulate(plunger(tube, F0, m_kg, x0), 3e-3, t_out=t, rtol=1e-11, atol=1e-14)
    x, v = res["tube.x"], res["mass.v"]
    G = MU0 * a * b / x
    assert x[-1] < 0.75 * x0
    work = F0 ** 2 / 2 * (G - G[0])
    # to the integration error: the states are held to 1e-14 m and 1e-11 relative
    np.testing.assert_allclose(0.5 * m_kg * v ** 2, work, rtol=0, atol=1e-7 * work[-1])
    np.testing.assert_allclose(res["tube.F"], -F0 ** 2 / 2 * MU0 * a * b / x ** 2,
                               rtol=1e-9)


def test_orthogonal_and_cylindrical_force_tubes():
    # overlap width x across the flux: a constant force, x = x0 + F t^2 / (2 m)
    l, b, F0, m_kg = 1e-3, 0.02, 400.0, 0.01
    F = F0 ** 2 / 2 * MU0 * b / l
    res = mt.simulate(plunger(mag.CuboidOrthogonalFluxForce(l=l, b=b, x=1e-3), F0, m_kg,
                              1e-3), 0.01, t_out=np.linspace(0, 0.01, 11), rtol=1e-11,
                      atol=1e-14)
    np.testing.assert_allclose(res["tube.x"], 1e-3 + F * res.t ** 2 / (2 * m_kg),
                               rtol=1e-9)
    # a cylindrical plunger gap: F against the finite-difference co-energy derivative
    tube = mag.HollowCylinderAxialFluxForce(r_i=0.002, r_o=0.006, x=1.5e-3)
    res = mt.simulate(plunger(tube, 300.0, 0.05, 1.5e-3), 1e-3,
                      t_out=np.linspace(0, 1e-3, 5), rtol=1e-11, atol=1e-14)
    x = res["tube.x"][-1]

    def coenergy(xx):
        return 0.5 * 300.0 ** 2 * MU0 * math.pi * (0.006 ** 2 - 0.002 ** 2) / xx
    dW = (coenergy(x * (1 + 1e-6)) - coenergy(x * (1 - 1e-6))) / (2e-6 * x)
    assert res["tube.F"][-1] == pytest.approx(dW, rel=1e-8)
