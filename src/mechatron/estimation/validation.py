"""Validation: the fitted model simulated on data it was not fitted to, with the usual
figures of system identification.

For each experiment and measured output, with ``e = ym - y`` the simulation error:

* ``RMSE = sqrt(mean(e^2))`` in the output's unit;
* ``NRMSE = ||e|| / ||ym - mean(ym)||`` and the fit ``100 (1 - NRMSE)`` % (the System
  Identification Toolbox's ``compare``; 100% is a perfect fit, 0% no better than the
  mean, negative worse);
* the autocorrelation of ``e`` at lags ``0 .. lags`` and its cross-correlation with each
  measured input at lags ``-lags .. lags``, with the 95% band ``+/- 1.96 / sqrt(N)`` of a
  white sequence independent of the input (Ljung, *System Identification*, 2nd ed.,
  section 16.6): correlation outside the band at positive lags of the cross-correlation
  means input dynamics the model misses; autocorrelation outside it, that the error is not
  white (the intervals then need :mod:`.uncertainty`).

The validation data are simulated with the shared fitted parameters. What belongs to one
run (initial states ``free_x0``, per-experiment parameters) cannot carry over to another:
by default those are fitted again on the validation data with everything shared held at
the fitted values (as ``compare`` estimates initial conditions), which is stated in the
report.
"""

from __future__ import annotations

import base64
import html
import logging
import math
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from string import Template

import numpy as np

from mechatron._io import save_figure, write_text
from mechatron.errors import DataError
from mechatron.estimation.uncertainty import acf, ccf

__all__ = ["ValidationReport", "validate", "write_html_report"]


@dataclass
class ValidationReport:
    """Figures of a simulated model against measured data (see the module docstring).

    ``rows``: one dict per experiment and output with ``experiment``, ``signal``, ``n``,
    ``rmse``, ``nrmse``, ``fit_percent``, ``relerr_percent`` (``100 ||e|| / ||ym||``), ``rho1`` (lag-1 autocorrelation of the error),
    ``acf_outside`` / ``ccf_outside`` (fraction of lags 1..lags, resp. -lags..lags,
    outside the 95% band) and ``max_ccf`` (largest absolute cross-correlation with an
    input)."""

    label: str
    rows: list
    lags: int
    parameters: dict
    refitted: list = field(default_factory=list)
    series: list = field(default_factory=list, repr=False)

    def to_dict(self) -> dict:
        rows = []
        for r, s in zip(self.rows, self.series):
            rows.append(dict(r, acf=np.round(s["acf"], 6).tolist(),
                             ccf={k: np.round(v, 6).tolist() for k, v in s["ccf"].items()}))
        return {"label": self.label, "lags": self.lags, "parameters": self.parameters,
                "refitted": self.refitted, "rows": rows}

    def summary(self) -> str:
        """One line per experiment and output."""
        return "\n".join(
            f"  {r['experiment']}/{r['signal']}: RMSE {r['rmse']:.4g}, fit "
            f"{r['fit_percent']:.1f}%, residual lag-1 autocorrelation {r['rho1']:+.2f}, "
            f"max |cross-correlation with input| {r['max_ccf']:.2f}" for r in self.rows)

    def plot(self, path) -> Path:
        """Measured and simulated outputs with the error, the error's autocorrelation and
        its cross-correlation with the inputs, one row per experiment and output."""
        from matplotlib.figure import Figure
        n = max(len(self.series), 1)
        fig = Figure(figsize=(12, 2.6 * n + 0.6), layout="constrained")
        axes = fig.subplots(n, 3, squeeze=False, width_ratios=(2.2, 1, 1))
        for row, s in zip(axes, self.series):
            band = 1.96 / math.sqrt(s["t"].size)
            ax = row[0]
            ax.plot(s["t"], s["measured"], ".", ms=2, color="0.55", label="measured")
            ax.plot(s["t"], s["simulated"], "-", color="tab:blue", label="model")
            ax.plot(s["t"], s["measured"] - s["simulated"], "-", lw=0.8, color="tab:red",
                    label="error")
            ax.set_ylabel(f"{s['experiment']}\n{s['signal']} [{s['unit'] or '1'}]")
            ax.set_xlabel("t [s]")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize="small", loc="best")
            lags = np.arange(s["acf"].size)
            row[1].bar(lags, s["acf"], width=0.6, color="tab:red")
            row[1].axhspan(-band, band, color="tab:blue", alpha=0.15, label="95% band")
            row[1].set_xlabel("lag [samples]")
            row[1].set_ylabel("error autocorrelation [1]")
            row[1].legend(fontsize="small")
            row[1].grid(True, alpha=0.3)
            for name, c in s["ccf"].items():
                row[2].plot(np.arange(-self.lags, self.lags + 1), c, ".-", ms=3,
                            label=name)
            row[2].axhspan(-band, band, color="tab:blue", alpha=0.15)
            row[2].set_xlabel("lag [samples] (input leads >0)")
            row[2].set_ylabel("cross-correlation\nerror, input [1]")
            row[2].grid(True, alpha=0.3)
            if s["ccf"]:
                row[2].legend(fontsize="small")
        fig.suptitle(f"{self.label} data: measured vs model; error correlations")
        return save_figure(fig, Path(path), dpi=90)


def validate(result, experiments=None, *, label: str | None = None, lags: int = 25,
             per_experiment=None, refit: bool = True, problem=None,
             substeps=None) -> ValidationReport:
    """Simulate the fitted model of ``result`` on ``experiments`` and report the fit.

    Parameters
    ----------
    result : EstimationResult or dict
        A fit from :func:`~mechatron.estimation.estimate`, or the fitted values by
        decision-variable name (``estimate.json``'s ``parameters``) with ``problem``.
    experiments : list of Experiment, optional
        Validation data with the signals of the estimation data. None: the estimation
        data themselves (the figures of the fit, ``label`` "estimation").
    lags : int
        Lags of the correlation functions.
    per_experiment : dict, optional
        Per-experiment free parameters of the validation experiments (by name), fitted
        on them with the shared values held.
    refit : bool
        Fit the run-specific unknowns (``free_x0`` of the problem, ``per_experiment``)
        on the validation data; False keeps their start values.
    substeps : int or list of int, optional
        Substeps per sample of the validation runs (default: chosen from the error
        estimate, as for a fit).
    """
    from mechatron.estimation.problem import EstimationProblem
    if isinstance(result, dict):
        if problem is None:
            raise TypeError("validate: parameter values given as a dict need the "
                            "problem they belong to (problem=...).")
        prob = problem
        missing = [n for n in prob.names if n not in result]
        if missing:
            raise DataError(f"validate: no value for {', '.join(missing)} among the "
                            f"fitted parameters ({', '.join(result)}). Was the fit made "
                            "with this problem file?")
        values = np.array([float(result[n]) for n in prob.names])
    else:
        prob, values = result.problem, np.asarray(result.values, dtype=float)
    if experiments is None:
        return _report(prob, values, label or "estimation", lags,
                       dict(zip(prob.names, map(float, values))), [])
    shared = {f.name: float(v) for f, v in zip(prob.free, values)}
    nf = len(prob.free)
    offsets = {lab: float(values[nf + k]) for k, lab in enumerate(prob.offsets)}
    per = {k: list(v) for k, v in dict(per_experiment or {}).items()}
    free_x0 = list(prob.free_x0)
    vprob = EstimationProblem(prob.cm, list(experiments), [], inputs=prob.inputs,
                              outputs=prob.outputs, fixed={**prob.fixed, **shared},
                              free_x0=free_x0, per_experiment=per, jit=prob.jit,
                              input_delays=prob.input_delays, smooth=prob.smooth,
                              substeps=substeps)
    refitted = []
    theta = vprob.initial
    if refit and vprob.names:
        theta = _refit(vprob, offsets)
        refitted = list(vprob.names)
    params = dict(shared, **{f"offset:{k}": v for k, v in offsets.items()})
    params.update(dict(zip(vprob.names, map(float, theta))))
    return _report(vprob, theta, label or "validation", lags, params, refitted,
                   offsets=offsets)


def _refit(vprob, offsets) -> np.ndarray:
    """Run-specific unknowns on the validation data (outputs shifted by the fitted
    sensor offsets first)."""
    from mechatron.estimation.problem import estimate
    saved = [b["Ym"].copy() for b in vprob.bound]
    for b in vprob.bound:
        for r, lab in enumerate(b["out_labels"]):
            b["Ym"][r] = b["Ym"][r] - offsets.get(lab, 0.0)
    try:
        logger = logging.getLogger("mechatron.estimation.problem")
        level = logger.level
        logger.setLevel(logging.ERROR)   # warnings about these few unknowns are noise here
        try:
            res = estimate(vprob, covariance="white")
        finally:
            logger.setLevel(level)
    finally:
        for b, ym in zip(vprob.bound, saved):
            b["Ym"] = ym
    return res.values


def _report(prob, theta, label, lags, params, refitted, offsets=None) -> ValidationReport:
    sims = prob.simulate(theta)
    rows, series = [], []
    for b, sim in zip(prob.bound, sims):
        e = b["exp"]
        for r, lab in enumerate(b["out_labels"]):
            ym = b["Ym"][r]
            y = sim[lab] + (offsets or {}).get(lab, 0.0)
            first = int(prob._outspec[lab].kind == "rate")    # rate: from sample 2 on
            err = (ym - y)[first:]
            den = float(np.linalg.norm(ym[first:] - ym[first:].mean())) or 1.0
            nrmse = float(np.linalg.norm(err)) / den
            L = max(1, min(lags, err.size - 2))
            a = acf(err, L)
            band = 1.96 / math.sqrt(err.size)
            c = {il: ccf(err, e.inputs[il][first:], L) for il in prob.inputs}
            rows.append(dict(experiment=e.name, signal=lab, n=int(err.size),
                             rmse=float(np.sqrt(np.mean(err ** 2))), nrmse=nrmse,
                             fit_percent=100.0 * (1.0 - nrmse),
                             relerr_percent=100.0 * float(np.linalg.norm(err))
                             / (float(np.linalg.norm(ym[first:])) or 1.0),
                             rho1=float(a[1]),
                             acf_outside=float(np.mean(np.abs(a[1:]) > band)),
                             ccf_outside=float(np.mean([np.mean(np.abs(v) > band)
                                                        for v in c.values()]))
                             if c else 0.0,
                             max_ccf=float(max((np.max(np.abs(v)) for v in c.values()),
                                               default=0.0))))
            series.append(dict(experiment=e.name, signal=lab, t=e.t[first:],
                               measured=ym[first:], simulated=y[first:], acf=a, ccf=c,
                               unit=prob._output_unit(lab)))
    return ValidationReport(label, rows, lags, params, refitted, series)


# ---------------------------------------------------------------------------- the report
def _png(path: Path) -> str:
    return base64.b64encode(Path(path).read_bytes()).decode("ascii")


def _table(head, rows) -> str:
    out = ["<table><tr>" + "".join(f"<th>{html.escape(str(h))}</th>" for h in head)
           + "</tr>"]
    for row in rows:
        out.append("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row)
                   + "</tr>")
    return "\n".join(out + ["</table>"])


def _section(rep: ValidationReport, figure: Path | None) -> str:
    parts = [f"<h2>{html.escape(rep.label.capitalize())} data</h2>"]
    if rep.refitted:
        parts.append("<p>Fitted again on these data (run-specific): "
                     + html.escape(", ".join(rep.refitted)) + ".</p>")
    parts.append(_table(["experiment", "signal", "samples", "RMSE", "NRMSE", "fit %",
                         "error lag-1 autocorr.", "max |xcorr| with input"],
                        [[r["experiment"], r["signal"], r["n"], f"{r['rmse']:.4g}",
                          f"{r['nrmse']:.4g}", f"{r['fit_percent']:.1f}",
                          f"{r['rho1']:+.3f}", f"{r['max_ccf']:.3f}"] for r in rep.rows]))
    if figure is not None:
        parts.append(f'<img alt="{html.escape(rep.label)} figures" '
                     f'src="data:image/png;base64,{_png(figure)}">')
    return "\n".join(parts)


def write_html_report(path, result, reports: list, figures: dict | None = None,
                      title: str = "Parameter estimation") -> Path:
    """One HTML page: the estimates with both kinds of intervals, the warnings, and one
    section per :class:`ValidationReport` (the estimation data and, when given, the
    validation data), with their figures (``figures``: label -> PNG path) embedded."""
    figures = figures or {}
    rows = []
    for j, name in enumerate(result.names):
        lo, hi = result.ci95[name]
        wlo, whi = result.ci95_white.get(name, (math.nan, math.nan))
        plo, phi = result.profile_ci95.get(name, (math.nan, math.nan))
        rows.append([name, f"{result.values[j]:.6g}", f"[{lo:.6g}, {hi:.6g}]",
                     f"[{wlo:.6g}, {whi:.6g}]",
                     f"[{plo:.6g}, {phi:.6g}]" if name in result.profile_ci95 else "-"])
    params = _table(["parameter", "estimate", f"95% interval ({result.covariance})",
                     "95% interval (white noise)", "profile likelihood"], rows)
    warnings = "".join(f"<li>{html.escape(w)}</li>" for w in result.warnings)
    text = Template(resources.files("mechatron.estimation").joinpath(
        "templates/estimate_report.html").read_text()).substitute(
        title=html.escape(title),
        summary=html.escape(f"{result.iterations} iterations, cost {result.cost_initial:.6g}"
                            f" -> {result.cost:.6g}; {result.message}"),
        parameters=params,
        warnings=f"<ul class='warn'>{warnings}</ul>" if warnings else "<p>None.</p>",
        sections="\n".join(_section(rep, figures.get(rep.label)) for rep in reports))
    return write_text(path, text)
