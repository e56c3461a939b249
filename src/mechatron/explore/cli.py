"""``mechatron explore``: the explorer, a local web app (see :mod:`mechatron.explore`).

``mechatron explore [MODEL | results.parquet | results.csv | estimate.json] [--port N]
[--no-browser]`` opens a model (simulated with its default experiment), a simlog or the
result of an estimation, sensitivity study or optimization, serves the page on
127.0.0.1 and opens it in the browser; Ctrl-C stops it.
"""

from __future__ import annotations

import argparse
from pathlib import Path

__all__ = ["add_commands", "cmd_explore"]


def add_commands(sub) -> None:
    """Add the ``explore`` subcommand to the ``mechatron`` parser."""
    p = sub.add_parser("explore", help="browse models and results in the browser",
                       description="Start the explorer, a local web app: the model "
                                   "database and component library with diagrams, a "
                                   "results explorer (variables by instance path, plots "
                                   "with zoom and cursor, runs overlaid, export), and live "
                                   "parameter changes. It listens on 127.0.0.1 only and "
                                   "fetches nothing from the internet.")
    p.add_argument("target", nargs="?", metavar="MODEL|FILE",
                   help="a model to simulate and open (a database name, see `mechatron "
                        "models`, or path/to/model.py[:Class]), a simlog to open (.csv or "
                        ".parquet), or the .json result of `mechatron estimate`, "
                        "`sensitivity` or `optimize`")
    p.add_argument("--port", type=int, default=0, metavar="N",
                   help="port to listen on (default: a free one)")
    p.add_argument("--no-browser", action="store_true",
                   help="do not open a browser; print the address only")
    p.set_defaults(func=cmd_explore)


def cmd_explore(args: argparse.Namespace) -> int:
    import webbrowser

    from mechatron.cli import EXIT_OK, CommandError, emit
    from mechatron.explore.server import ExploreServer
    from mechatron.explore.workspace import Workspace
    from mechatron.results import SUFFIXES

    if not 0 <= args.port <= 65535:
        raise CommandError(f"--port must be 0 to 65535, got {args.port}.")
    workspace = Workspace()
    startup: dict = {}
    target = args.target
    if target:
        if Path(target).suffix.lower() == ".json":
            study = workspace.load_study(Path(target))
            startup = {"view": "studies", "study": study["id"]}
            emit(f"opened {target}: {study['kind']} result")
        elif Path(target).suffix.lower() in SUFFIXES:
            run = workspace.load(Path(target))
            startup = {"view": "results", "run": run.id}
            emit(f"opened {target}: {run.summary()['n_vars']} variables, "
                 f"{run.summary()['n_t']} time points")
        else:
            workspace.model(target)                    # unknown name: error, exit 2
            emit(f"compiling and simulating {target} ...")
            run = workspace.simulate(target)
            startup = {"view": "results", "run": run.id, "model": target}
    try:
        server = ExploreServer(workspace, port=args.port, startup=startup)
    except OSError as exc:
        raise CommandError(f"--port {args.port}: cannot listen ({exc.strerror or exc}). "
                           "Choose another port, or 0 for any free one.") from None
    emit(f"explorer at {server.url} (Ctrl-C stops it)")
    if not args.no_browser:
        webbrowser.open(server.url)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        emit("stopped")
    finally:
        server.server_close()
    return EXIT_OK
