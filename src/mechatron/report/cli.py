"""``mechatron diagram`` and ``mechatron report`` (see :mod:`mechatron.cli`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from mechatron.cli import MODEL_HELP, CommandError, add_json, emit, emit_json
from mechatron.models.user import entry_for

__all__ = ["add_commands"]


def cmd_diagram(args: argparse.Namespace) -> int:
    from mechatron.report.diagram import FORMATS, write_diagram
    from mechatron.report.html import diagram_variant
    entry = entry_for(args.name)
    out = Path(args.out)
    if out.suffix.lower() not in FORMATS:
        raise CommandError(f"--out {out}: use one of {', '.join(FORMATS)}.")
    if not out.parent.exists():
        raise FileNotFoundError(f"--out {out}: the folder '{out.parent}' does not exist.")
    variant = args.variant or diagram_variant(entry)
    if variant is None:
        raise CommandError(f"model '{entry.name}': every variant is written as equations; "
                           "there is no network to draw.")
    model = entry.build(variant)
    if not model.components:
        raise CommandError(f"model '{entry.name}', variant '{variant}' is written as "
                           "equations; there is no network to draw. Try "
                           f"--variant {diagram_variant(entry) or '?'}.")
    write_diagram(model, out, entry.name)
    if args.json:
        emit_json({"model": entry.name, "variant": variant, "out": str(out)})
    else:
        emit(f"wrote {out} ({entry.name}, variant '{variant}')")
    return 0


def cmd_report(args: argparse.Namespace) -> int:
    from mechatron.report.html import write_report
    entry = entry_for(args.name)
    path = write_report(entry, args.out)
    if args.json:
        emit_json({"model": entry.name, "out": str(path)})
    else:
        emit(f"wrote {path} ({entry.name}: diagram, parameters, plots, variants, profile)")
    return 0


def add_commands(sub) -> None:
    p = sub.add_parser("diagram", help="draw a model's network",
                       description="Draw the network of a database model: its parts with "
                                   "their ports, connections in the colour of their domain, "
                                   "and a legend (Graphviz).")
    p.add_argument("name", metavar="NAME", help=MODEL_HELP)
    p.add_argument("--out", required=True, metavar="FILE",
                   help="output file: .svg, .png, .pdf, or .dot (no Graphviz needed)")
    p.add_argument("--variant", metavar="V",
                   help="variant to draw (default: the first one built from parts)")
    add_json(p)
    p.set_defaults(func=cmd_diagram)

    p = sub.add_parser("report", help="write a model's HTML report",
                       description="Write one self-contained HTML page about a database "
                                   "model: description, diagram, parameter table, plots of "
                                   "the default experiment, variants compared, solver "
                                   "profile.")
    p.add_argument("name", metavar="NAME", help=MODEL_HELP)
    p.add_argument("--out", required=True, metavar="FILE.html", help="output file")
    add_json(p)
    p.set_defaults(func=cmd_report)
