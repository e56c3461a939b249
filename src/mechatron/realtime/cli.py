"""Command-line entry of the real-time package: ``add_commands(sub)`` adds one command
per function below (see ``mechatron.cli.EXTENSIONS``)."""

from __future__ import annotations


def add_commands(sub) -> None:
    """Add the real-time commands (``hil``) to the ``mechatron`` sub-parsers."""
    from mechatron.realtime.hil_cli import add_hil_command
    add_hil_command(sub)
    add_rtcheck_command(sub)


def add_rtcheck_command(sub) -> None:
    """``mechatron rtcheck NAME --rate HZ [--json]``: real-time readiness of a model."""
    from mechatron.cli import MODEL_HELP, add_json, add_set
    p = sub.add_parser("rtcheck", help="check a model for real time at a sample rate",
                       description="Run a variable-step reference, report zero crossings "
                                   "by component, estimate stiffness from the Jacobian's "
                                   "eigenvalues, sweep the fixed-step methods over step "
                                   "sizes and Newton iterations, time the compiled C of "
                                   "each, and recommend a configuration for the rate.")
    p.add_argument("name", metavar="NAME", help=MODEL_HELP)
    p.add_argument("--rate", type=float, required=True, metavar="HZ",
                   help="sample rate of the real-time loop in Hz")
    p.add_argument("--variant", metavar="V", help="variant to build (default: the first)")
    add_set(p)
    p.add_argument("--t-stop", type=float, metavar="T",
                   help="length of the check in s (default: the experiment's)")
    p.add_argument("--tolerance", type=float, default=1e-3, metavar="E",
                   help="largest error relative to each output's peak (default: "
                        "%(default)g)")
    p.add_argument("--min-margin", type=float, default=0.5, metavar="F",
                   help="smallest share of the period left after the steps (default: "
                        "%(default)g)")
    p.add_argument("--solvers", metavar="S,S", help="comma-separated methods to sweep "
                   "(default: all)")
    p.add_argument("--no-timing", action="store_true",
                   help="skip compiling and timing the C (faster)")
    add_json(p)
    p.set_defaults(func=cmd_rtcheck)


def cmd_rtcheck(args) -> int:
    import math

    from mechatron.cli import CommandError, _parse_sets, emit, emit_json, progress, table
    from mechatron.models.user import entry_for
    from mechatron.realtime.rtcheck import rtcheck

    entry = entry_for(args.name)
    params = _parse_sets(args.set, entry)
    variant = args.variant or entry.default_variant
    if not (math.isfinite(args.rate) and args.rate > 0):
        raise CommandError(f"--rate: a sample rate in Hz > 0, got {args.rate!r}.")
    model = entry.build(variant, **params)
    outputs = list(entry.output_paths(variant).values())
    t_stop = args.t_stop if args.t_stop is not None else entry.experiment.t_stop
    solvers = [s.strip() for s in args.solvers.split(",")] if args.solvers else None
    with progress(args, desc="rtcheck", unit="run") as bar:
        def tell(done, total, what):
            if bar.total != total:
                bar.total = total
                bar.refresh()
            bar.set_postfix_str(what, refresh=False)
            bar.update(done - bar.n)
        r = rtcheck(model, rate=args.rate, t_stop=t_stop, outputs=outputs,
                    solvers=solvers, tolerance=args.tolerance,
                    min_margin=args.min_margin, measure=not args.no_timing, progress=tell)
    if args.json:
        emit_json({"variant": variant, "set": params, **r.as_dict()})
        return 0
    emit(f"{entry.name} ({variant}) at {args.rate:g} Hz (T = {1 / args.rate:.3g} s), "
         f"{r.t_stop:g} s; error on {', '.join(r.outputs)}")
    ref = r.reference
    emit(f"reference: {ref['solver']}, rtol {ref['rtol']:g}, {ref['steps']} steps, "
         f"{ref['points']} comparison points")
    if r.zero_crossings:
        emit("zero crossings by component:")
        emit(table(["component", "events", "last at [s]"],
                   [[k, v, f"{r.event_times.get(k, float('nan')):.6g}"]
                    for k, v in sorted(r.zero_crossings.items())], right="12"))
    else:
        emit("zero crossings: none")
    emit("stiffness:")
    for line in r.reasons[:-1]:
        emit(f"  {line}")
    rows = []
    for c in r.candidates:
        err = "diverged" if not math.isfinite(c.max_error) else f"{c.max_error:.2e}"
        rows.append([c.solver, f"{c.dt * 1e6:.4g}", c.iterations or "-", err,
                     "-" if c.ns_per_step is None else f"{c.ns_per_step:.0f}",
                     "-" if c.margin is None else f"{c.margin:.1%}",
                     "ok" if c.ok else ("unstable" if not c.stable else "")])
    emit(f"\nsweep (error relative to each output's peak; margin: share of the period "
         f"left at {args.rate:g} Hz):")
    emit(table(["solver", "step [us]", "iter", "max error", "ns/step", "margin", ""],
               rows, right="12345"))
    emit(r.reasons[-1])
    return 0
