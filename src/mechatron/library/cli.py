"""``mechatron library``: the component catalog on the command line (Simscape's library
browser).

``mechatron library [--domain D] [--json] [--docs DIR]`` lists every component of the
library by section (domain), with its ports, parameters (units, defaults) and one-line
description; ``--domain`` keeps one section, ``--docs`` (re)writes the domain pages.
"""

from __future__ import annotations

import argparse

from mechatron.library import catalog

__all__ = ["add_commands", "cmd_library"]


def add_commands(sub) -> None:
    """Add the ``library`` subcommand to the ``mechatron`` parser."""
    from mechatron.cli import add_json
    p = sub.add_parser("library", help="list the component library by domain",
                       description="List every component of the library by domain "
                                   "(library section): ports with their domains, "
                                   "parameters with units and defaults, and a one-line "
                                   "description.")
    p.add_argument("--domain", metavar="D",
                   help="only the components of section D (e.g. rotational, electrical)")
    p.add_argument("--docs", metavar="DIR",
                   help="also write the domain pages DIR/<domain>.md and DIR/README.md")
    add_json(p)
    p.set_defaults(func=cmd_library)


def cmd_library(args: argparse.Namespace) -> int:
    from mechatron.cli import EXIT_FAILURE, EXIT_OK, CommandError, emit, emit_json, table
    secs = catalog.sections()
    names = [s.name for s in secs]
    if args.domain is not None:
        if args.domain not in names:
            raise CommandError(f"--domain {args.domain}: no such library domain. Valid "
                               f"domains: {', '.join(names)}.")
        secs = [s for s in secs if s.name == args.domain]
    written = catalog.write_docs(args.docs) if args.docs else []
    errors = catalog.import_errors()
    total = sum(len(s.components) for s in secs)
    if args.json:
        emit_json({"count": total, "domains": [s.as_dict() for s in secs],
                   "import_errors": errors, "docs": [str(p) for p in written]})
        return EXIT_FAILURE if errors else EXIT_OK
    for s in secs:
        d = s.domain
        head = f"{s.name} ({len(s.components)} components)"
        if d is not None:
            head += f": across {d.across}, through {d.through}"
        elif s.domains:
            head += f": ports of {', '.join(s.domains)}"
        emit(head)
        rows = [(c.name, ", ".join(p.label() for p in c.ports),
                 ", ".join(p.label() for p in c.parameters) or "-", c.description)
                for c in s.components]
        if rows:
            emit(table(("component", "ports", "parameters", "description"), rows))
        emit()
    emit(f"{total} components in {len(secs)} domain(s).")
    if written:
        emit(f"wrote {len(written)} pages to {args.docs}")
    for module, err in errors.items():
        emit(f"import error in {module}: {err}")
    return EXIT_FAILURE if errors else EXIT_OK
