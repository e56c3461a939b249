"""EMPS: the electro-mechanical positioning system of the nonlinear system-identification
benchmark (A. Janot, M. Gautier, M. Brunot, "Data Set and Reference Models of EMPS", 2019
Workshop on Nonlinear System Identification Benchmarks, Eindhoven). Results on its data
must cite them.

A prismatic axis driven by a DC motor through a ball screw, under the authors' digital
position control. The plant, on the load side (the authors' model)::

    M q'' = gtau vir - Fv q' - Fc sign(q') - offset

with ``gtau`` the drive gain (motor torque constant times amplifier gain, load side) and
``vir`` the controller output in V. The controller (dSPACE, ``Ts = 1 ms``) samples the
measured position ``q`` at the ticks ``t_k = k Ts`` and applies, held until the next
tick::

    qf_k  = (q_k + q_k-1) / 2,          dq_k = (qf_k - qf_k-1) / Ts
    vir_k = sat_vmax( kv (kp (qg_k - q_k) - dq_k) + pulse_k )

(a P loop on the position and a P loop on the filtered speed estimate; the saturation
after the added test pulse reproduces the logged ``vir`` best, see the data's README). The
reference position ``qg`` and the pulse ``pulse`` are external inputs
(``mt.simulate(..., inputs={"qg": (t, qg)})``, or measured inputs of an estimation).

Coulomb friction: ``sign(q')`` is replaced by ``tanh(q' / v_c)``, a smooth law that
estimation can differentiate, with a steep slope (``v_c = 1e-4 m/s`` by default: the
drive reverses through that band in a fraction of a millisecond, and ``Fc / v_c`` is a
damping 1000 times ``Fv``). Set ``v_c`` smaller for a closer approximation of the sign
(the estimation then needs more substeps per sample) or larger for a softer law. There
is no stuck mode: the load creeps at speeds below ``v_c``.

Parameter values: the drive and controller constants stored in the benchmark's files
(``gtau``, ``kp``, ``kv``, ``Ts``, the 10 V limit); the load parameters are the authors'
IDIM-LS estimates on ``DATA_EMPS`` (symmetric friction model).

The default experiment is a step of the reference from rest: the drive saturates, and the
load settles where the position loop balances the offset force,
``q = qg - offset / (gtau kv kp)`` (friction vanishes at rest).
"""

from __future__ import annotations

import casadi as ca

import mechatron as mt
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.models.registry import register

__all__ = ["EMPS", "REFERENCE", "REFERENCE_STD", "CONSTANTS", "final_position"]

AUTHORS = "Janot, Gautier, Brunot 2019 (EMPS benchmark), IDIM-LS on DATA_EMPS"
FILES = "EMPS benchmark data files (DATA_EMPS.mat)"

#: The authors' IDIM-LS estimates (symmetric friction) and their standard deviations.
REFERENCE = {"M": 95.1089, "Fv": 203.5034, "Fc": 20.3935, "offset": -3.1648}
REFERENCE_STD = {"M": 0.1085, "Fv": 1.146, "Fc": 0.1012, "offset": 0.0444}
#: Drive and controller constants stored in the data files.
CONSTANTS = {"gtau": 35.15065188248547, "kp": 160.18, "kv": 243.45, "Ts": 1e-3,
             "vir_max": 10.0}


class EMPS(mt.Component):
    """EMPS axis: rigid load with viscous and (smoothed) Coulomb friction and an offset
    force, driven through the drive gain by the sampled cascade position controller with
    a saturated output (see the module docstring)."""

    M = mt.Parameter("kg", default=REFERENCE["M"], min=0, doc="Moving mass, load side")
    Fv = mt.Parameter("N*s/m", default=REFERENCE["Fv"], min=0,
                      doc="Viscous friction coefficient")
    Fc = mt.Parameter("N", default=REFERENCE["Fc"], min=0, doc="Coulomb friction force")
    offset = mt.Parameter("N", default=REFERENCE["offset"], doc="Offset force")
    v_c = mt.Parameter("m/s", default=1e-4, min=0,
                       doc="Width of the Coulomb law, tanh(v / v_c) for sign(v)")
    gtau = mt.Parameter("N/V", default=CONSTANTS["gtau"], min=0,
                        doc="Drive gain: motor constant times amplifier gain, load side")
    kp = mt.Parameter("1/s", default=CONSTANTS["kp"], doc="Position loop gain")
    kv = mt.Parameter("V*s/m", default=CONSTANTS["kv"], doc="Speed loop gain")
    Ts = mt.Parameter("s", default=CONSTANTS["Ts"], min=0, doc="Controller sample time")
    vir_max = mt.Parameter("V", default=CONSTANTS["vir_max"], min=0,
                           doc="Limit of the controller output")
    qg = mt.Input("m", start=0.0, doc="Reference position")
    pulse = mt.Input("V", start=0.0,
                     doc="Test pulse added to the controller output (0 when absent)")
    q = mt.Variable("m", start=0.0, doc="Load position")
    v = mt.Variable("m/s", start=0.0, doc="Load velocity")
    vir = mt.Variable("V", start=0.0, doc="Controller output, held between ticks")
    q_prev = mt.Variable("m", start=0.0, doc="Position at the previous tick")
    qf_prev = mt.Variable("m", start=0.0, doc="Filtered position at the previous tick")
    force = mt.Variable("N", doc="Drive force gtau vir")
    friction = mt.Variable("N", doc="Friction force against the motion")

    def equations(self):
        qf = (self.q + self.q_prev) / 2
        dq = (qf - self.qf_prev) / self.Ts
        law = self.kv * (self.kp * (self.qg - self.q) - dq) + self.pulse
        return [mt.der(self.q) == self.v,
                self.force == self.gtau * self.vir,
                self.friction == self.Fv * self.v + self.Fc * ca.tanh(self.v / self.v_c),
                self.M * mt.der(self.v) == self.force - self.friction - self.offset,
                mt.sample(mt.Clock(self.Ts, 0.0),
                          output={self.vir: ca.fmin(ca.fmax(law, -self.vir_max),
                                                    self.vir_max)},
                          update={self.q_prev: self.q, self.qf_prev: qf})]


def final_position(qg: float, offset: float = REFERENCE["offset"],
                   gtau: float = CONSTANTS["gtau"], kp: float = CONSTANTS["kp"],
                   kv: float = CONSTANTS["kv"]) -> float:
    """Where the load comes to rest for a constant reference ``qg``: the position loop's
    force ``gtau kv kp (qg - q)`` balances the offset force (friction is zero at rest)."""
    return qg - offset / (gtau * kv * kp)


_QG = 0.01


def _equation(M, Fv, Fc, offset, v_c, gtau, kp, kv, Ts, vir_max, qg):
    model = EMPS(M=M, Fv=Fv, Fc=Fc, offset=offset, v_c=v_c, gtau=gtau, kp=kp, kv=kv,
                 Ts=Ts, vir_max=vir_max)
    model._name = "emps"
    model._starts["qg"] = mt.Start(qg, "none")     # the input's value when none is given
    return model


_PARAMS = {
    "M": ParameterInfo("kg", REFERENCE["M"], "Moving mass, load side", AUTHORS),
    "Fv": ParameterInfo("N*s/m", REFERENCE["Fv"], "Viscous friction coefficient", AUTHORS),
    "Fc": ParameterInfo("N", REFERENCE["Fc"], "Coulomb friction force", AUTHORS),
    "offset": ParameterInfo("N", REFERENCE["offset"], "Offset force", AUTHORS),
    "v_c": ParameterInfo("m/s", 1e-4, "Width of the smooth Coulomb law tanh(v / v_c)",
                         "chosen: reversal through the band in well under a sample"),
    "gtau": ParameterInfo("N/V", CONSTANTS["gtau"], "Drive gain (motor constant times "
                          "amplifier gain, load side)", FILES),
    "kp": ParameterInfo("1/s", CONSTANTS["kp"], "Position loop gain", FILES),
    "kv": ParameterInfo("V*s/m", CONSTANTS["kv"], "Speed loop gain", FILES),
    "Ts": ParameterInfo("s", CONSTANTS["Ts"], "Controller sample time (dSPACE)", FILES),
    "vir_max": ParameterInfo("V", CONSTANTS["vir_max"], "Controller output limit", FILES),
    "qg": ParameterInfo("m", _QG, "Reference position of the default experiment (a step "
                        "from rest)", "chosen: 10 mm, a move that saturates the drive briefly"),
}

ENTRY = register(ModelEntry(
    name="emps",
    description=("EMPS positioning axis (Janot, Gautier, Brunot 2019): rigid load with "
                 "viscous and Coulomb friction and an offset force under the authors' "
                 "sampled cascade position controller with a 10 V output limit."),
    parameters=_PARAMS,
    variants={"equation": _equation},
    outputs={"equation": {"q": "q", "v": "v", "vir": "vir", "force": "force"}},
    output_units={"q": "m", "v": "m/s", "vir": "V", "force": "N"},
    experiment=Experiment(t_stop=4.0, rtol=1e-8, atol=1e-11),
    # at rest the position loop balances the offset force
    expected={"q": final_position(_QG),
              "vir": REFERENCE["offset"] / CONSTANTS["gtau"]},
    expected_tolerance=1e-6,
    tags=("electromechanical", "servo", "discrete", "friction", "real data",
          "estimation"),
))
