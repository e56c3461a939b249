"""Models from outside the database: a user's Python file, or an importable class.

Wherever a database name is accepted (the commands, ``[model] name`` of a problem file),
two more forms are:

``path/to/file.py`` or ``path/to/file.py:ClassName``
    A Python file of the user's. The file is run (as ``python file.py`` would run it) and
    its :class:`~mechatron.Component` subclass is taken; when the file defines several,
    ``:ClassName`` chooses one.
``package.module:ClassName``
    A class of an importable module. The object must be a concrete
    :class:`~mechatron.Component` subclass; this is checked before anything is called, so
    that ``os:abort`` or ``shutil:rmtree`` are refused, not run.

:func:`entry_for` turns either into a :class:`~mechatron.models.ModelEntry` (one variant,
named ``model``), so that the commands treat it like a database entry: ``--set`` sets
the class's own parameters, the outputs are its own variables (or, when it declares none,
the states of its default build), and the experiment is the class attribute ``experiment`` (a dict of
:class:`~mechatron.models.Experiment` fields, e.g. ``{"t_stop": 0.5}``; default: 1 s).
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import inspect
import logging
import math
import re
import sys
from pathlib import Path

from mechatron.core import Component
from mechatron.core.declarations import Input, Parameter, Variable
from mechatron.errors import ModelError
from mechatron.models.entry import Experiment, ModelEntry, ParameterInfo
from mechatron.units import to_si

__all__ = ["is_model_file", "load_model_file", "import_component", "component_class",
           "entry_for", "entry_from_class"]

log = logging.getLogger(__name__)

_FILE = re.compile(r"^(?P<path>.+\.py)(?::(?P<cls>[A-Za-z_]\w*))?$")
_IMPORT = re.compile(r"^(?P<module>[A-Za-z_][\w.]*):(?P<cls>[A-Za-z_]\w*)$")

#: The variant name of a model that is not from the database.
VARIANT = "model"


def is_model_file(spec: str) -> bool:
    """Whether ``spec`` names a Python file (``file.py`` or ``file.py:ClassName``)."""
    return bool(_FILE.match(spec))


def _concrete(obj) -> bool:
    return isinstance(obj, type) and issubclass(obj, Component) and not obj._partial


def load_model_file(spec: str, *, base: str | Path | None = None) -> type[Component]:
    """The :class:`~mechatron.Component` subclass of a user's file.

    Parameters
    ----------
    spec : str
        ``path/to/file.py`` or ``path/to/file.py:ClassName``.
    base : path, optional
        Folder that a relative path is relative to (default: the current folder).

    Raises
    ------
    ModelError
        If the file does not exist, defines no component class or several without a
        ``:ClassName``, or ``ClassName`` is not a component class of the file.
    """
    m = _FILE.match(spec)
    if m is None:
        raise ModelError(f"{spec}: not a Python file; give path/to/file.py or "
                         "path/to/file.py:ClassName.", path=spec)
    path = Path(m["path"]).expanduser()
    if base is not None and not path.is_absolute():
        path = Path(base) / path
    if not path.is_file():
        raise ModelError(f"{spec}: no such file ({path}). Give the path of a Python file "
                         "that defines a mechatron Component subclass.", path=spec)
    try:
        module = _run_file(path)
    except Exception as exc:       # an error in the user's file, not in Mechatron
        where = ""
        if isinstance(exc, SyntaxError) and exc.lineno:
            where = f" (line {exc.lineno})"
        raise ModelError(f"{spec}: running the file failed{where}: {type(exc).__name__}: "
                         f"{exc}. Fix the file; `python {path}` shows the traceback.",
                         path=spec) from exc
    own = {name: obj for name, obj in vars(module).items()
           if _concrete(obj) and obj.__module__ == module.__name__}
    if m["cls"]:
        obj = getattr(module, m["cls"], None)
        if not _concrete(obj):
            what = ("not defined in the file" if obj is None else
                    f"a {type(obj).__name__}, not a concrete mechatron Component subclass")
            raise ModelError(f"{spec}: '{m['cls']}' is {what}. Component classes of the "
                             f"file: {', '.join(own) or '(none)'}.", path=spec)
        return obj
    if len(own) == 1:
        return next(iter(own.values()))
    if not own:
        raise ModelError(f"{spec}: the file defines no mechatron Component subclass; "
                         "define one (class MyModel(mt.Component): ...), see "
                         "docs/modeling.md.", path=spec)
    raise ModelError(f"{spec}: the file defines {len(own)} component classes "
                     f"({', '.join(own)}); choose one with {m['path']}:ClassName, e.g. "
                     f"{m['path']}:{list(own)[-1]}.", path=spec)


def _run_file(path: Path):
    """Run the file ``path`` as a module of its own name (derived from its path)."""
    path = path.resolve()
    digest = hashlib.sha1(str(path).encode()).hexdigest()[:12]
    stem = re.sub(r"\W", "_", path.stem)
    name = f"mechatron_user_{stem}_{digest}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module          # dataclasses and pickle look classes up here
    log.info("loading model file %s", path)
    try:
        spec.loader.exec_module(module)
    except BaseException:
        sys.modules.pop(name, None)
        raise
    return module


def import_component(spec: str) -> type[Component]:
    """The class named by ``package.module:ClassName``, which must be a concrete
    :class:`~mechatron.Component` subclass (checked before anything is called).

    Raises
    ------
    ModelError
        If ``spec`` is malformed, the module cannot be imported, or the object is not a
        component class (``os:abort`` is refused here).
    """
    m = _IMPORT.match(spec)
    if m is None:
        raise ModelError(f"{spec}: expected package.module:ClassName.", path=spec)
    try:
        module = importlib.import_module(m["module"])
    except ImportError as exc:
        raise ModelError(f"{spec}: cannot import module '{m['module']}' ({exc}).",
                         path=spec) from None
    obj = getattr(module, m["cls"], None)
    if not _concrete(obj):
        what = ("not found in the module" if obj is None else
                f"a {_kind(obj)}, not a concrete mechatron Component subclass")
        raise ModelError(f"{spec}: '{m['cls']}' is {what}; refusing to use it. Give a "
                         "database model (see `mechatron models`), a Component class "
                         "(package.module:ClassName) or a file (path/to/model.py).",
                         path=spec)
    return obj


def _kind(obj) -> str:
    if inspect.isclass(obj):
        return "class" if not issubclass(obj, Component) else "partial (abstract) component"
    if callable(obj):
        return "function"
    return type(obj).__name__


def component_class(spec: str, *, base: str | Path | None = None) -> type[Component] | None:
    """The class of a file or ``module:Class`` spec; ``None`` for a database name."""
    if is_model_file(spec):
        return load_model_file(spec, base=base)
    if ":" in spec:
        return import_component(spec)
    return None


def entry_from_class(cls: type[Component], *, name: str | None = None,
                     source: str = "") -> ModelEntry:
    """A one-variant :class:`ModelEntry` for a component class (see the module doc)."""
    params = {}
    for key, decl in cls._declarations.items():
        if isinstance(decl, Parameter):
            default = (math.nan if decl.default is None else
                       to_si(decl.default, decl.unit, f"{cls.__name__}.{key}"))
            params[key] = ParameterInfo(decl.unit, default, decl.doc, source)
    outputs = {key: key for key, decl in cls._declarations.items()
               if isinstance(decl, Variable) and not isinstance(decl, Input)}
    units = {key: cls._declarations[key].unit for key in outputs}
    exp = getattr(cls, "experiment", None)
    if isinstance(exp, dict):
        try:
            exp = Experiment(**exp)
        except TypeError as exc:
            raise ModelError(f"{cls.__name__}.experiment: {exc}; use the fields t_stop, "
                             "solver, rtol, atol, dt.", path=cls.__name__) from None
    elif not isinstance(exp, Experiment):
        exp = Experiment(t_stop=1.0)
    required = [k for k, p in params.items() if math.isnan(p.default)]

    def build(**values):
        # parameters without a default that the user did not set stay unset, so that the
        # component reports them itself
        return cls(**{k: v for k, v in values.items()
                      if not (k in required and isinstance(v, float) and math.isnan(v))})

    if not outputs and not required:
        # no variables of its own (a network of parts): its states stand for it
        from mechatron.compiler import compile_model
        cm = compile_model(build(**{k: p.default for k, p in params.items()}))
        outputs = {name: name for name in cm.state_names}
        units = dict(zip(cm.state_names, _state_units(cm)))
    doc = inspect.getdoc(cls) or cls.__name__
    return ModelEntry(name=name or cls.__name__, description=doc.split("\n\n")[0],
                      parameters=params, variants={VARIANT: build},
                      outputs={VARIANT: outputs}, output_units=units, experiment=exp,
                      tags=("user",))


def _state_units(cm) -> list[str]:
    units = dict(zip(cm.names, cm.units))
    return [units.get(name, "") for name in cm.state_names]


def entry_for(spec: str) -> ModelEntry:
    """The entry of a database name, a user's file (``file.py[:Class]``) or an importable
    component class (``module:Class``)."""
    cls = component_class(spec)
    if cls is None:
        import mechatron.models
        return mechatron.models.get(spec)
    return entry_from_class(cls, name=spec, source=spec)
