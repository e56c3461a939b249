"""Parameter estimation: weighted least squares over several experiments, exact derivatives.

The problem
-----------
Free parameters ``theta`` (model parameters by path, optional output offsets, optional
initial states per experiment) minimize ::

    S(theta) = sum_e sum_l sum_k ( (y_l(t_k; theta) + b_l - ym_l[k]) / sigma_l )^2

over experiments ``e``, measured outputs ``l`` and samples ``k``, where ``y`` is the model
output on the sample grid (:class:`~mechatron.estimation.discretize.Trajectory`: Radau IIA
substeps, measured inputs held between samples), ``b_l`` an optional sensor offset and
``sigma_l`` the output's noise level (given by the experiment; otherwise the signal's
peak-to-peak range, so that signals of different units count alike).

The solver is Levenberg-Marquardt (Marquardt's diagonal scaling, Nielsen's damping
update, steps clipped to the bounds) on the exact Jacobian ``dr/dtheta`` from the forward
sensitivities of the discrete trajectory (:mod:`.discretize`): each trial point costs one
simulation with sensitivities, and the normal equations are only ``q x q``. The decision
variables are scaled by ``scale`` (default: the starting value) and a step changes none
by more than ``max_step`` scales (a trust region: from a start off by a factor of 3 a
full Gauss-Newton step can jump to a bound and into another valley). With
``log_space=True`` positive parameters move in log space instead.

Uncertainty
-----------
With ``J`` the Jacobian at the optimum, ``n`` residuals and ``q`` free parameters, the
white-noise covariance is ``C = s^2 (J^T J)^-1`` with ``s^2 = S / (n - q)`` and the 95%
interval ``theta_i -/+ t_{0.975, n-q} sqrt(C_ii)``. Residuals of dynamic models are
rarely white, so by default (``covariance="hac"``) the covariance is the Newey-West
sandwich with a Bartlett lag window and the interval uses the fixed-b critical value
(:mod:`.uncertainty`, which also says why not a bootstrap); both are reported. The
correlation matrix is ``C_ij / sqrt(C_ii C_jj)``. Correlated residuals and poorly
identified parameters (with their correlation partners) are warned about
(``result.warnings``); profile-likelihood intervals are computed on request. All assume
a model that can describe the data.

Fit
---
``NRMSE = ||ym - y|| / ||ym - mean(ym)||`` per experiment and signal (0 is a perfect fit;
MATLAB's ``goodnessOfFit`` 'NRMSE' cost; the System Identification Toolbox's fit percent
is ``100 (1 - NRMSE)``).
"""

from __future__ import annotations

import contextlib
import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import mechatron as mt
from mechatron._io import save_figure
from mechatron.compiler.compiled import CompiledModel
from mechatron.errors import DataError, ParameterError, SimulationError
from mechatron.estimation.bounds import at_bounds, check_bounds, describe_at_bounds
from mechatron.estimation.data import unit_factor
from mechatron.estimation.delays import prepare_delays, shift
from mechatron.estimation.expressions import parse_output
from mechatron.estimation.native import compiler
from mechatron.estimation.uncertainty import (RHO_WARN, acf, bartlett_critical, diagnose,
                                              hac_covariance, profile_interval)
from mechatron.estimation.discretize import (Trajectory, check_model, choose_substeps,
                                             fastest_time_constant, grid_fits, noise_floor,
                                             noise_level)

log = logging.getLogger(__name__)


@contextlib.contextmanager
def passing_only(keep):
    """While inside, the estimator's log passes on only the records for which
    ``keep(record)`` is true (the multi-start holds back each start's warnings, the
    command line the ones its summary prints itself)."""
    log.addFilter(keep)
    try:
        yield
    finally:
        log.removeFilter(keep)

__all__ = ["FreeParameter", "EstimationProblem", "EstimationResult", "estimate",
           "validation_errors"]

#: Substeps per simulation from which ``jit="auto"`` compiles the step functions.
JIT_STEPS = 4000


@dataclass
class FreeParameter:
    """A parameter to estimate: model path, starting value, bounds and scale (SI)."""

    name: str
    initial: float | None = None
    min: float = -math.inf
    max: float = math.inf
    scale: float | None = None

    def __post_init__(self):
        check_bounds(self, "free parameter")


def _as_free(spec) -> FreeParameter:
    if isinstance(spec, FreeParameter):
        return spec
    if isinstance(spec, str):
        return FreeParameter(spec)
    if isinstance(spec, dict):
        return FreeParameter(**spec)
    raise TypeError(f"a free parameter is a name, a dict or a FreeParameter, got {spec!r}")


def compiled(model) -> CompiledModel:
    return model if isinstance(model, CompiledModel) else mt.compile_model(model)



#: The most Radau substeps per sample an estimation problem takes (the step functions
#: unroll them).
MAX_SUBSTEPS = 1000


class EstimationProblem:
    """Model, experiments, what is free, and how the data bind to the model.

    Parameters
    ----------
    model : Component or CompiledModel
        An ODE model, with or without events: sampled blocks, discrete states,
        saturations and other time events are exact; state events need ``smooth``
        (see :mod:`.discretize`).
    experiments : list of Experiment
    free : list of str, dict or FreeParameter
        Parameters to estimate (paths as in ``CompiledModel.param_names``).
    inputs : dict label -> parameter path
        Which model parameter each measured input drives.
    outputs : dict label -> variable path
        Which logged model variable each measured output is compared with;
        ``"rate(path)"`` compares the variable's increment over each sample interval
        divided by the interval (a speed computed from encoder counts: constant encoder
        offsets cancel, quantization errors stay bounded).
    fixed : dict path -> value
        Parameter values for every experiment (an experiment's ``params`` override them).
    offsets : list of labels
        Outputs that get an estimated constant sensor offset (shared by the experiments).
    free_x0 : list of state names
        Initial states estimated per experiment.
    input_delays : dict label -> float
        Transport delays (s) of measured inputs: the data are shifted (see
        :mod:`.delays`). A :class:`~mechatron.library.blocks.Delay` block on a measured
        input of ``model`` adds its delay here by itself.
    per_experiment : dict experiment name -> list of str, dict or FreeParameter
        Parameters estimated separately for each experiment named (an initial position
        or a sensor offset per run), next to the shared ``free`` ones; the decision
        variable is ``"<experiment>:<parameter>"``. The start value defaults to the
        experiment's ``params``, then to ``fixed`` and the model's value.
    substeps : int or None
        Radau substeps per sample; ``None`` chooses, per experiment, the fewest whose
        step-doubling error estimate at the starting values is below ``substep_tol``
        (at most ``max_substeps``, itself at most :data:`MAX_SUBSTEPS`); the estimate is
        checked again at the solution (see :meth:`discretization_error`).
    substep_tol : float
        Tolerance of that estimate: ``||(y_m - y_2m) / sigma||_2`` over the samples and
        outputs of an experiment, ``sigma`` the noise level of each output (given, else
        estimated from the data by :func:`~.discretize.noise_level`). A systematic error
        ``e`` moves the weighted least-squares estimates by at most ``||e / sigma||``
        standard errors (white-noise metric), so the default 0.1 bounds the bias the
        discretization adds to a tenth of the statistical uncertainty.
    jit : bool or "auto"
        Compile the step functions to native code (see :mod:`.native`).
    smooth : float or None
        Width of the smooth approximation of state events (relations that switch with
        the continuous states), ``tanh(distance / smooth)`` for their modes; None refuses
        such models (see :mod:`.discretize`).
    validation : list of Experiment
        Experiments not fitted: :func:`estimate` simulates them with the estimates and
        reports their errors (``EstimationResult.validation``).
    """

    def __init__(self, model, experiments, free, *, inputs=None, outputs=None, fixed=None,
                 offsets=(), free_x0=(), per_experiment=None, input_delays=None,
                 substeps=None, max_substeps: int = 400,
                 step_ratio: float = 4.0, jit="auto", smooth=None, validation=(),
                 substep_tol: float = 0.1):
        if not (isinstance(substep_tol, (int, float)) and math.isfinite(substep_tol)
                and substep_tol > 0):
            raise ParameterError(f"estimation: substep_tol must be a number > 0, got "
                                 f"{substep_tol!r}.")
        if not (isinstance(max_substeps, (int, np.integer)) and
                1 <= max_substeps <= MAX_SUBSTEPS):
            raise ParameterError(f"estimation: max_substeps must be a whole number from 1 "
                                 f"to {MAX_SUBSTEPS}, got {max_substeps!r}.")
        self.substep_tol = float(substep_tol)
        self.max_substeps = int(max_substeps)
        for m in (substeps if isinstance(substeps, (list, tuple)) else [substeps]):
            if m is not None and (isinstance(m, bool) or not isinstance(m, (int, np.integer))
                                  or m < 1):
                raise ParameterError(f"estimation: substeps must be a whole number >= 1 "
                                     f"(or None to choose them), got {substeps!r}.")
            if m is not None and m > MAX_SUBSTEPS:
                raise ParameterError(f"estimation: substeps = {m} per sample is more than "
                                     f"the {MAX_SUBSTEPS} the step functions are built for "
                                     "(the generated code grows with them: 1e5 gave 80 MB "
                                     "of C); resample the data or give fewer substeps, or "
                                     "none to choose them.")
        self.cm, found = prepare_delays(model, dict(inputs or {}))
        self.input_delays = {**found, **dict(input_delays or {})}
        check_model(self.cm, "estimation")
        cm = self.cm
        self.experiments = list(experiments)
        if not self.experiments:
            raise DataError("no experiment given; an estimation needs measured data.")
        self.free = [_as_free(f) for f in free]
        self.inputs = dict(inputs or {})
        self.outputs = dict(outputs or {})
        self.fixed = dict(fixed or {})
        self.offsets = list(offsets)
        self.free_x0 = list(free_x0)
        self.per_experiment = {k: [_as_free(f) for f in v]
                               for k, v in dict(per_experiment or {}).items()}
        self.jit = jit
        self.smooth = smooth
        self.validation = list(validation)
        self._init = dict(inputs=self.inputs, outputs=self.outputs, fixed=self.fixed,
                          offsets=self.offsets, free_x0=self.free_x0,
                          per_experiment=self.per_experiment,
                          input_delays=self.input_delays,
                          max_substeps=max_substeps, step_ratio=step_ratio, jit=jit,
                          smooth=smooth, substep_tol=substep_tol)
        pindex = {n: i for i, n in enumerate(cm.param_names)}
        problems = []
        for f in self.free:
            if f.name not in pindex:
                problems.append(f"free parameter '{f.name}' is not a parameter of model "
                                f"'{cm.name}': {cm.not_a_parameter(f.name)}")
        for lab, path in self.inputs.items():
            if path not in pindex:
                problems.append(f"input '{lab}' drives '{path}', which is not a parameter "
                                f"of model '{cm.name}'.")
        self._outspec = {}
        for lab, spec in self.outputs.items():
            try:
                self._outspec[lab] = parse_output(spec, cm.names, f"output '{lab}'")
            except DataError as exc:
                problems.append(str(exc).replace("the model does not log",
                                                 f"the model '{cm.name}' does not log"))
        for s in self.free_x0:
            if s not in cm.state_names:
                problems.append(f"free initial state '{s}' is not a state of '{cm.name}' "
                                f"(states: {', '.join(cm.state_names)}).")
        exp_names = [e.name for e in self.experiments]
        shared = {f.name for f in self.free}
        for ename, fs in self.per_experiment.items():
            if ename not in exp_names:
                problems.append(f"per-experiment parameters for '{ename}', which is not "
                                f"an experiment (experiments: {', '.join(exp_names)}).")
            elif exp_names.count(ename) > 1:
                problems.append(f"per-experiment parameters for '{ename}': "
                                f"{exp_names.count(ename)} experiments have that name; "
                                "name them apart.")
            for f in fs:
                if f.name not in pindex:
                    problems.append(f"experiment '{ename}': free parameter '{f.name}' is "
                                    f"not a parameter of model '{cm.name}'.")
                elif f.name in shared:
                    problems.append(f"experiment '{ename}': '{f.name}' is free both per "
                                    "experiment and shared; choose one.")
        for lab in self.offsets:
            if lab not in self.outputs:
                problems.append(f"offset for '{lab}', which is not a measured output.")
        if problems:
            raise ParameterError(" ".join(problems), problems=problems, path=cm.name)
        self.base = cm.parameter_vector(self.fixed)
        for f in self.free:
            i = pindex[f.name]
            if f.initial is None:
                f.initial = float(self.base[i])
            lo, hi = cm.param_bounds[i] if cm.param_bounds else (None, None)
            if lo is not None and f.min < lo:
                f.min = lo
            if hi is not None and f.max > hi:
                f.max = hi
            if not (f.min <= f.initial <= f.max):
                raise ParameterError(f"free parameter '{f.name}': starting value "
                                     f"{f.initial:g} is outside [{f.min:g}, {f.max:g}].",
                                     path=f.name)
            if f.scale is None:
                f.scale = abs(f.initial) or 1.0
        for e in self.experiments:
            for f in self.per_experiment.get(e.name, []):
                i = pindex[f.name]
                if f.initial is None:
                    f.initial = float(e.params.get(f.name, self.base[i]))
                lo, hi = cm.param_bounds[i] if cm.param_bounds else (None, None)
                f.min = max(f.min, lo) if lo is not None else f.min
                f.max = min(f.max, hi) if hi is not None else f.max
                if not (f.min <= f.initial <= f.max):
                    raise ParameterError(f"experiment '{e.name}': free parameter "
                                         f"'{f.name}': starting value {f.initial:g} is "
                                         f"outside [{f.min:g}, {f.max:g}].", path=f.name)
                if f.scale is None:
                    f.scale = abs(f.initial) or 1.0
        # the decision vector: parameters, offsets, per-experiment initial states and
        # parameters
        self.names = [f.name for f in self.free] + [f"offset:{lab}" for lab in self.offsets]
        self.names += [f"{e.name}:{s}" for e in self.experiments for s in self.free_x0]
        self.names += [f"{e.name}:{f.name}" for e in self.experiments
                       for f in self.per_experiment.get(e.name, [])]
        self._bind(substeps, max_substeps, step_ratio)

    # ------------------------------------------------------------------------------------
    def _bind(self, substeps, max_substeps, step_ratio) -> None:
        """Check every experiment against the model and build its trajectory function."""
        cm = self.cm
        pindex = {n: i for i, n in enumerate(cm.param_names)}
        self.bound = []
        problems = []
        for e in self.experiments:
            # an input the experiment lacks is allowed when it sets the parameter the
            # input drives to a constant (params = { pulse = 0 }: no pulses in this run)
            missing = [lab for lab in self.inputs
                       if lab not in e.inputs and self.inputs[lab] not in e.params]
            if not any(lab in e.outputs for lab in self.outputs):
                missing += list(self.outputs)
            if missing:
                problems.append(f"{e.source}: experiment '{e.name}' lacks signal(s) "
                                f"{', '.join(missing)} (it has "
                                f"{', '.join([*e.inputs, *e.outputs])}).")
                continue
            in_labels = [lab for lab in self.inputs if lab in e.inputs]
            out_labels = [lab for lab in self.outputs if lab in e.outputs]
            try:
                fin = [unit_factor(e.units.get(lab, ""),
                                   cm.param_units[pindex[self.inputs[lab]]],
                                   e.where(lab)) for lab in in_labels]
                fout = [unit_factor(e.units.get(lab, ""), self._output_unit(lab),
                                    e.where(lab)) for lab in out_labels]
            except DataError as exc:
                problems.append(str(exc))
                continue
            U = np.array([e.inputs[lab] * f for lab, f in zip(in_labels, fin)]).reshape(
                len(in_labels), e.n)
            try:
                for j, lab in enumerate(in_labels):
                    if lab in self.input_delays:
                        U[j] = shift(U[j], e.t, self.input_delays[lab], e.where(lab))
            except DataError as exc:
                problems.append(str(exc))
                continue
            Ym = np.array([e.outputs[lab] * f for lab, f in zip(out_labels, fout)])
            sig, noise, floor = [], [], []
            for lab, f, y in zip(out_labels, fout, Ym):
                s = e.sigma.get(lab)
                noise.append(s * f if s else noise_level(y))
                # the least level such data can show; none where the noise is given
                floor.append(0.0 if s else noise_floor(y))
                s = s * f if s else float(np.ptp(y)) or 1.0
                sig.append(s)
            pe = self.base.copy()
            for key, val in e.params.items():
                if key not in pindex:
                    problems.append(f"{e.source}: experiment '{e.name}' sets '{key}', "
                                    f"which is not a parameter of '{cm.name}'.")
                    continue
                pe[pindex[key]] = val
            x0 = np.array(cm.x_start, dtype=float)[:cm.nx].copy()
            for key, val in e.x0.items():
                if key not in cm.state_names:
                    problems.append(f"{e.source}: experiment '{e.name}' gives initial "
                                    f"state '{key}', not a state of '{cm.name}'.")
                    continue
                x0[cm.state_names.index(key)] = val
            m = substeps[len(self.bound)] if isinstance(substeps, (list, tuple)) \
                else substeps
            auto = m is None
            if auto:
                try:
                    # the time constants' rule refuses a rate the model cannot follow
                    self._substeps(e, pe, x0, U, in_labels, self._start_values(),
                                   step_ratio, max_substeps)
                except DataError as exc:
                    problems.append(str(exc))
                    continue
            if not self.bound:
                self._check_informative()        # before the first (compiled) trajectory
            paths = list(dict.fromkeys(p for lab in out_labels
                                       for p in self._outspec[lab].paths))
            rows = [[paths.index(p) for p in self._outspec[lab].paths] for lab in out_labels]
            b = dict(exp=e, U=U, Ym=Ym, sigma=np.array(sig), noise=np.array(noise),
                     floor_ratio=np.array(floor) / np.array(noise), p=pe,
                     x0=x0, out_labels=out_labels, out_rows=rows, in_labels=in_labels,
                     in_index=[pindex[self.inputs[lab]] for lab in in_labels],
                     out_index=[cm.names.index(p) for p in paths], auto=auto)
            traj = None
            if auto:
                pp = pe.copy()
                for name, v in self._start_values().items():
                    pp[pindex[name]] = v
                try:
                    m, err, traj = self._choose_by_error(b, pp, x0, 1)
                except (DataError, SimulationError) as exc:
                    problems.append(str(exc))
                    continue
                b["error_initial"] = err
                b["substeps_initial"] = m
            if traj is None:
                traj = self._trajectory(b, m)
            try:
                traj.check_ticks(pe)
            except DataError as exc:
                problems.append(f"{e.source}: experiment '{e.name}': {exc}")
                continue
            b.update(traj=traj, substeps=m)
            self.bound.append(b)
        if problems:
            raise DataError(" ".join(problems), problems=problems)
        self._build_residual()

    def _trajectory(self, b, m: int) -> Trajectory:
        """Experiment ``b``'s trajectory with ``m`` substeps per sample, in native code
        when its runs are long enough for it (`_use_jit`): the step-doubling checks and
        the fit run alike, and the trajectory the checks choose serves the fit."""
        e = b["exp"]
        return Trajectory(self.cm, e.t, b["in_index"], b["out_index"], substeps=int(m),
                          hold=e.hold, jit=self._use_jit(e.n * m), smooth=self.smooth)

    def _signals(self, b, Y) -> list:
        """The model signals compared with the data (rates as increments per sample)."""
        out = []
        dt = np.diff(b["exp"].t)
        for r, lab in enumerate(b["out_labels"]):
            y, _ = self._label_output(b, r, Y)
            out.append(np.diff(y) / dt if self._outspec[lab][1] == "rate" else y)
        return out

    def _error_between(self, b, p, x0, coarse, fine) -> float:
        """``||(y_coarse - y_fine) / noise||_2`` over the samples and outputs of ``b``
        (inf when a Radau step does not converge or the result is not finite)."""
        try:
            Yc, _ = coarse(p, x0, b["U"])
            Yf, _ = fine(p, x0, b["U"])
        except SimulationError:
            return math.inf
        total = sum(float(np.sum(((a - c) / n) ** 2)) for a, c, n in
                    zip(self._signals(b, Yc), self._signals(b, Yf), b["noise"]))
        return math.sqrt(total) if math.isfinite(total) else math.inf

    def _choose_by_error(self, b, p, x0, start: int, std_scale: float = 1.0):
        """``(m, error, trajectory)``: the fewest substeps ``m >= start`` whose
        step-doubling estimate (``m`` against ``2m`` substeps, at the parameter vector
        ``p``) is at most ``substep_tol``. Doubles from the first ``m >= start`` that
        puts every clock tick on a substep end, then tries a count between the last two
        (predicted from the observed order, checked against the ``2m`` solution)."""
        e = b["exp"]
        top = self.max_substeps
        base = int(start)
        while base <= top and not grid_fits(self.cm, e.t, base, p, b["in_index"]):
            base += 1
        if base > top:
            base = int(start)                  # check_ticks reports it
        cache = {}

        def traj(k):
            if k not in cache:
                cache[k] = self._trajectory(b, k)
            return cache[k]

        tol = self.substep_tol * std_scale
        errs = {}
        m = base
        while True:
            errs[m] = self._error_between(b, p, x0, traj(m), traj(2 * m))
            if errs[m] <= tol:
                break
            if 2 * m > top:
                shown = "did not converge" if math.isinf(errs[m]) else \
                    f"{errs[m]:.3g} standard errors"
                raise DataError(
                    f"{e.where('t')}: experiment '{e.name}': with {m} Radau substeps per "
                    f"sample the discretization error estimate (against {2 * m}) is "
                    f"{shown}, above the tolerance substep_tol = {self.substep_tol:g}"
                    + (f" (x {std_scale:.3g}, the fit's standard errors over the noise's)"
                       if std_scale != 1.0 else "") + f"; {2 * m} "
                    f"would exceed max_substeps = {top} (at most {MAX_SUBSTEPS}). "
                    f"Measure faster, raise max_substeps, give substeps yourself, or "
                    f"loosen substep_tol (the estimates may then be biased by the "
                    f"discretization).", path=e.where("t"))
            m *= 2
        lo = m // 2
        if lo >= base and lo in errs and math.isfinite(errs[lo]) and errs[lo] > tol \
                and m - lo > 1:
            order = math.log2(errs[lo] / errs[m]) if errs[m] > 0 else 5.0
            order = min(max(order, 1.0), 6.0)
            mc = math.ceil(lo * (errs[lo] / (0.7 * tol)) ** (1.0 / order))
            while mc < m and not grid_fits(self.cm, e.t, mc, p, b["in_index"]):
                mc += 1
            if lo < mc < m:
                err = self._error_between(b, p, x0, traj(mc), traj(2 * m))
                if err <= tol:
                    return mc, err, traj(mc)
        return m, errs[m], traj(m)

    def discretization_error(self, theta) -> dict:
        """Step-doubling estimate of the discretization error of each experiment at
        ``theta`` (its substeps against twice as many), in standard errors:
        ``{experiment: error}``; compare with ``substep_tol``."""
        theta = np.asarray(theta, dtype=float)
        out = {}
        for b in self.bound:
            p, x0 = self._point(b, theta)
            fine = self._trajectory(b, 2 * b["substeps"])
            out[b["exp"].name] = self._error_between(b, p, x0, b["traj"], fine)
        return out

    def _check_informative(self) -> None:
        """A :class:`DataError` when every measured output of every experiment is zero:
        such data carry no information, and building the problem would only cost time."""
        if all(e.outputs and all(not np.any(np.asarray(v, dtype=float))
                                 for v in e.outputs.values()) for e in self.experiments):
            names = ", ".join(f"'{e.name}' ({e.source})" for e in self.experiments)
            raise DataError(f"estimation: every measured output of {names} is zero: such "
                            "data hold no information about the parameters. Is a sensor "
                            "not connected, or are the wrong columns read?")

    def _use_jit(self, steps: int) -> bool:
        """Native code for long experiments (``jit="auto"``: at least JIT_STEPS substeps
        per simulation, and a C compiler present)."""
        if self.jit == "auto":
            return steps >= JIT_STEPS and compiler() is not None
        return bool(self.jit)

    def _output_unit(self, lab: str) -> str:
        spec = self._outspec[lab]
        unit = spec.unit(dict(zip(self.cm.names, self.cm.units)))
        return f"({unit or '1'})/s" if spec.kind == "rate" else unit

    def _label_output(self, b, r: int, Y, dY=None):
        """Model output ``r`` of experiment ``b`` (its expression of the simulated
        variables) and, with their sensitivities ``dY``, its own ``(N, nq)``."""
        spec = self._outspec[b["out_labels"][r]]
        rows = b["out_rows"][r]
        V = np.asarray(Y)[rows]
        if spec.plain:
            y = V[0]
            dy = dY[rows[0]::Y.shape[0], :].T if dY is not None else None
            return y, dy
        f = spec.function.map(V.shape[1])
        val, grad = f(V)
        y = np.asarray(val).ravel()
        if dY is None:
            return y, None
        grad = np.asarray(grad).reshape(V.shape[1], len(rows)) if len(rows) > 1 else \
            np.asarray(grad).reshape(V.shape[1], 1)
        dy = sum(grad[:, j:j + 1] * dY[i::Y.shape[0], :].T for j, i in enumerate(rows))
        return y, dy

    def use_native(self) -> bool:
        """Compile every experiment's step functions to native code (for many
        simulations, e.g. a sensitivity analysis); False if no C compiler is present."""
        if compiler() is None:
            return False
        for b in self.bound:
            tr = b["traj"]
            if not tr.jit:
                b["traj"] = Trajectory(self.cm, tr.t, tr.input_index, tr.output_index,
                                       substeps=tr.substeps, hold=tr.hold, jit=True,
                                       smooth=tr.smooth)
        self._init["jit"] = True
        return True

    def __reduce__(self):
        """Pickle as the constructor's arguments (the CasADi functions are rebuilt, with
        the same substeps) and how each experiment's substeps were chosen (so that
        :meth:`refine` checks them the same way): for process pools and Dask workers."""
        import copy
        chosen = [{k: b[k] for k in ("auto", "error_initial", "substeps_initial") if k in b}
                  for b in self.bound]
        return (_rebuild, (self.cm, self.experiments, copy.deepcopy(self.free),
                           dict(self._init, substeps=[b["substeps"] for b in self.bound],
                                validation=self.validation), chosen))

    def substep_state(self) -> list:
        """The substeps of each experiment and their step functions, as they are now
        (:meth:`refine` may change them during a fit): give it to
        :meth:`restore_substeps` to start the next fit from the same discretization."""
        return [(b["substeps"], b["traj"]) for b in self.bound]

    def restore_substeps(self, state: list) -> None:
        """Put back the substeps of :meth:`substep_state`: ``(substeps, trajectory)`` per
        experiment, or plain substep counts (the step functions are then rebuilt where
        the count differs from the present one)."""
        changed = False
        for b, item in zip(self.bound, state):
            m, traj = item if isinstance(item, tuple) else (int(item), None)
            if traj is None:
                if m == b["substeps"]:
                    continue
                traj = self._trajectory(b, m)
                traj.check_ticks(b["p"])
            if traj is not b["traj"] or m != b["substeps"]:
                b["traj"], b["substeps"] = traj, m
                changed = True
        if changed:
            self._build_residual()

    def _start_values(self) -> dict:
        return {f.name: f.initial for f in self.free}

    def _substeps(self, e, pe, x0, U, in_labels, values, ratio, max_substeps,
                  traj=None) -> int:
        """Substeps for experiment ``e`` from the fastest time constant with the free
        parameters at ``values`` and the inputs at their largest magnitude, along the
        states of ``traj`` (default: a coarse probe run)."""
        cm = self.cm
        pindex = {n: i for i, n in enumerate(cm.param_names)}
        p = pe.copy()
        for name, v in values.items():
            p[pindex[name]] = v
        for j, lab in enumerate(in_labels):
            p[pindex[self.inputs[lab]]] = U[j][np.argmax(np.abs(U[j]))] if U[j].size else 0
        # states along a coarse (one substep, L-stable) simulation at these values
        probe = traj or Trajectory(cm, e.t, [pindex[self.inputs[lab]] for lab in in_labels],
                                   [], substeps=1, hold=e.hold, smooth=self.smooth,
                                   jit=self._use_jit(e.n))
        pp = pe.copy()
        for name, v in values.items():
            pp[pindex[name]] = v
        _, X = probe(pp, x0, U)
        X = X[:, np.linspace(0, X.shape[1] - 1, min(X.shape[1], 60)).astype(int)]
        tau = fastest_time_constant(cm, p, X)
        return choose_substeps(float(np.diff(e.t).max()), tau, ratio=ratio,
                               max_substeps=max_substeps, where=e.where("t"))

    def least_std_scale(self) -> float:
        """The least `std_scale` that means anything: an output whose noise level is
        `noise_level`'s floor (1e-4 of its range: noise-free or quantized data) cannot
        show a discretization error below that level, however small the fit's residuals
        (on noise-free data they are the discretization error itself). The smallest ratio
        of that floor to the output's noise level, over the outputs whose noise was not
        given (0 when every one was)."""
        ratios = [r for b in self.bound for r in b["floor_ratio"] if r > 0]
        return min(ratios, default=0.0)

    def refine(self, theta, ratio: float = 1.0, max_substeps: int = 400,
               std_scale: float = 1.0) -> bool:
        """Re-choose the substeps for the parameters ``theta``; rebuild and return True
        if any experiment needs more than it has (for accuracy at the solution).
        Substeps chosen from the error estimate are checked against ``substep_tol *
        std_scale`` (``std_scale``: the fit's standard errors over the noise-level ones,
        see :func:`std_scale`)."""
        values = dict(zip([f.name for f in self.free], theta[:len(self.free)]))
        changed = False
        for b in self.bound:
            if b.get("auto"):
                # chosen from the error estimate: check it at theta, and double as needed
                p, x0 = self._point(b, theta)
                m = b["substeps"]
                err = self._error_between(b, p, x0, b["traj"], self._trajectory(b, 2 * m))
                if err <= self.substep_tol * std_scale or 2 * m > self.max_substeps:
                    continue
                try:
                    m, err, _ = self._choose_by_error(b, p, x0, 2 * m, std_scale)
                except DataError as exc:
                    log.warning("estimate: %s", exc)
                    m = self.max_substeps
                b["traj"] = self._trajectory(b, m)
                b["traj"].check_ticks(b["p"])
                b["substeps"] = m
                changed = True
                continue
            m = self._substeps(b["exp"], b["p"], b["x0"], b["U"], b["in_labels"],
                               values, ratio, max_substeps, traj=b["traj"])
            if m > b["substeps"]:
                b["traj"] = self._trajectory(b, m)
                b["traj"].check_ticks(b["p"])
                b["substeps"] = m
                changed = True
        if changed:
            self._build_residual()
        return changed

    def _build_residual(self) -> None:
        """Direction matrices of every experiment: ``D`` maps the decision vector to the
        parameter vector, ``S0`` to the initial state."""
        cm = self.cm
        pindex = {n: i for i, n in enumerate(cm.param_names)}
        nq = len(self.names)
        nf, no = len(self.free), len(self.offsets)
        k0 = nf + no
        for b in self.bound:
            D = np.zeros((cm.p0.size, nq))
            for j, f in enumerate(self.free):
                D[pindex[f.name], j] = 1.0
            S0 = np.zeros((cm.nx, nq))
            cols = []
            for s in self.free_x0:
                S0[cm.state_names.index(s), k0] = 1.0
                cols.append(k0)
                k0 += 1
            b["D"], b["S0"], b["x0_cols"] = D, S0, cols
        for b in self.bound:
            b["pe_cols"] = []
            for f in self.per_experiment.get(b["exp"].name, []):
                b["D"][pindex[f.name], k0] = 1.0
                b["pe_cols"].append((pindex[f.name], k0, f))
                k0 += 1
        self.n_residuals = sum(
            sum(b["exp"].n - (self._outspec[lab][1] == "rate") for lab in b["out_labels"])
            for b in self.bound)

    def residual_groups(self) -> list:
        """Per experiment, ``(rows, sample index)`` of the residuals of each output (in
        the order of :meth:`residuals`): the time structure for
        :func:`~mechatron.estimation.uncertainty.hac_covariance`."""
        out, k0 = [], 0
        for b in self.bound:
            segs = []
            for lab in b["out_labels"]:
                first = int(self._outspec[lab][1] == "rate")
                m = b["exp"].n - first
                segs.append((slice(k0, k0 + m), np.arange(first, first + m)))
                k0 += m
            out.append(segs)
        return out

    def _point(self, b, theta):
        cm = self.cm
        p = b["p"].copy()
        nf = len(self.free)
        p[b["D"][:, :nf].argmax(axis=0)] = theta[:nf] if nf else p[[]]
        x0 = b["x0"].copy()
        for s, c in zip(self.free_x0, b["x0_cols"]):
            x0[cm.state_names.index(s)] = theta[c]
        for i, c, _f in b["pe_cols"]:
            p[i] = theta[c]
        return p, x0

    def _assemble(self, b, theta, Y, dY=None):
        """Weighted residuals (and their Jacobian) of one experiment from its outputs."""
        nf = len(self.free)
        nq = len(self.names)
        r_parts, j_parts = [], []
        dt = np.diff(b["exp"].t)
        for r, lab in enumerate(b["out_labels"]):
            y, dy = self._label_output(b, r, Y, dY)                 # (N,), (N, nq)
            ym = b["Ym"][r]
            if self._outspec[lab][1] == "rate":
                y = np.diff(y) / dt
                ym = ym[1:]
                if dy is not None:
                    dy = np.diff(dy, axis=0) / dt[:, None]
            if lab in self.offsets:
                k = nf + self.offsets.index(lab)
                y = y + theta[k]
                if dy is not None:
                    dy = dy.copy()
                    dy[:, k] += 1.0
            sig = b["sigma"][r]
            r_parts.append((y - ym) / sig)
            if dy is not None:
                j_parts.append(dy / sig)
        r = np.concatenate(r_parts) if r_parts else np.zeros(0)
        J = np.vstack(j_parts) if j_parts else np.zeros((0, nq))
        return r, J

    def residuals(self, theta) -> np.ndarray:
        """Weighted residuals at (unscaled) ``theta``."""
        theta = np.asarray(theta, dtype=float)
        out = []
        for b in self.bound:
            p, x0 = self._point(b, theta)
            Y, _ = b["traj"](p, x0, b["U"])
            out.append(self._assemble(b, theta, Y)[0])
        return np.concatenate(out)

    def jacobian(self, theta):
        """``(r, dr/dtheta)`` at (unscaled) ``theta``: exact forward sensitivities."""
        theta = np.asarray(theta, dtype=float)
        rs, js = [], []
        for b in self.bound:
            p, x0 = self._point(b, theta)
            f = b["traj"].sensitivity_function(b["D"])
            Y, dY = f(p, x0, b["U"], b["S0"])
            r, J = self._assemble(b, theta, Y, dY)
            rs.append(r)
            js.append(J)
        return np.concatenate(rs), np.vstack(js)

    # ------------------------------------------------------------------------------------
    @property
    def initial(self) -> np.ndarray:
        vals = [f.initial for f in self.free] + [0.0] * len(self.offsets)
        for b in self.bound:
            for s in self.free_x0:
                vals.append(b["x0"][self.cm.state_names.index(s)])
        for b in self.bound:
            vals += [f.initial for _i, _c, f in b["pe_cols"]]
        return np.array(vals, dtype=float)

    @property
    def scales(self) -> list:
        out = [f.scale for f in self.free]
        for lab in self.offsets:
            b = next(b for b in self.bound if lab in b["out_labels"]) if getattr(
                self, "bound", None) else None
            out.append(float(b["sigma"][b["out_labels"].index(lab)]) if b else 1.0)
        pe = [f.scale for b in getattr(self, "bound", []) for _i, _c, f in b["pe_cols"]]
        out += [1.0] * (len(self.names) - len(out) - len(pe)) + pe
        return out

    @property
    def bounds(self):
        pe = [f for b in self.bound for _i, _c, f in b["pe_cols"]]
        rest = len(self.names) - len(self.free) - len(pe)
        lo = [f.min for f in self.free] + [-math.inf] * rest + [f.min for f in pe]
        hi = [f.max for f in self.free] + [math.inf] * rest + [f.max for f in pe]
        return np.array(lo), np.array(hi)

    def simulate(self, theta=None) -> list[dict]:
        """Model outputs of every experiment at ``theta`` (default: the starting values):
        ``[{label: array}]`` in the model's units, offsets included."""
        theta = self.initial if theta is None else np.asarray(theta, dtype=float)
        nf = len(self.free)
        out = []
        for b in self.bound:
            p, x0 = self._point(b, theta)
            Y, _ = b["traj"](p, x0, b["U"])
            sims = {}
            for r, lab in enumerate(b["out_labels"]):
                y, _ = self._label_output(b, r, Y)
                if self._outspec[lab][1] == "rate":
                    y = np.concatenate([[b["Ym"][r][0]], np.diff(y) / np.diff(b["exp"].t)])
                if lab in self.offsets:
                    y = y + theta[nf + self.offsets.index(lab)]
                sims[lab] = y
            out.append(sims)
        return out


@dataclass
class EstimationResult:
    """Outcome of :func:`estimate` (see the module docstring for the statistics)."""

    names: list
    initial: np.ndarray
    values: np.ndarray
    std: np.ndarray
    ci95: dict
    correlation: np.ndarray
    cost_initial: float
    cost: float
    nrmse: dict
    nrmse_initial: dict
    history: list
    iterations: int
    evaluations: int
    wall_time: float
    success: bool
    message: str
    problem: EstimationProblem = field(repr=False, default=None)
    #: Errors on the validation experiments (not fitted), per experiment and output:
    #: ``{"rmse", "nrmse", "fit_pct", "relerr_pct"}`` (see :func:`validation_errors`).
    validation: dict = field(default_factory=dict)
    #: Parameters that ended on a bound of ``min``/``max``: ``{name: {"side", "bound"}}``
    #: (see :func:`~mechatron.estimation.bounds.at_bounds`); their intervals assume an
    #: interior optimum and do not hold there.
    at_bound: dict = field(default_factory=dict)
    #: ``"hac"`` or ``"white"``: how ``std``, ``ci95`` and ``correlation`` were computed.
    covariance: str = "white"
    #: Standard errors and intervals assuming white residuals, for comparison.
    std_white: np.ndarray = None
    ci95_white: dict = field(default_factory=dict)
    #: Bartlett bandwidth as a fraction of the record (0 for white).
    bandwidth_fraction: float = 0.0
    #: Lag-1 autocorrelation of the residuals by ``"experiment/label"``.
    residual_rho1: dict = field(default_factory=dict)
    #: Correlated residuals, poorly identified parameters (see :mod:`.uncertainty`).
    warnings: list = field(default_factory=list)
    #: Profile-likelihood 95% intervals of the parameters asked for.
    profile_ci95: dict = field(default_factory=dict)
    #: Parameters the data cannot determine, ``{name: why}`` (see
    #: :func:`identifiability`): zero, without influence on the outputs, or with a
    #: standard deviation above the estimate.
    flags: dict = field(default_factory=dict)
    #: Per experiment: ``substeps`` per sample, ``chosen`` (``"error"`` from the error
    #: estimate, or ``"given"``), the step-doubling error estimate in standard errors at
    #: the start (``error_initial``, when chosen) and at the estimates (``error``), and
    #: the ``tolerance`` (see :class:`EstimationProblem`'s ``substep_tol``).
    discretization: dict = field(default_factory=dict)
    #: Multi-start estimation (``estimate(..., starts=K)``): every start, in start
    #: order, as ``{"start", "initial", "parameters", "cost", "converged", "message",
    #: "iterations", "evaluations", "wall_time_s", "error"}`` (see
    #: :mod:`.multistart`); empty for a single start.
    starts: list = field(default_factory=list)
    #: The start this result comes from (0: the problem's starting values).
    best_start: int = 0

    @property
    def parameters(self) -> dict:
        return dict(zip(self.names, map(float, self.values)))

    def to_dict(self) -> dict:
        return {"parameters": self.parameters,
                "initial": dict(zip(self.names, map(float, self.initial))),
                "at_bound": self.at_bound, "flags": self.flags,
                "ci95": {k: [float(lo), float(hi)] for k, (lo, hi) in self.ci95.items()},
                "std": dict(zip(self.names, map(float, self.std))),
                "covariance": self.covariance,
                "std_white": dict(zip(self.names, map(float, self.std_white)))
                if self.std_white is not None else {},
                "ci95_white": {k: [float(lo), float(hi)]
                               for k, (lo, hi) in self.ci95_white.items()},
                "profile_ci95": {k: [float(lo), float(hi)]
                                 for k, (lo, hi) in self.profile_ci95.items()},
                "residual_rho1": self.residual_rho1, "warnings": self.warnings,
                "correlation": {"names": self.names,
                                "matrix": np.round(self.correlation, 6).tolist()},
                "cost_initial": self.cost_initial, "cost": self.cost,
                "nrmse": self.nrmse, "nrmse_initial": self.nrmse_initial,
                "validation": self.validation,
                "discretization": self.discretization,
                "iterations": self.iterations, "evaluations": self.evaluations,
                "wall_time_s": self.wall_time, "success": self.success,
                "message": self.message,
                "trajectory": [{"iteration": h["iteration"], "cost": h["cost"],
                                "parameters": dict(zip(self.names, h["theta"]))}
                               for h in self.history],
                "starts": self.starts, "best_start": self.best_start}

    # -- plots -------------------------------------------------------------------------------
    def plot_fit(self, path) -> Path:
        """Measured data, model before and after, per experiment and signal."""
        from matplotlib.figure import Figure
        prob = self.problem
        before = prob.simulate(self.initial)
        after = prob.simulate(self.values)
        rows = sum(len(b["out_labels"]) for b in prob.bound)
        fig = Figure(figsize=(8, 2.2 * rows + 0.6), layout="constrained")
        axes = fig.subplots(rows, 1, squeeze=False)
        r = 0
        for b, y0, y1 in zip(prob.bound, before, after):
            e = b["exp"]
            for k, lab in enumerate(b["out_labels"]):
                ax = axes[r, 0]
                ax.plot(e.t, b["Ym"][k], ".", ms=2, color="0.6", label="measured")
                ax.plot(e.t, y0[lab], "--", color="tab:red", label="before")
                ax.plot(e.t, y1[lab], "-", color="tab:blue", label="after")
                ax.set_ylabel(f"{e.name}\n{lab} [{prob._output_unit(lab) or '1'}]")
                ax.set_xlabel("t [s]")
                ax.grid(True, alpha=0.3)
                r += 1
        axes[0, 0].legend(loc="best", fontsize="small")
        fig.suptitle("parameter estimation: measured vs model before/after")
        path = Path(path)
        save_figure(fig, path, dpi=90)
        return path

    def plot_trajectory(self, path) -> Path:
        """Each free parameter relative to its final value, per iteration."""
        from matplotlib.figure import Figure
        th = np.array([h["theta"] for h in self.history])
        fig = Figure(figsize=(7, 6), layout="constrained")
        axes = fig.subplots(2, 1, sharex=True)
        for j, name in enumerate(self.names):
            ref = self.values[j] if self.values[j] else 1.0
            axes[0].plot(th[:, j] / ref, marker="o", ms=3, label=name)
        axes[0].set_ylabel("value / final value [1]")
        axes[0].legend(fontsize="small", ncol=2)
        axes[0].grid(True, alpha=0.3)
        axes[1].semilogy([h["cost"] for h in self.history], marker="o", ms=3)
        axes[1].set_ylabel("cost S [1]")
        axes[1].set_xlabel("iteration [1]")
        axes[1].grid(True, alpha=0.3)
        path = Path(path)
        save_figure(fig, path, dpi=90)
        return path


def _rebuild(cm, experiments, free, kwargs, chosen=()):
    prob = EstimationProblem(cm, experiments, free, **kwargs)
    for b, how in zip(prob.bound, chosen):
        b.update(how)
    return prob


def validation_errors(prob: EstimationProblem, theta, experiments=None) -> dict:
    """Simulate ``experiments`` (default: ``prob.validation``) with the free parameters
    and offsets at ``theta`` and compare with their measurements, per experiment and
    output: ``rmse`` (model unit), ``nrmse`` (as the fit), ``fit_pct`` ``100 (1 -
    nrmse)`` and ``relerr_pct`` ``100 ||ym - y|| / ||ym||``: the figures of
    :func:`~mechatron.estimation.validation.validate`, with the runs' own initial states
    (nothing fitted again) and the fit's substeps."""
    from mechatron.estimation.validation import validate
    experiments = prob.validation if experiments is None else list(experiments)
    if not experiments:
        return {}
    m = max(b["substeps"] for b in prob.bound)
    rep = validate(dict(zip(prob.names, map(float, theta))), experiments, problem=prob,
                   refit=False, substeps=[m] * len(experiments))
    out: dict = {}
    for r in rep.rows:
        out.setdefault(r["experiment"], {})[r["signal"]] = {
            "rmse": r["rmse"], "nrmse": r["nrmse"], "fit_pct": r["fit_percent"],
            "relerr_pct": r["relerr_percent"]}
    return out


def _nrmse(prob: EstimationProblem, sims: list[dict]) -> dict:
    out = {}
    for b, s in zip(prob.bound, sims):
        d = {}
        for k, lab in enumerate(b["out_labels"]):
            ym = b["Ym"][k]
            den = np.linalg.norm(ym - ym.mean()) or 1.0
            d[lab] = float(np.linalg.norm(ym - s[lab]) / den)
        out[b["exp"].name] = d
    return out


def estimate(problem: EstimationProblem, *, max_iterations: int = 100, xtol: float = 1e-8,
             ftol: float = 1e-10, gtol: float = 1e-10, callback=None, refine: bool = True,
             fine_ratio: float = 1.0, max_step: float = 0.5,
             log_space: bool = False, covariance: str = "hac", bandwidth=None,
             profile=(), initial=None, starts: int = 1, seed: int = 0,
             sampling: str = "lhs", workers: int | None = None, address: str | None = None,
             client=None, progress=None) -> EstimationResult:
    """Solve ``problem`` (see the module docstring); ``callback(iteration, theta, cost)``
    is called after each Jacobian evaluation (one per iteration) for progress display.

    ``initial`` starts from that decision vector (in the order of ``problem.names``)
    instead of the problem's starting values. ``starts`` above 1 runs a multi-start
    estimation (:mod:`.multistart`): the starting values and ``starts - 1`` points
    sampled inside the bounds (``sampling`` "lhs" or "sobol", from ``seed``), each fit a
    batch task on local processes (``workers``) or a Dask cluster (``client`` or
    ``address``); the best fit is returned with every start in ``result.starts``, and
    ``progress(done, starts)`` is called as the fits arrive (``callback`` is not).

    ``covariance`` is ``"hac"`` (default: the Newey-West sandwich with a Bartlett window,
    valid for correlated residuals, see :mod:`.uncertainty`) or ``"white"`` (the
    textbook ``s^2 (J^T J)^-1``, for independent errors only); ``bandwidth`` fixes the
    Bartlett bandwidth in samples (default: Andrews' rule). ``profile`` names parameters
    (or ``True`` for all) whose profile-likelihood intervals are computed as well
    (``result.profile_ci95``; a few fits each)."""
    from scipy.special import stdtrit

    if covariance not in ("hac", "white"):
        raise ParameterError(f"estimate: covariance must be 'hac' or 'white', got "
                             f"{covariance!r}.")
    if isinstance(starts, bool) or not isinstance(starts, (int, np.integer)) or starts < 1:
        raise ParameterError(f"estimate: starts must be a whole number >= 1, got "
                             f"{starts!r}.")
    if starts > 1:
        from mechatron.estimation.multistart import estimate_multistart
        return estimate_multistart(
            problem, starts=int(starts), seed=seed, sampling=sampling, workers=workers,
            address=address, client=client, progress=progress, initial=initial,
            max_iterations=max_iterations, xtol=xtol, ftol=ftol, gtol=gtol,
            refine=refine, fine_ratio=fine_ratio, max_step=max_step,
            log_space=log_space, covariance=covariance, bandwidth=bandwidth,
            profile=profile)
    prob = problem
    scales = np.array(prob.scales)
    lo_t, hi_t = prob.bounds
    if initial is None:
        theta0 = np.clip(prob.initial, lo_t, hi_t)
    else:
        theta0 = np.asarray(initial, dtype=float)
        if theta0.shape != lo_t.shape or not np.all(np.isfinite(theta0)):
            raise ParameterError(f"estimate: initial must be {lo_t.size} finite number(s), "
                                 f"one per decision variable ({', '.join(prob.names)}), "
                                 f"got {initial!r}.")
        theta0 = np.clip(theta0, lo_t, hi_t)
    # with log_space, positive parameters (lower bound >= 0, positive start) move in log
    # space: a step is a factor and they cannot reach 0 (but they may creep towards it)
    logv = np.zeros(theta0.size, dtype=bool)
    if log_space:
        logv[:len(prob.free)] = (lo_t[:len(prob.free)] >= 0) & (theta0[:len(prob.free)] > 0)

    def to_theta(x):
        return np.where(logv, scales * np.exp(np.where(logv, x, 0.0)), x * scales)

    def to_x(theta):
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(logv, np.log(np.where(logv, theta, 1.0) / scales),
                            theta / scales)

    hi = to_x(hi_t)
    with np.errstate(divide="ignore"):
        lo = np.where(logv, np.log(np.maximum(lo_t, 0.0) / scales), lo_t / scales)
    history = []
    counts = {"sims": 0}
    start = time.perf_counter()

    def point(x):
        counts["sims"] += 1
        theta = to_theta(x)
        r, j = prob.jacobian(theta)
        return r, j * np.where(logv, theta, scales)

    x = to_x(theta0)
    r, J = point(x)
    cost0 = cost = float(r @ r)
    message, success = "maximum number of iterations reached", False

    def record(x, cost):
        history.append({"iteration": len(history), "theta": to_theta(x).tolist(),
                        "cost": cost})
        if callback is not None:
            callback(len(history) - 1, to_theta(x), cost)

    record(x, cost)
    for _round in range(3):
        lam = None
        for _it in range(max_iterations):
            g = J.T @ r
            A = J.T @ J
            free_dir = ~(((x <= lo) & (g > 0)) | ((x >= hi) & (g < 0)))
            if np.max(np.abs(g[free_dir]), initial=0.0) <= gtol * max(cost, 1e-300):
                message, success = "gradient below gtol", True
                break
            d = np.maximum(np.diag(A), 1e-12 * max(np.diag(A).max(), 1e-300))
            if lam is None:
                lam = 1e-3
            accepted = False
            while lam < 1e16:
                try:
                    dx = np.linalg.solve(A + lam * np.diag(d), -g)
                except np.linalg.LinAlgError:
                    dx = -np.linalg.pinv(A + lam * np.diag(d)) @ g
                big = np.max(np.abs(dx))
                if big > max_step:                 # at most a factor e per iteration
                    dx = dx * (max_step / big)
                xn = np.clip(x + dx, lo, hi)
                step = xn - x
                pred = -(2 * g @ step + step @ A @ step)
                rn, Jn = point(xn)
                cn = float(rn @ rn)
                if np.isfinite(cn) and cn < cost and pred > 0:
                    rho = (cost - cn) / pred
                    lam *= max(1 / 3, 1 - (2 * rho - 1) ** 3)
                    accepted = True
                    break
                lam *= 4.0
            if not accepted:
                message, success = "no decrease along any step length", True
                break
            small_step = np.linalg.norm(step) <= xtol * (np.linalg.norm(x) + xtol)
            small_gain = cost - cn <= ftol * cost
            x, r, J, cost = xn, rn, Jn, cn
            record(x, cost)
            if small_step or small_gain:
                message = "relative step below xtol" if small_step else \
                    "relative decrease below ftol"
                success = True
                break
        # the substeps were chosen at the starting values, coarse (L-stable steps); make
        # them fine enough at the solution, and polish the solution with them
        if not refine or not prob.refine(to_theta(x), fine_ratio,
                                         std_scale=std_scale(prob, r, J, covariance,
                                                             bandwidth)):
            break
        r, J = point(x)
        cost = float(r @ r)
    theta = to_theta(x)
    J = J / np.where(logv, theta, scales)
    n, q = r.size, theta.size
    dof = max(n - q, 1)
    s2 = cost / dof
    JtJ = J.T @ J
    try:
        cov_white = s2 * np.linalg.inv(JtJ)
    except np.linalg.LinAlgError:
        cov_white = s2 * np.linalg.pinv(JtJ)
    std_white = np.sqrt(np.clip(np.diag(cov_white), 0, None))
    tq_white = float(stdtrit(dof, 0.975))
    ci_white = {name: (float(v - tq_white * s), float(v + tq_white * s))
                for name, v, s in zip(prob.names, theta, std_white)}
    rho1 = residual_rho1(prob, r)
    if covariance == "hac":
        cov, b = hac_covariance(J, r, prob.residual_groups(), bandwidth=bandwidth)
        tq = bartlett_critical(b)
    else:
        cov, b, tq = cov_white, 0.0, tq_white
    std = np.sqrt(np.clip(np.diag(cov), 0, None))
    ci = {name: (float(v - tq * s), float(v + tq * s))
          for name, v, s in zip(prob.names, theta, std)}
    with np.errstate(invalid="ignore", divide="ignore"):
        corr = cov / np.outer(std, std)
    warnings = diagnose(prob.names, std, theta, corr,
                        rho1 if covariance == "hac" else {},
                        std_white=std_white, relative=[f.name for f in prob.free])
    if covariance != "hac" and any(v > RHO_WARN for v in rho1.values()):
        warnings.insert(0, "residuals are correlated (lag-1 autocorrelation " + ", ".join(
            f"{k} {v:.2f}" for k, v in rho1.items() if v > RHO_WARN) + ") but the "
            "intervals assume white noise (covariance=\"white\"): they are too narrow. "
            "Use covariance=\"hac\".")
    disc = {}
    # the bias bound ||e / sigma|| in the reported standard errors: divided by the
    # residual level s and by how much wider these are than the white-noise ones
    ratio = float(np.nanmin(std / std_white)) if np.all(std_white > 0) else 1.0
    scale = math.sqrt(s2) * max(1.0, ratio if math.isfinite(ratio) else 1.0)
    for bb, (name, err) in zip(prob.bound, prob.discretization_error(theta).items()):
        rel = err / scale if scale > 0 else err
        disc[name] = {"substeps": int(bb["substeps"]),
                      "substeps_initial": int(bb.get("substeps_initial", bb["substeps"])),
                      "chosen": "error" if bb.get("auto") else "given",
                      "error_initial": bb.get("error_initial"),
                      "error": err if math.isfinite(err) else None,
                      "error_std": rel if math.isfinite(rel) else None,
                      "tolerance": prob.substep_tol}
        if not rel <= prob.substep_tol:
            shown = "not finite (a Radau step did not converge)" if not math.isfinite(
                rel) else f"{rel:.3g} standard errors of the estimates"
            warnings.append(
                f"experiment '{name}': the discretization error estimate at the estimates "
                f"is {shown} with {bb['substeps']} substeps per sample (tolerance "
                f"{prob.substep_tol:g}): the estimates may be biased by the "
                f"discretization. Give more substeps (or substeps = None to choose them "
                f"from the error), or raise max_substeps.")
    for w in warnings:
        log.warning("estimate: %s", w, extra={"in_summary": True})
    profile_ci = profile_intervals(prob, theta, profile, s2=s2, tq=tq, std=std,
                                   std_white=std_white)
    wall = time.perf_counter() - start
    lo_b, hi_b = prob.bounds
    hits = at_bounds(prob.names, theta, lo_b, hi_b)
    if hits:
        log.warning("estimate: %s", describe_at_bounds(hits, "estimate"))
    flags = identifiability(prob.names, theta, J, std, converged=bool(success),
                            on_bound=hits)
    for name, why in flags.items():
        log.warning("estimate: %s %s", name, why)
    return EstimationResult(
        names=list(prob.names), initial=theta0, values=theta, std=std, ci95=ci,
        correlation=corr, cost_initial=cost0, cost=cost,
        nrmse=_nrmse(prob, prob.simulate(theta)),
        nrmse_initial=_nrmse(prob, prob.simulate(theta0)), history=history,
        iterations=len(history) - 1, evaluations=counts["sims"], wall_time=wall,
        success=bool(success), message=message, problem=prob, at_bound=hits,
        covariance=covariance, std_white=std_white, ci95_white=ci_white,
        bandwidth_fraction=b, residual_rho1=rho1, warnings=warnings,
        profile_ci95=profile_ci, validation=validation_errors(prob, theta),
        flags=flags, discretization=disc)


def profile_intervals(prob: EstimationProblem, theta, profile, *, s2: float, tq: float,
                      std, std_white) -> dict:
    """Profile-likelihood 95% intervals of the parameters named in ``profile`` (``True``:
    all) at the estimates ``theta``: ``s2`` the residual variance, ``tq`` the interval's
    critical value, ``std``/``std_white`` the reported and white-noise standard errors
    (see :func:`estimate`)."""
    out = {}
    if not profile:
        return out
    names = list(prob.names) if profile is True else list(profile)
    for name in names:
        if name not in prob.names:
            raise ParameterError(f"estimate: profile: '{name}' is not a free "
                                 f"parameter ({', '.join(prob.names)}).", path=name)
        i = prob.names.index(name)
        # the likelihood-ratio threshold s^2 c^2, widened by the HAC design effect
        ratio = (std[i] / std_white[i]) ** 2 if std_white[i] > 0 else 1.0
        out[name] = profile_interval(prob, theta, i, s2 * tq ** 2 * ratio, std[i])
    return out


def std_scale(prob: EstimationProblem, r, J, covariance: str = "hac",
              bandwidth=None) -> float:
    """The fit's standard errors over those of the noise level the discretization error
    is measured in: ``s`` (the residuals' level, 1 when ``sigma`` is right) times the
    smallest ratio of the HAC to the white-noise standard errors (at least 1). A
    discretization error ``E`` moves no estimate by more than ``E / std_scale`` of its
    reported standard error. At least `EstimationProblem.least_std_scale`: on noise-free
    data the residuals are the discretization error itself, and would shrink it with
    every refinement."""
    r = np.asarray(r, dtype=float)
    J = np.asarray(J, dtype=float)
    n, q = J.shape
    s = math.sqrt(float(r @ r) / max(n - q, 1))
    least = max(prob.least_std_scale(), 1e-300)
    if covariance != "hac" or q == 0:
        return max(s, least)
    try:
        white = s * s * np.linalg.pinv(J.T @ J)
        cov, _b = hac_covariance(J, r, prob.residual_groups(), bandwidth=bandwidth)
        with np.errstate(invalid="ignore", divide="ignore"):
            ratio = float(np.nanmin(np.sqrt(np.diag(cov) / np.diag(white))))
    except (np.linalg.LinAlgError, ValueError):
        ratio = 1.0
    return max(s * max(1.0, ratio if math.isfinite(ratio) else 1.0), least)


def residual_rho1(prob: EstimationProblem, r: np.ndarray) -> dict:
    """Lag-1 autocorrelation of the residuals of each experiment and output, by
    ``"experiment/label"``."""
    out = {}
    for b, segments in zip(prob.bound, prob.residual_groups()):
        for lab, (rows, _k) in zip(b["out_labels"], segments):
            out[f"{b['exp'].name}/{lab}"] = float(acf(r[rows], 1)[-1]) \
                if r[rows].size > 2 else 0.0
    return out




def identifiability(names, theta, J, std, *, rel_column: float = 1e-8,
                    rel_std: float = 1.0, converged: bool = True,
                    on_bound=()) -> dict:
    """Parameters the data cannot determine, ``{name: why}``: an estimate of exactly 0
    (no relative uncertainty, and rarely what the physics means), a column of the
    (scaled) Jacobian ``J`` below ``rel_column`` of the largest (the outputs do not
    depend on it), or a standard deviation above ``rel_std`` times the estimate (the
    95% interval spans zero twice over: the data barely inform it); the last only when
    the fit ``converged`` (away from an optimum the covariance means nothing). A zero on
    a bound (names in ``on_bound``) is reported as on its bound instead."""
    J = np.asarray(J, dtype=float)
    norms = np.linalg.norm(J, axis=0) if J.size else np.zeros(len(names))
    top = float(norms.max()) if norms.size else 0.0
    out = {}
    for j, name in enumerate(names):
        if top == 0.0 or norms[j] <= rel_column * top:
            out[name] = ("is not identifiable: the measured outputs do not depend on it "
                         "(its Jacobian column is zero); fix it, or add an experiment "
                         "that excites it.")
        elif theta[j] == 0.0 and name not in on_bound:
            out[name] = ("is estimated as exactly 0: is it needed, or is 0 its bound? Its "
                         "relative uncertainty is undefined.")
        elif converged and (not np.isfinite(std[j]) or std[j] > rel_std * abs(theta[j])):
            out[name] = (f"is poorly identifiable: standard deviation {std[j]:.3g} is more "
                         f"than {rel_std:.0%} of the estimate {theta[j]:.3g}; the data "
                         "barely inform it (see the correlations).")
    return out
