"""The explorer: a local web app to browse the model database and the component library,
plot simulation logs, and change parameters live.

``mechatron explore [MODEL | results.parquet | results.csv] [--port N] [--no-browser]``
starts it (see :mod:`mechatron.explore.cli`); :class:`ExploreServer` runs it from Python::

    from mechatron.explore import ExploreServer
    server = ExploreServer(port=0)      # 127.0.0.1, a free port
    server.start()                      # in a thread; server.url is the address
    ...
    server.shutdown()

The parts: :mod:`~mechatron.explore.workspace` (runs, compiled models kept between
parameter changes, the database and library answers), :mod:`~mechatron.explore.server`
(the HTTP server and its JSON API), :mod:`~mechatron.explore.decimate` (min/max per pixel
column), and the page in ``templates/`` (HTML, CSS and the plotting script, no external
library). See docs/explore.md.
"""

from mechatron.explore.decimate import decimate
from mechatron.explore.server import ExploreServer
from mechatron.explore.workspace import Run, Workspace

__all__ = ["ExploreServer", "Workspace", "Run", "decimate"]
