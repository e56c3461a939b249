"""``mechatron linearize``: a model's linearization at an operating point.

``mechatron linearize NAME --input P [--input ...] [--output Y ...] [--at T | --trim Y=V
--free P] [--bode FILE.png] [--json]`` prints the state-space matrices, the poles and
the DC gain of the model linearized from parameters or external inputs ``P`` to logged
variables ``Y``, and draws a Bode plot of each input-output pair.
"""

from __future__ import annotations

import argparse

import numpy as np

__all__ = ["add_commands", "cmd_linearize"]


def add_commands(sub) -> None:
    """Add the ``linearize`` subcommand to the ``mechatron`` parser."""
    from mechatron.cli import MODEL_HELP, add_json, add_set
    p = sub.add_parser("linearize", help="linearize a model at an operating point",
                       description="Linearize one variant of a model at an operating point "
                                   "(the initial point, the state at a time, or a trimmed "
                                   "equilibrium) from exact Jacobians; print A, B, C, D, "
                                   "the poles and the DC gain; draw a Bode plot.")
    p.add_argument("name", metavar="NAME", help=MODEL_HELP)
    p.add_argument("--variant", metavar="V", help="variant to build (default: the first)")
    add_set(p)
    p.add_argument("--input", action="append", default=[], metavar="P", required=True,
                   help="a parameter or external input that becomes an input, by instance "
                        "path (e.g. source.V). Repeatable.")
    p.add_argument("--output", action="append", default=[], metavar="Y",
                   help="a logged variable that becomes an output (default: the states). "
                        "Repeatable.")
    p.add_argument("--at", type=float, metavar="T",
                   help="linearize at the state a default simulation reaches at T s "
                        "(default: the initial point)")
    p.add_argument("--trim", action="append", default=[], metavar="Y=VALUE",
                   help="linearize at the equilibrium where Y holds VALUE (with one --free "
                        "per --trim). Repeatable.")
    p.add_argument("--free", action="append", default=[], metavar="P",
                   help="a parameter or input that trim may move")
    p.add_argument("--bode", metavar="FILE.png", help="write a Bode plot")
    add_json(p)
    p.set_defaults(func=cmd_linearize)


def _trim_targets(items) -> dict[str, float]:
    from mechatron.cli import CommandError
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            raise CommandError(f"--trim {item}: expected NAME=NUMBER (SI units), e.g. "
                               "--trim inertia.w=100.") from None
        if not sep or not name.strip():
            raise CommandError(f"--trim {item}: expected NAME=NUMBER.")
    return out


def cmd_linearize(args: argparse.Namespace) -> int:
    import mechatron as mt
    from mechatron.analysis.linear import linear_matrices, trim
    from mechatron.cli import (EXIT_OK, CommandError, emit, emit_json, new_figure, num,
                               output_path, parse_sets, table)
    from mechatron.models.user import entry_for
    entry = entry_for(args.name)
    params = parse_sets(args.set, entry)
    variant = args.variant or entry.default_variant
    bode = output_path(args.bode, "--bode", (".png", ".svg", ".pdf")) if args.bode else None
    if args.trim and args.at is not None:
        raise CommandError("--at and --trim choose the operating point two ways; give one.")
    cm = mt.compile_model(entry.build(variant, **params))
    at = args.at
    if args.trim:
        at = trim(cm, targets=_trim_targets(args.trim), free=args.free)
    outputs = args.output or None
    A, B, C, D, op = linear_matrices(cm, at, inputs=args.input, outputs=outputs)
    outputs = outputs or list(cm.state_names)
    poles = np.linalg.eigvals(A) if A.size else np.zeros(0)
    try:
        gain = D - C @ np.linalg.solve(A, B) if A.size else D
    except np.linalg.LinAlgError:
        gain = None       # a pole at the origin: no finite DC gain
    files = {}
    if bode is not None:
        files["bode"] = str(_bode(A, B, C, D, args.input, outputs, bode, new_figure))
    if args.json:
        emit_json({"model": entry.name, "variant": variant, "states": cm.state_names,
                   "inputs": args.input, "outputs": outputs, "A": A.tolist(),
                   "B": B.tolist(), "C": C.tolist(), "D": D.tolist(),
                   "poles": [[p.real, p.imag] for p in poles],
                   "dc_gain": None if gain is None else gain.tolist(),
                   "operating_point": {"t": op.t, "states": dict(zip(cm.state_names,
                                                                     op.x[:cm.nx].tolist())),
                                       "inputs": {u: float(op.p[cm.param_names.index(u)])
                                                  for u in args.input}},
                   "files": files})
        return EXIT_OK
    emit(f"{entry.name} ({variant}) linearized at t = {op.t:g} s; "
         f"{len(cm.state_names)} states, inputs {', '.join(args.input)}")
    emit("\noperating point:")
    emit(table(["name", "value"], [[n, num(v)] for n, v in zip(cm.state_names, op.x)] +
               [[u, num(op.p[cm.param_names.index(u)])] for u in args.input], right="1"))
    for label, M, rows, cols in (("A", A, cm.state_names, cm.state_names),
                                 ("B", B, cm.state_names, args.input),
                                 ("C", C, outputs, cm.state_names),
                                 ("D", D, outputs, args.input)):
        emit(f"\n{label}:")
        emit(table(["", *cols], [[r, *[num(v) for v in row]] for r, row in zip(rows, M)],
                   right="".join(str(k + 1) for k in range(min(len(cols), 9)))))
    emit("\npoles: " + ", ".join(f"{p.real:.6g}{p.imag:+.6g}j" if p.imag else f"{p.real:.6g}"
                                 for p in poles))
    if gain is not None:
        emit("\nDC gain:")
        emit(table(["", *args.input], [[r, *[num(v) for v in row]]
                                       for r, row in zip(outputs, gain)]))
    for kind, path in files.items():
        emit(f"\nwrote {path} (Bode plot)")
    return EXIT_OK


def _bode(A, B, C, D, inputs, outputs, path, new_figure):
    """Magnitude (dB) and phase (deg) of every input-output pair over the frequencies the
    poles span."""
    from mechatron._io import save_figure
    poles = np.abs(np.linalg.eigvals(A)) if A.size else np.array([1.0])
    poles = poles[poles > 0] if np.any(poles > 0) else np.array([1.0])
    w = np.logspace(np.floor(np.log10(poles.min())) - 2,
                    np.ceil(np.log10(poles.max())) + 2, 400)
    n = A.shape[0]
    H = np.array([C @ np.linalg.solve(1j * wk * np.eye(n) - A, B) + D for wk in w])
    fig, (mag, phase) = new_figure(2, width=8.0, height=2.6)
    for j, u in enumerate(inputs):
        for i, y in enumerate(outputs):
            h = H[:, i, j]
            label = f"{u} -> {y}"
            mag.semilogx(w, 20 * np.log10(np.maximum(np.abs(h), 1e-300)), label=label)
            phase.semilogx(w, np.degrees(np.unwrap(np.angle(h))), label=label)
    mag.set_ylabel("magnitude (dB)")
    phase.set_ylabel("phase (deg)")
    phase.set_xlabel("angular frequency (rad/s)")
    mag.legend(fontsize=7)
    mag.grid(True, which="both", alpha=0.3)
    phase.grid(True, which="both", alpha=0.3)
    return save_figure(fig, path, dpi=110)
