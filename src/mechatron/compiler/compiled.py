"""The compiled model: CasADi functions plus the metadata that names their entries.

The integration state is ``X = [x; s; c; te]``: the continuous states ``x``, one mode
``s`` in {-1, +1} per relation, and per relation an event counter ``c`` and the time of
its last event ``te`` (both piecewise constant; they make event statistics and event times
part of the native integration, with no Python callback).
"""

from __future__ import annotations

import pickle
from dataclasses import dataclass, field
from pathlib import Path

import casadi as ca
import numpy as np

from mechatron.errors import DataError, ParameterError
from mechatron.units import to_si

__all__ = ["CompiledModel"]

#: Marks that the event functions add to a relation's event counter in ``X`` (read by
#: the solvers after a run): a relation that chattered, an event iteration that did not
#: converge (see `mechatron.compiler.events`).
CHATTER_FLAG = 1e15
LOOP_FLAG = 2e15

_FUNCS = ("f_ode", "f_alg", "f_out", "f_zero", "f_dist", "f_transition", "f_scales",
          "f_events", "f_init", "f_dist2")


@dataclass
class CompiledModel:
    """A model lowered to CasADi functions ``f(t, X, z, p)``.

    Attributes
    ----------
    name : str
    state_names : list of str
        Continuous states (instance paths, ``der(x)`` for a derivative that is a state).
    alg_names : list of str
        Algebraic unknowns left to the DAE solver (tearing variables of nonlinear loops).
    param_names, param_units, p0
        Parameters by instance path, their units and default values (SI).
    input_names, input_index, input_units, input_docs, input_defaults
        External inputs: the slots of ``p`` that are signals of time (see
        :mod:`mechatron.solvers.inputs`).
    names, units, docs
        Every logged variable by instance path.
    relations : list of (owner, op)
        The event-generating relations with the component they belong to.
    report : dict
        Counts before/after each pass, chosen states, pass timings.
    """

    name: str
    state_names: list[str]
    alg_names: list[str]
    param_names: list[str]
    param_units: list[str]
    p0: np.ndarray
    names: list[str]
    units: list[str]
    docs: list[str]
    relations: list[tuple[str, str]]
    x_start: np.ndarray
    x_priority: list[str]
    z_start: np.ndarray
    targets: list[tuple[str, int, float, str]]   # (name, output index, value, priority)
    f_ode: ca.Function = None
    f_alg: ca.Function = None
    f_out: ca.Function = None
    f_zero: ca.Function = None
    f_dist: ca.Function = None
    f_transition: ca.Function = None
    f_scales: ca.Function = None
    #: ``X`` after the events found at a point (ticks due, relations changed, their
    #: actions): called at the initial time and at the end of every fixed step.
    f_events: ca.Function = None
    #: Residuals of the initial equations (``initial_equations()``), or None: they hold
    #: at ``t0`` beside the start values of high priority (see solvers.initial).
    f_init: ca.Function = None
    #: ``(d, d_dot, d_ddot)`` of the relations: distances and their first two time
    #: derivatives along the trajectory (modes of relations at rest on their surface).
    f_dist2: ca.Function = None
    param_bounds: list = field(default_factory=list)   # (min or None, max or None)
    #: External inputs (signal inputs of the root component) by instance path: each is a
    #: slot ``input_index[k]`` of ``p`` that ``simulate(inputs=...)`` fills with a signal
    #: of time; ``input_defaults`` holds each one's start value (NaN: none, must be given)
    input_names: list = field(default_factory=list)
    input_index: list = field(default_factory=list)
    input_units: list = field(default_factory=list)
    input_docs: list = field(default_factory=list)
    input_defaults: list = field(default_factory=list)
    report: dict = field(default_factory=dict)
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    # -- sizes ----------------------------------------------------------------------------
    @property
    def nx(self) -> int:
        return len(self.state_names)

    @property
    def nr(self) -> int:
        return len(self.relations)

    @property
    def nz(self) -> int:
        return len(self.alg_names)

    @property
    def nX(self) -> int:
        return self.nx + 3 * self.nr

    # -- parameters -----------------------------------------------------------------------
    def binding_of(self, name: str) -> str:
        """A sentence for messages if ``name`` is a part's parameter bound to its parent's
        (``r = Resistor(R=R)`` in the parent's class; not a parameter of the compiled
        model of its own), naming the one to set instead; else ``""``."""
        bound = self._cache.get("bindings")
        if bound is None:
            bound = self._cache["bindings"] = {}
            for owner, key, parent, source in self.report.get("bindings", ()):
                if key is None:             # an expression: its text says where
                    bound[owner] = (source, None)
                else:
                    bound[f"{owner}.{key}" if owner else key] = (
                        f"{source} of '{parent or self.name}'",
                        f"{parent}.{source}" if parent else source)
        got = bound.get(name)
        if got is None:
            return ""
        text, target = got
        seen = {name}
        while target in bound and target not in seen:   # passed on again: its source
            seen.add(target)
            target = bound[target][1]
        return (f"'{name}' is bound to {text} (a part's parameter its parent passes on) and "
                "has no value of its own: " + (f"set '{target}' instead." if target else
                                               "set the parameters it is written in."))

    def not_a_parameter(self, name: str) -> str:
        """Why ``name`` is not a parameter of the model, for messages: what it is bound
        to (`binding_of`), else the model's parameters."""
        return self.binding_of(name) or f"its parameters are {', '.join(self.param_names)}."

    def parameter_vector(self, params: dict | None = None) -> np.ndarray:
        """Default parameter values with ``params`` (path -> value or quantity) applied."""
        p = self.p0.copy()
        if not params:
            return p
        index = self._cache.get("pindex")
        if index is None:
            index = self._cache["pindex"] = {n: i for i, n in enumerate(self.param_names)}
        unknown = [k for k in params if k not in index]
        if unknown:
            for k in unknown:
                why = self.binding_of(k)
                if why:
                    raise ParameterError(f"model '{self.name}': {why}", path=self.name)
            import difflib
            hints = {k: difflib.get_close_matches(k, self.param_names, 3) for k in unknown}
            text = "; ".join(f"'{k}'" + (f" (did you mean {', '.join(v)}?)" if v else "")
                             for k, v in hints.items())
            raise ParameterError(f"model '{self.name}': unknown parameter(s) {text}. "
                                 f"Parameters: {', '.join(self.param_names[:12])}"
                                 f"{' ...' if len(self.param_names) > 12 else ''}.",
                                 path=self.name)
        problems = []
        for key, value in params.items():
            i = index[key]
            p[i] = to_si(value, self.param_units[i], key)
            low, high = self.param_bounds[i] if self.param_bounds else (None, None)
            if p[i] != p[i]:
                problems.append(f"{key} is NaN.")
            if low is not None and p[i] < low:
                problems.append(f"{key} must be >= {low:g}, got {p[i]:g}.")
            if high is not None and p[i] > high:
                problems.append(f"{key} must be <= {high:g}, got {p[i]:g}.")
        if problems:
            raise ParameterError(f"model '{self.name}': " + " ".join(problems),
                                 problems=problems, path=self.name)
        return p

    # -- persistence ----------------------------------------------------------------------
    def save(self, path) -> Path:
        """Save to a file (functions serialized by CasADi); :meth:`load` reads it back.
        All or nothing (`mechatron._io.atomic_path`): an interrupted save leaves the file
        that was there before."""
        from mechatron._io import atomic_path
        path = Path(path)
        with atomic_path(path) as tmp, open(tmp, "wb") as fh:
            pickle.dump(self, fh, protocol=pickle.HIGHEST_PROTOCOL)
        return path

    @classmethod
    def load(cls, path) -> "CompiledModel":
        path = Path(path)
        if not path.exists():
            raise DataError(f"{path}: no such file. Save a model with "
                            "CompiledModel.save(path) first.", path=str(path))
        with open(path, "rb") as fh:
            try:
                obj = pickle.load(fh)
            except (pickle.UnpicklingError, EOFError, AttributeError, ImportError,
                    IndexError, TypeError, ValueError, RuntimeError) as exc:
                raise DataError(f"{path}: not a readable saved CompiledModel (truncated or "
                                f"damaged: {type(exc).__name__}: {exc}). Save the model "
                                "again with CompiledModel.save(path).",
                                path=str(path)) from exc
        if not isinstance(obj, cls):
            raise DataError(f"{path}: not a saved CompiledModel.", path=str(path))
        return obj

    def __getstate__(self):
        state = dict(self.__dict__)
        unread = state.pop("_serialized", {})
        for key in _FUNCS:
            f = state.get(key)
            state[key] = f.serialize() if f is not None else unread.get(key)
        state["_cache"] = {}
        return state

    def __setstate__(self, state):
        for key in ("input_names", "input_index", "input_units", "input_docs",
                    "input_defaults"):   # files saved before external inputs existed
            state.setdefault(key, [])
        state.setdefault("f_init", None)
        state.setdefault("f_dist2", None)
        # each function deserialized when first read (`_Deserialized`): a run reads few
        # of them, and a large model's take most of the time of loading it
        state["_serialized"] = {key: state.pop(key) for key in _FUNCS
                                if state.get(key) is not None}
        self.__dict__.update(state)

    def _repr_html_(self) -> str:
        """Notebook display: sizes, states and the passes' timings."""
        from mechatron._html import compiled_html
        return compiled_html(self)

    def __repr__(self) -> str:
        return (f"<CompiledModel '{self.name}': {self.nx} states, {self.nz} algebraic, "
                f"{len(self.param_names)} parameters, {len(self.names)} logged variables, "
                f"{self.nr} event relations>")


class _Deserialized:
    """A function of a model read from a file or a pickle (`CompiledModel.__setstate__`),
    deserialized when first read and then held as an ordinary attribute: a class-level
    descriptor that the instance's own attribute hides once it is set. Deserializing
    the functions of a model of 10^4 sections takes most of the time of loading it,
    and a run reads the right-hand side, the outputs and the time scales; a model
    without events, algebraic unknowns or initial equations needs none of the others."""

    def __init__(self, key: str):
        self.key = key

    def __get__(self, obj, cls=None):
        if obj is None:
            return None                    # the dataclass field's default
        text = obj.__dict__.get("_serialized", {}).get(self.key)
        f = None
        if text is not None:
            try:
                f = ca.Function.deserialize(text)
            except RuntimeError as exc:
                raise DataError(f"model '{obj.name}': its saved function {self.key} cannot "
                                "be read (damaged, or written by another CasADi version). "
                                "Save the model again with CompiledModel.save(path).",
                                path=obj.name) from exc
        # the attribute set before the text is dropped: a thread reading the function at
        # the same time finds one or the other
        obj.__dict__[self.key] = f
        obj.__dict__.get("_serialized", {}).pop(self.key, None)
        return f


for _key in _FUNCS:     # after the dataclass has read the fields' defaults (None)
    setattr(CompiledModel, _key, _Deserialized(_key))
