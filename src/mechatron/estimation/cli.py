"""``mechatron estimate``, ``validate``, ``sensitivity`` and ``optimize``.

Each reads a TOML problem file (format: ``docs/estimation.md``), shows progress on stderr
(a bar, or one line per step when stderr is not a terminal; ``--quiet`` silences it), and
prints a summary, or with ``--json`` one JSON object on stdout. ``--out DIR`` writes the
plots and the full result as JSON.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from mechatron._io import write_text
from mechatron.cli import CommandError, add_json, emit, emit_json, jsonable, table

__all__ = ["add_commands", "Progress"]


class Progress:
    """Progress on stderr: on a terminal a tqdm bar (``total`` known) or counter, shown
    once the run lasts over :data:`mechatron.cli.PROGRESS_DELAY` s; otherwise one line
    per tenth of the run (or per step when ``total`` is None)."""

    def __init__(self, label: str, total: int | None = None, *, enabled: bool = True):
        self.label, self.total, self.enabled = label, total, enabled
        self.tty = sys.stderr.isatty()
        self.start = time.perf_counter()
        self._last = 0.0
        self.bar = None
        if enabled and self.tty:
            from mechatron.cli import progress
            self.bar = progress(total=total, desc=label)

    def update(self, done: int, text: str = "") -> None:
        if not self.enabled:
            return
        if self.bar is not None:
            if text:
                self.bar.set_postfix_str(text, refresh=False)
            self.bar.update(done - self.bar.n)
            return
        now = time.perf_counter()
        final = self.total is not None and done >= self.total
        if self.tty and not final and now - self._last < 0.1:
            return
        self._last = now
        if self.total:
            frac = min(done / self.total, 1.0)
            bar = "#" * int(30 * frac) + "-" * (30 - int(30 * frac))
            line = f"{self.label} [{bar}] {done}/{self.total} {text}"
        else:
            line = f"{self.label}: {done} {text}"
        line += f"  ({now - self.start:.1f} s)"
        if self.tty:
            print("\r" + line[:120].ljust(120), end="", file=sys.stderr, flush=True)
        elif final or self.total is None or done % max(1, self.total // 10) == 0:
            print(line, file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()


def _out_dir(path: str | None) -> Path | None:
    if path is None:
        return None
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise NotADirectoryError(f"--out {p}: exists and is not a directory.")
    p.mkdir(parents=True, exist_ok=True)
    return p


# ---------------------------------------------------------------------------- estimate
def cmd_estimate(args: argparse.Namespace) -> int:
    from mechatron.estimation.config import build_estimation, load_config
    from mechatron.estimation.problem import estimate, passing_only
    _positive("--max-iterations", args.max_iterations)
    _positive("--starts", args.starts)
    _positive("--workers", args.workers)
    _positive("--seed", args.seed, 0)
    cfg = load_config(args.config)
    out = _out_dir(args.out)
    opts = cfg.get("estimation", {})
    starts = args.starts if args.starts is not None else int(opts.get("starts", 1))
    address = args.dask or opts.get("address")
    if args.dask and starts == 1:
        raise CommandError("--dask: the cluster runs the starts of a multi-start "
                           "estimation; give --starts K (K > 1) or [estimation] starts.")
    if address and starts > 1:
        where = args.dask and "--dask" or "[estimation] address"
        _need_dask(where)
        _reach_scheduler(where, str(address))
    t0 = time.perf_counter()
    prob = build_estimation(cfg)
    setup = time.perf_counter() - t0
    if starts > 1:
        bar = Progress("estimate", starts, enabled=not args.quiet)
        multi = dict(starts=starts, seed=args.seed if args.seed is not None
                     else int(opts.get("seed", 0)),
                     sampling=args.sampling or opts.get("sampling", "lhs"),
                     workers=args.workers if args.workers is not None
                     else opts.get("workers"), address=address,
                     progress=lambda done, total: bar.update(done, "starts"))
    else:
        bar = Progress("estimate", enabled=not args.quiet)
        multi = dict(callback=lambda k, th, cost: bar.update(
            k, f"(iteration), cost {cost:.6g}"))
    with passing_only(_not_in_summary):
        res = estimate(prob, max_iterations=args.max_iterations,
                       covariance=args.covariance, profile=_profile_arg(args.profile),
                       **multi)
    bar.close()
    doc = res.to_dict()
    doc["setup_s"] = setup
    doc["config"] = str(args.config)
    reports = []
    if out is not None:
        reports = _validation_reports(cfg, res, prob, ())
        doc["validation"] = {rep.label: rep.to_dict() for rep in reports}
    plots = {"estimate_fit.png": res.plot_fit,
             "estimate_trajectory.png": res.plot_trajectory}
    plots.update({f"{rep.label}_residuals.png": rep.plot for rep in reports})
    files = _save(out, doc, plots, "estimate")
    if out is not None:
        files.append(_html(out / "estimate_report.html", res, reports, cfg, args))
        doc["files"].append(str(files[-1]))
    if args.json:
        emit_json(doc)
        return 0
    emit(f"{cfg.get('title', args.config)}")
    emit(f"  {len(prob.experiments)} experiment(s), {prob.n_residuals} residuals, "
         f"{len(prob.names)} free; {res.iterations} iterations, {res.evaluations} "
         f"simulations, {res.wall_time:.2f} s (+{setup:.2f} s setup); {res.message}")
    if res.starts:
        emit(_starts_summary(res, address))
    emit(f"  cost {res.cost_initial:.6g} -> {res.cost:.6g}")
    rows = []
    for j, name in enumerate(res.names):
        lo, hi = res.ci95[name]
        rows.append([name, f"{res.initial[j]:.6g}", f"{res.values[j]:.6g}",
                     f"[{lo:.6g}, {hi:.6g}]",
                     f"{100 * res.std[j] / abs(res.values[j]):.2f}%" if res.values[j] else "-",
                     _bound_note(res.at_bound.get(name)) or _flag_note(res.flags.get(name))])
    emit(table(["parameter", "start", "estimate", "95% interval", "rel. std", "note"], rows,
               right="1234"))
    emit("  fit (NRMSE, 0 = perfect): " + "; ".join(
        f"{e}: " + ", ".join(f"{lab} {v0:.3g} -> {v:.3g}"
                             for (lab, v), v0 in zip(d.items(), res.nrmse_initial[e].values()))
        for e, d in res.nrmse.items()))
    if res.discretization:
        emit("  discretization (Radau substeps per sample; step-doubling error estimate "
             "in noise-level units, start -> estimates): " + "; ".join(
                 f"{e}: " + (f"{d['substeps_initial']} -> "
                             if d.get("substeps_initial", d["substeps"]) != d["substeps"]
                             else "")
                 + f"{d['substeps']} ({d['chosen']}), "
                 + (f"{d['error_initial']:.2g} -> " if d.get("error_initial") is not None
                    else "")
                 + (f"{d['error']:.2g} = {d['error_std']:.2g} standard errors of the "
                    f"estimates" if d.get("error_std") is not None else "not finite")
                 + f" (tolerance {d['tolerance']:g})"
                 for e, d in res.discretization.items()))
    for e, d in res.validation.items():
        emit(f"  validation on {e} (not fitted): " + "; ".join(
            f"{lab} RMSE {v['rmse']:.4g}, NRMSE {v['nrmse']:.3g}, relative error "
            f"{v['relerr_pct']:.3g}%" for lab, v in d.items()))
    strong = [(res.names[a], res.names[b], res.correlation[a, b])
              for a in range(len(res.names)) for b in range(a)
              if abs(res.correlation[a, b]) > 0.9]
    if strong:
        emit("  strongly correlated: " + ", ".join(f"{a}/{b} {c:+.3f}" for a, b, c in strong))
    if res.profile_ci95:
        emit("  profile-likelihood 95% intervals: " + "; ".join(
            f"{k} [{lo:.6g}, {hi:.6g}]" for k, (lo, hi) in res.profile_ci95.items()))
    for w in res.warnings:
        emit(f"  ! {w}")
    for rep in reports:
        emit(f"  {rep.label} data:")
        emit(rep.summary())
    for f in files:
        emit(f"  wrote {f}")
    return 0


def _starts_summary(res, address) -> str:
    """The table of a multi-start estimation: every start, the chosen one marked."""
    rows = []
    for r in res.starts:
        values = r["parameters"] or {}
        rows.append([("* " if r["start"] == res.best_start else "  ") + str(r["start"])]
                    + [f"{r['initial'][n]:.4g}" for n in res.names]
                    + [f"{values[n]:.6g}" if n in values else "-" for n in res.names]
                    + [f"{r['cost']:.6g}" if r["error"] is None else "-",
                       "yes" if r["converged"] else ("FAILED" if r["error"] else "no")])
    failed = [r for r in res.starts if r["error"]]
    best = res.cost
    reached = sum(1 for r in res.starts if r["error"] is None
                  and r["cost"] <= best * (1 + 1e-6) + 1e-300)
    head = (f"  {len(res.starts)} starts on "
            f"{'the Dask cluster at ' + str(address) if address else 'local processes'}"
            f" ({sum(r['evaluations'] for r in res.starts)} simulations); start "
            f"{res.best_start} has the lowest cost, reached by {reached} start(s)"
            + (f"; {len(failed)} failed (first: {failed[0]['error']})" if failed else "")
            + ":\n")
    return head + table(["start"] + [f"{n} start" for n in res.names] + list(res.names)
                        + ["cost", "converged"], rows,
                        right="".join(str(k) for k in range(1, 2 * len(res.names) + 2)))


def _not_in_summary(record) -> bool:
    """Holds back the estimator's uncertainty warnings (correlated residuals, poorly
    identified parameters) that the command prints in its summary and JSON
    (``extra={"in_summary": True}``). Flags of parameters on a bound or not
    identifiable are still logged."""
    return not getattr(record, "in_summary", False)


def _profile_arg(value):
    if not value:
        return ()
    return True if value == ["all"] else [v for item in value for v in item.split(",")]


def _validation_reports(cfg, res, prob, data) -> list:
    """The figures of the estimation data and of the validation data (``data`` files, or
    ``[[validation]]`` of the problem file), when there are any."""
    from mechatron.estimation.config import per_experiment, validation_experiments
    from mechatron.estimation.validation import validate
    reports = [validate(res, problem=prob)]
    exps = validation_experiments(cfg, data)
    if exps:
        reports.append(validate(res, exps, problem=prob,
                                per_experiment=per_experiment(cfg, "validation", data)))
    return reports


def _html(path: Path, res, reports, cfg, args) -> Path:
    from mechatron.estimation.validation import write_html_report
    return write_html_report(path, res, reports,
                             {rep.label: path.parent / f"{rep.label}_residuals.png"
                              for rep in reports},
                             title=str(cfg.get("title", args.config)))


# ---------------------------------------------------------------------------- validate
def cmd_validate(args: argparse.Namespace) -> int:
    from mechatron.estimation.config import build_estimation, load_config
    from mechatron.estimation.problem import estimate, passing_only
    cfg = load_config(args.config)
    out = _out_dir(args.out)
    if not args.data and not cfg.get("validation"):
        raise CommandError(f"{args.config}: nothing to validate on; give --data FILE.csv "
                           "or a [[validation]] table in the problem file.")
    prob = build_estimation(cfg)
    res = None
    if args.fit:
        values = _read_fit(args.fit)
    else:
        bar = Progress("estimate", enabled=not args.quiet)
        with passing_only(_not_in_summary):
            res = estimate(prob, max_iterations=args.max_iterations,
                           callback=lambda k, th, cost: bar.update(
                               k, f"(iteration), cost {cost:.6g}"))
        bar.close()
        values = res.parameters
    from mechatron.estimation.validation import validate
    reports = [validate(values, problem=prob)]
    from mechatron.estimation.config import per_experiment, validation_experiments
    reports.append(validate(values, validation_experiments(cfg, args.data or ()),
                            problem=prob,
                            per_experiment=per_experiment(cfg, "validation", args.data)))
    doc = {"config": str(args.config), "parameters": values,
           "validation": {rep.label: rep.to_dict() for rep in reports}}
    files = _save(out, doc, {f"{rep.label}_residuals.png": rep.plot for rep in reports},
                  "validate")
    if out is not None and res is not None:
        files.append(_html(out / "validate_report.html", res, reports, cfg, args))
        doc["files"].append(str(files[-1]))
    if args.json:
        emit_json(doc)
        return 0
    emit(f"{cfg.get('title', args.config)}")
    for rep in reports:
        emit(f"  {rep.label} data" + (f" (fitted again: {', '.join(rep.refitted)})"
                                      if rep.refitted else "") + ":")
        emit(rep.summary())
    for f in files:
        emit(f"  wrote {f}")
    return 0


def _read_fit(path: str) -> dict:
    p = Path(path)
    try:
        doc = json.loads(p.read_text())
        values = doc["parameters"]
        if not isinstance(values, dict):
            raise TypeError
        return {k: float(v) for k, v in values.items()}
    except FileNotFoundError:
        raise CommandError(f"--fit {p}: no such file.") from None
    except (ValueError, KeyError, TypeError):
        raise CommandError(f"--fit {p}: not the estimate.json of `mechatron estimate "
                           "--out` (no 'parameters' table of numbers).") from None


def _flag_note(why: str | None) -> str:
    if not why:
        return ""
    return ("NOT IDENTIFIABLE" if "not identifiable" in why else
            "ZERO" if "exactly 0" in why else "POORLY IDENTIFIABLE")


def _bound_note(hit: dict | None) -> str:
    if not hit:
        return ""
    return f"AT {'LOWER' if hit['side'] == 'min' else 'UPPER'} BOUND {hit['bound']:g}"


def _positive(option: str, value: int | None, minimum: int = 1) -> None:
    if value is not None and value < minimum:
        raise CommandError(f"{option}: at least {minimum}, got {value}.")


def _sobol_flags(res, j: int) -> list[str]:
    """``"!"`` beside a total Sobol index outside [0, 1] (see ``res.warnings``)."""
    if res.ST is None:
        return [""] * len(res.requirements)
    hi = res.intervals.get("ST_high")
    return ["!" if res.ST[j, a] > 1 or (res.ST[j, a] < 0 and hi is not None
                                         and hi[j, a] < 0) else ""
            for a in range(len(res.requirements))]


def _need_dask(where: str) -> None:
    import importlib.util
    if importlib.util.find_spec("dask") is None or \
            importlib.util.find_spec("distributed") is None:
        raise CommandError(f"{where}: evaluating on a Dask cluster needs the packages dask "
                           "and distributed, which are not installed (pip install "
                           "\"dask[distributed]\"); or drop it to run on local processes "
                           "(--workers N).")


def _reach_scheduler(where: str, address: str, timeout: float = 5.0) -> None:
    """A :class:`CommandError` at once when no scheduler listens at a TCP ``address``
    (``tcp://host:port`` or ``host:port``), instead of Dask's 30 s connection timeout."""
    import socket
    from urllib.parse import urlsplit
    text = address if "://" in address else f"tcp://{address}"
    parts = urlsplit(text)
    if parts.scheme not in ("tcp", "tls"):
        return                                  # other transports: Dask checks them
    try:
        host, port = parts.hostname, parts.port
    except ValueError:
        host = port = None
    if not host or port is None:
        raise CommandError(f"{where} {address}: expected the scheduler's address as "
                           "tcp://HOST:PORT, e.g. tcp://127.0.0.1:8786.")
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise CommandError(f"{where} {address}: no Dask scheduler answers there "
                           f"({reason}). Start one (`dask scheduler`, then `dask worker "
                           f"{address}`) or drop "
                           f"{'--dask' if where == '--dask' else 'the address'} to run on "
                           "local processes (--workers N).") from None


def _save(out: Path | None, doc: dict, plots, name: str) -> list[Path]:
    """Write the plots (callables taking a path, by file name) and ``doc`` as
    ``name.json`` into ``out``; record the files in ``doc``. Nothing without ``out``."""
    if out is None:
        return []
    files = [plot(out / file) for file, plot in plots.items()]
    path = out / f"{name}.json"
    write_text(path, json.dumps(jsonable(doc), indent=2))
    files.append(path)
    doc["files"] = [str(f) for f in files]
    return files


# ------------------------------------------------------------------------- sensitivity
def cmd_sensitivity(args: argparse.Namespace) -> int:
    from mechatron.estimation.config import build_sensitivity, load_config
    from mechatron.estimation.sensitivity import run_sensitivity
    _positive("--samples", args.samples, 2)
    _positive("--workers", args.workers)
    cfg = load_config(args.config)
    out = _out_dir(args.out)
    prob, dists, opts = build_sensitivity(cfg)
    n = args.samples or int(opts.get("samples", 64))
    method = args.method or opts.get("method", "sobol")
    workers = args.workers if args.workers is not None else opts.get("workers")
    address = args.dask or opts.get("address")
    if address:
        where = args.dask and "--dask" or "[sensitivity] address"
        _need_dask(where)
        _reach_scheduler(where, str(address))
    total = n * (len(dists) + 2) if method == "sobol" else n
    bar = Progress("sensitivity", total, enabled=not args.quiet)
    res = run_sensitivity(prob, dists, n=n, method=method, seed=int(opts.get("seed", 0)),
                          workers=workers, address=address, best=int(opts.get("best", 5)),
                          progress=lambda done, tot: bar.update(done, "simulations"))
    bar.close()
    doc = res.to_dict()
    files = _save(out, doc, {"sensitivity_scatter.png": res.plot_scatter,
                             "sensitivity_tornado.png": res.plot_tornado}, "sensitivity")
    if args.json:
        emit_json(doc)
        return 0
    emit(f"{cfg.get('title', args.config)}")
    emit(f"  {res.evaluations} simulations ({method}, {n} base samples) in "
         f"{res.wall_time:.2f} s: {res.throughput:.0f} simulations/s on "
         f"{res.workers or 'a Dask cluster at ' + str(address)} worker(s); "
         f"{res.failed} failed")
    measure = res.ST if res.ST is not None else res.src
    head = "total Sobol index" if res.ST is not None else "std. regression coef."
    rows = []
    for name in res.ranking:
        j = res.names.index(name)
        flag = _sobol_flags(res, j)
        rows.append([name] + [f"{measure[j, a]:+.3f}{flag[a]}"
                              for a in range(len(res.requirements))]
                    + [f"{res.spearman[j, a]:+.2f}" for a in range(len(res.requirements))])
    emit(f"  ranking by {head} (then Spearman correlation), most important first:")
    emit(table(["parameter"] + res.requirements + [f"rho {r}" for r in res.requirements],
               rows, right="".join(str(k) for k in range(1, 2 * len(res.requirements) + 1))))
    if res.warnings and res.ST is None:
        emit(f"  ! {n} samples are too few for the regression coefficients (see the "
             f"warning): use more, e.g. --samples {max(4 * n, 10 * (len(res.names) + 1))}.")
    elif res.warnings:
        emit(f"  ! {len(res.warnings)} Sobol index/indices outside [0, 1] (sampling "
             f"error; see the warnings): use more samples than {n}, e.g. --samples {4 * n}.")
    emit("  best samples (starting values for `mechatron estimate`):")
    emit(table(res.names + ["cost"],
               [[f"{b[nm]:.6g}" for nm in res.names] + [f"{b['cost']:.6g}"]
                for b in res.best[:3]]))
    for f in files:
        emit(f"  wrote {f}")
    return 0


# ---------------------------------------------------------------------------- optimize
def cmd_optimize(args: argparse.Namespace) -> int:
    from mechatron.estimation.config import build_response, load_config
    from mechatron.estimation.optimize import optimize_response, verify
    _positive("--max-iterations", args.max_iterations)
    cfg = load_config(args.config)
    out = _out_dir(args.out)
    prob = build_response(cfg)
    bar = Progress("optimize", enabled=not args.quiet)
    res = optimize_response(prob, max_iterations=args.max_iterations,
                            callback=lambda k, x, f, v: bar.update(
                                k, f"(iteration), objective {f:.4g}, violation {v:.3g}"))
    bar.close()
    before, after = verify(prob, res.initial), verify(prob, res.values)
    doc = res.to_dict()
    doc["requirements"] = [dict(r, start=b["value"], start_met=b["met"])
                           for r, b in zip(after["rows"], before["rows"])]
    doc["all_met"] = after["all_met"]
    files = _save(out, doc, {"optimize_response.png": res.plot}, "optimize")
    if args.json:
        emit_json(doc)
        return 0
    emit(f"{cfg.get('title', args.config)}")
    emit(f"  {res.iterations} SQP iterations in {res.wall_time:.2f} s; {res.message}")
    emit(table(["design variable", "start", "optimized", "note"],
               [[n, f"{a:.6g}", f"{b:.6g}", _bound_note(res.at_bound.get(n))] for n, a, b in
                zip(res.names, res.initial, res.values)], right="12"))
    if res.active:
        emit(f"  active constraints (they decide the optimum): {', '.join(res.active)}")
    emit("  requirements, checked by an independent variable-step simulation:")
    emit(table(["requirement", "limit", "start", "optimized", "met"],
               [[r["requirement"], f"{r['limit']:.4g} {r['unit']}",
                 f"{b['value']:.4g}", f"{r['value']:.4g}", "yes" if r["met"] else "NO"]
                for r, b in zip(after["rows"], before["rows"])], right="123"))
    for f in files:
        emit(f"  wrote {f}")
    return 0 if after["all_met"] else 1


# ------------------------------------------------------------------------------ parser
def add_commands(sub) -> None:
    """Add ``estimate``, ``validate``, ``sensitivity`` and ``optimize`` to the
    ``mechatron`` parser."""
    p = sub.add_parser("estimate", help="estimate parameters from measured data",
                       description="Weighted least-squares estimation of model parameters "
                                   "from one or more measured experiments, with exact "
                                   "derivatives; prints estimates, 95%% intervals, "
                                   "correlations and the fit. The problem file format is "
                                   "in docs/estimation.md.")
    p.add_argument("config", metavar="FILE.toml", help="problem file")
    p.add_argument("--out", metavar="DIR", help="write plots and the result as JSON here")
    p.add_argument("--max-iterations", type=int, default=100, metavar="N",
                   help="limit on solver iterations (default: %(default)s)")
    p.add_argument("--covariance", choices=("hac", "white"), default="hac",
                   help="interval covariance: hac (Newey-West, for correlated residuals; "
                        "default) or white (independent errors only)")
    p.add_argument("--profile", action="append", metavar="NAME[,NAME]",
                   help="also compute profile-likelihood intervals of these parameters "
                        "('all' for every one)")
    p.add_argument("--starts", type=int, metavar="K",
                   help="multi-start: fit from the starting values and K-1 points spread "
                        "inside the bounds, keep the best (file: [estimation] starts; "
                        "default 1)")
    p.add_argument("--seed", type=int, metavar="S",
                   help="seed of the multi-start points (file: [estimation] seed; "
                        "default 0)")
    p.add_argument("--sampling", choices=("lhs", "sobol"),
                   help="multi-start points: Latin hypercube (default) or Sobol "
                        "(file: [estimation] sampling)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="local worker processes for the starts (default: one per CPU, at "
                        "most K; 1: serial)")
    p.add_argument("--dask", metavar="ADDRESS",
                   help="run the starts on the Dask cluster at ADDRESS (needs "
                        "dask.distributed)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    add_json(p)
    p.set_defaults(func=cmd_estimate)

    p = sub.add_parser("validate", help="check a fitted model on other data",
                       description="Simulate the fitted model on another data set and "
                                   "report RMSE, NRMSE fit %%, the residuals' "
                                   "autocorrelation and their cross-correlation with the "
                                   "input, with plots. The fit is made from the problem "
                                   "file (or read with --fit); the data are --data files "
                                   "(read like the first [[experiments]] entry) or the "
                                   "file's [[validation]] tables.")
    p.add_argument("config", metavar="FILE.toml", help="problem file")
    p.add_argument("--data", action="append", metavar="FILE.csv",
                   help="validation data (repeatable)")
    p.add_argument("--fit", metavar="estimate.json",
                   help="fitted values from `mechatron estimate --out` (default: fit now)")
    p.add_argument("--out", metavar="DIR",
                   help="write plots, the result as JSON and an HTML report here")
    p.add_argument("--max-iterations", type=int, default=100, metavar="N",
                   help="limit on solver iterations of the fit (default: %(default)s)")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    add_json(p)
    p.set_defaults(func=cmd_validate)

    p = sub.add_parser("sensitivity", help="Monte Carlo sensitivity of parameters",
                       description="Sample parameter distributions, simulate every sample "
                                   "against the measured data (in parallel), and rank the "
                                   "parameters by Sobol indices or regression "
                                   "coefficients; list the best samples as starting "
                                   "values. Format: docs/estimation.md.")
    p.add_argument("config", metavar="FILE.toml", help="problem file")
    p.add_argument("--samples", type=int, metavar="N", help="base samples (file: samples)")
    p.add_argument("--method", choices=("random", "lhs", "sobol"),
                   help="sampling (file: method; default sobol)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="local worker processes (default: one per CPU; 1: serial)")
    p.add_argument("--dask", metavar="ADDRESS",
                   help="evaluate on the Dask cluster at ADDRESS (needs dask.distributed)")
    p.add_argument("--out", metavar="DIR", help="write plots and the result as JSON here")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    add_json(p)
    p.set_defaults(func=cmd_sensitivity)

    p = sub.add_parser("optimize", help="tune controller gains to requirements",
                       description="Response optimization: tune design variables so that "
                                   "the step response envelope and signal bounds are met, "
                                   "with exact gradients; the result is checked by an "
                                   "independent simulation. Exit code 1 if a requirement "
                                   "is not met. Format: docs/estimation.md.")
    p.add_argument("config", metavar="FILE.toml", help="problem file")
    p.add_argument("--max-iterations", type=int, default=100, metavar="N",
                   help="limit on SQP iterations (default: %(default)s)")
    p.add_argument("--out", metavar="DIR", help="write the plot and the result as JSON here")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    add_json(p)
    p.set_defaults(func=cmd_optimize)

