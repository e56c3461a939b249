"""The explorer's HTTP server: the page, its scripts, and a JSON API over a
:class:`~mechatron.explore.workspace.Workspace`.

Built on the standard library (:class:`http.server.ThreadingHTTPServer`): one request per
thread, so a long simulation does not block the browsing of another run. The server binds
to 127.0.0.1 and answers only requests addressed to that host and sent by its own page
(another site open in the browser can neither reach it through DNS rebinding nor post
to it); nothing is fetched from elsewhere, the page and its plotting code are files of
this package (``templates/``).

API (``GET`` unless marked; errors are ``{"error": message}`` with status 400 for bad
input, 404 for an unknown address, 500 for a bug; the server keeps serving):

=============================================  ==========================================
``/api/state``                                 runs, and what the command line opened
``/api/models``                                the database
``/api/models/NAME``                           one entry (parameters with provenance...)
``/api/models/NAME/parts?variant=V``           its parts with their documentation
``/api/models/NAME/diagram?variant=V``         the schematic (SVG)
``/api/models/NAME/parameters?variant=V``      the compiled model's parameters
``/api/library``                               the component library by section
``POST /api/simulate``                         ``{model, variant, params, t_stop, replace}``
``POST /api/open``                             ``{path}``: a .csv/.parquet simlog, or the
                                               .json of estimate/sensitivity/optimize
``/api/studies``                               the studies opened
``/api/studies/ID/image/NAME``                 one of a study's plots (PNG)
``POST /api/upload?filename=F``                the body is a simlog file
``/api/runs``                                  every run
``/api/runs/ID/variables``                     names, units, descriptions (no values)
``/api/runs/ID/signal?name=&width=&t0=&t1=``   one variable, decimated to ``width`` px
``  ...&minus=RUN``                              its difference to the same one of RUN
``/api/runs/ID/export?name=..&format=&t0=&t1``  a selection as CSV or Parquet
``DELETE /api/runs/ID``                        forget a run
``POST /api/scenario``, ``GET /api/scenario``  a scripted page's report (browser tests)
=============================================  ==========================================
"""

from __future__ import annotations

import json
import logging
import math
import threading
import traceback
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from urllib.parse import parse_qs, unquote, urlsplit

import numpy as np

from mechatron.errors import MechatronError
from mechatron.explore.workspace import Workspace

__all__ = ["ExploreServer", "TEMPLATES"]

log = logging.getLogger("mechatron.explore")

#: The page and its scripts.
TEMPLATES = Path(__file__).parent / "templates"
_TYPES = {".html": "text/html; charset=utf-8", ".js": "text/javascript; charset=utf-8",
          ".css": "text/css; charset=utf-8", ".svg": "image/svg+xml"}
#: Largest upload accepted, bytes.
MAX_UPLOAD = 512 * 1024 * 1024
#: Input errors: reported to the page as such (status 400), not as bugs.
USER_ERRORS = (MechatronError, ValueError, TypeError, KeyError, OSError)


class _NotFound(Exception):
    pass


class ExploreServer(ThreadingHTTPServer):
    """The explorer on ``host:port`` (port 0: a free one, see :attr:`url`).

    Parameters
    ----------
    workspace : Workspace, optional
        The state to serve (a new one by default).
    host : str
        Address to bind; the default keeps the server private to this machine.
    port : int
        Port, or 0 for any free one.
    startup : dict, optional
        What the page opens first, e.g. ``{"run": "r1"}`` or ``{"model": "dc_motor"}``.
    """

    daemon_threads = True

    def __init__(self, workspace: Workspace | None = None, host: str = "127.0.0.1",
                 port: int = 0, startup: dict | None = None):
        self.workspace = workspace or Workspace()
        self.startup = dict(startup or {})
        self.scenario_report: dict | None = None
        super().__init__((host, port), _Handler)

    @property
    def url(self) -> str:
        host, port = self.server_address[:2]
        return f"http://{host}:{port}/"

    def start(self) -> threading.Thread:
        """Serve in a background thread (for tests and scripts); :meth:`shutdown` stops."""
        thread = threading.Thread(target=self.serve_forever, name="mechatron-explore",
                                  daemon=True)
        thread.start()
        return thread


def _finite(values) -> list:
    """A JSON-ready list: NaN and infinities become ``null``."""
    return [v if math.isfinite(v) else None for v in np.asarray(values, float).tolist()]


def _plain(obj):
    if isinstance(obj, dict):
        return {str(k): _plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _finite(obj)
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if obj is None or isinstance(obj, str):
        return obj
    return str(obj)


def _float(query: dict, key: str) -> float | None:
    raw = query.get(key, [""])[0].strip()
    if not raw:
        return None
    try:
        value = float(raw)
    except ValueError:
        raise ValueError(f"query parameter {key}: expected a number, got '{raw}'.") from None
    if not math.isfinite(value):
        raise ValueError(f"query parameter {key}: expected a finite number, got '{raw}'.")
    return value


def _one(query: dict, key: str, default: str | None = None) -> str | None:
    values = query.get(key)
    return values[0] if values else default


class _Handler(BaseHTTPRequestHandler):
    server: ExploreServer
    protocol_version = "HTTP/1.1"

    # -------------------------------------------------------------- plumbing
    def log_message(self, format, *args):  # noqa: A002 - the base class's name
        log.debug("%s %s", self.address_string(), format % args)

    def _send(self, status: int, body: bytes, ctype: str, extra: dict | None = None):
        self.send_response(status)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        for k, v in (extra or {}).items():
            self.send_header(k, v)
        self.end_headers()
        if self.command != "HEAD":
            self.wfile.write(body)

    def _json(self, obj, status: int = 200):
        body = json.dumps(_plain(obj), allow_nan=False, separators=(",", ":")).encode()
        self._send(status, body, "application/json")

    def _error(self, status: int, message: str):
        self._json({"error": message}, status)

    def _body(self) -> bytes:
        length = int(self.headers.get("Content-Length") or 0)
        if length > MAX_UPLOAD:
            raise ValueError(f"upload of {length} bytes refused: more than "
                             f"{MAX_UPLOAD // 2**20} MiB.")
        return self.rfile.read(length) if length else b""

    def _json_body(self) -> dict:
        raw = self._body()
        try:
            data = json.loads(raw or b"{}")
        except json.JSONDecodeError as exc:
            raise ValueError(f"request body: not JSON ({exc}).") from None
        if not isinstance(data, dict):
            raise ValueError("request body: expected a JSON object.")
        return data

    def _host_ok(self) -> bool:
        """The request is addressed to this machine and, when a browser says which page
        sent it (``Origin``), comes from the explorer's own page: another site open in the
        browser can neither read from the explorer nor make it simulate or open files."""
        local = ("127.0.0.1", "localhost", "::1", self.server.server_address[0])
        host = (self.headers.get("Host") or "").rsplit(":", 1)[0].strip("[]").lower()
        if host not in local:
            return False
        origin = self.headers.get("Origin")
        if origin is None:
            return True
        parts = urlsplit(origin)
        return parts.scheme == "http" and (parts.hostname or "") in local and \
            parts.port == self.server.server_address[1]

    def _dispatch(self):
        if not self._host_ok():
            self._error(403, f"request for host '{self.headers.get('Host')}' from "
                             f"'{self.headers.get('Origin') or 'no page'}' refused: the "
                             "explorer answers its own page on this machine only "
                             "(127.0.0.1).")
            return
        split = urlsplit(self.path)
        parts = [unquote(p) for p in split.path.split("/") if p]
        query = parse_qs(split.query, keep_blank_values=True)
        try:
            self._route(self.command, parts, query)
        except _NotFound as exc:
            self._error(404, str(exc))
        except USER_ERRORS as exc:
            message = exc.args[0] if isinstance(exc, KeyError) and exc.args else str(exc)
            self._error(400, str(message))
        except Exception as exc:  # noqa: BLE001 - a bug: report it, keep serving
            log.error("explore: %s %s failed:\n%s", self.command, self.path,
                      traceback.format_exc())
            self._error(500, f"internal error ({type(exc).__name__}: {exc}); this is a bug "
                             "in Mechatron, please report it.")

    do_GET = do_POST = do_DELETE = do_HEAD = _dispatch

    # -------------------------------------------------------------- routes
    def _route(self, method: str, parts: list[str], query: dict):
        ws = self.server.workspace
        if method in ("GET", "HEAD") and not parts:
            return self._static("index.html")
        if method in ("GET", "HEAD") and len(parts) == 2 and parts[0] == "static":
            return self._static(parts[1])
        if not parts or parts[0] != "api":
            raise _NotFound(f"no page at {self.path}.")
        route = parts[1:]
        variant = _one(query, "variant") or None
        if method == "GET":
            if route == ["state"]:
                return self._json({"startup": self.server.startup, "runs": ws.runs()})
            if route == ["models"]:
                return self._json(ws.models())
            if route == ["library"]:
                return self._json(ws.library())
            if route == ["runs"]:
                return self._json(ws.runs())
            if route == ["scenario"]:
                return self._json(self.server.scenario_report or {})
            if route == ["studies"]:
                return self._json(ws.studies())
            if len(route) == 4 and route[0] == "studies" and route[2] == "image":
                return self._send(200, ws.study_image(route[1], route[3]), "image/png")
            if len(route) == 2 and route[0] == "models":
                return self._json(ws.model(route[1]))
            if len(route) == 3 and route[0] == "models":
                name, what = route[1], route[2]
                if what == "parts":
                    return self._json(ws.parts(name, variant))
                if what == "parameters":
                    return self._json(ws.parameters(name, variant))
                if what == "diagram":
                    svg = ws.diagram(name, variant)
                    return self._send(200, svg.encode(), _TYPES[".svg"])
            if len(route) == 3 and route[0] == "runs":
                run_id, what = route[1], route[2]
                if what == "variables":
                    return self._json(ws.variables(run_id))
                if what == "signal":
                    name = _one(query, "name")
                    if not name:
                        raise ValueError("signal: give the variable as ?name=PATH.")
                    width = _one(query, "width", "800")
                    try:
                        width = int(width)
                    except ValueError:
                        raise ValueError(f"signal: width must be a whole number of pixels, "
                                         f"got '{width}'.") from None
                    return self._json(ws.signal(run_id, name, width, _float(query, "t0"),
                                                _float(query, "t1"),
                                                _one(query, "minus") or None))
                if what == "export":
                    fmt = _one(query, "format", "csv")
                    data = ws.export(run_id, query.get("name", []), fmt,
                                     _float(query, "t0"), _float(query, "t1"))
                    label = ws.run(run_id).label
                    stem = "".join(c if c.isalnum() or c in "-_" else "_" for c in label)
                    return self._send(200, data, "text/csv" if fmt == "csv" else
                                      "application/vnd.apache.parquet",
                                      {"Content-Disposition":
                                       f'attachment; filename="{stem[:60]}.{fmt}"'})
        elif method == "POST":
            if route == ["simulate"]:
                data = self._json_body()
                model = data.get("model")
                if not isinstance(model, str) or not model:
                    raise ValueError("simulate: give the model by name, "
                                     "{\"model\": \"dc_motor\"}.")
                params = data.get("params") or {}
                if not isinstance(params, dict):
                    raise ValueError("simulate: params must map instance paths to values.")
                run = ws.simulate(model, data.get("variant") or None, params,
                                  data.get("t_stop"), data.get("label"), data.get("replace"))
                return self._json(run.summary())
            if route == ["open"]:
                path = self._json_body().get("path")
                if not isinstance(path, str) or not path.strip():
                    raise ValueError("open: give the file as {\"path\": \"run.csv\"}.")
                path = Path(path.strip()).expanduser()
                if path.suffix.lower() == ".json":
                    return self._json({"study": ws.load_study(path)})
                return self._json(ws.load(path).summary())
            if route == ["upload"]:
                filename = _one(query, "filename", "")
                return self._json(ws.load_bytes(self._body(), filename).summary())
            if route == ["scenario"]:
                self.server.scenario_report = self._json_body()
                return self._json({"ok": True})
        elif method == "DELETE" and len(route) == 2 and route[0] == "runs":
            ws.remove(route[1])
            return self._json({"ok": True})
        raise _NotFound(f"no API {method} {self.path}.")

    def _static(self, name: str):
        path = TEMPLATES / name
        if "/" in name or name.startswith(".") or path.suffix not in _TYPES \
                or not path.is_file():
            raise _NotFound(f"no file '{name}' in the explorer.")
        self._send(200, path.read_bytes(), _TYPES[path.suffix])
