"""External inputs: driving a model with given signals, ``simulate(..., inputs={...})``.

A model's external inputs are the signal inputs of its root component
(``u = mt.Input("V")``, or ``System.input("u", unit="V")``), as a top-level ``input`` of
Modelica or a root Inport of Simulink. The compiler makes each one a slot of the
parameter vector ``p`` (``CompiledModel.input_names``, ``input_index``) and adds the
equation ``u == p_u``; every compiled function keeps its signature ``f(t, X, z, p)``, so
generated C, FMUs and estimation see an input as a tunable parameter, and ``u`` is logged
like any other variable.

What an input value can be
--------------------------
- a number (SI, in the input's unit), a quantity string (``"3.5 V"``) or a pint quantity:
  a constant;
- a table ``(t, values)`` of two 1-D arrays of equal length (at least 2 points, ``t`` in
  s and strictly increasing, values SI or a pint quantity array): **piecewise linear**
  between its points and **held constant** outside ``[t[0], t[-1]]`` (the default of
  Simulink's *From Workspace* block);
- a callable ``f(t)`` taking a NumPy array of times and returning an array of values
  (SI or a pint quantity). Variable-step runs sample it on :data:`SAMPLES` equally spaced
  points over ``[t0, t_stop]`` and use that table; fixed-step runs sample it at the start
  of every step.

An input not given takes its declared start value (``mt.Input("V", start=0.0)``); one
without a start value must be given (``SimulationError``). An input may also be given as a
constant through ``params={...}``, since it is a parameter slot.

How the solvers see it
----------------------
Variable step: the input slots of ``p`` are replaced, in the DAE handed to the integrator,
by CasADi linear interpolants of time whose grid and values are *parametric*
(``casadi.interpolant(name, "linear", [n], 1)``): they enter the integrator as extra
entries of its parameter vector, so a new table of the same length reuses the integrator
built for the last one. Error control handles the kinks of the piecewise-linear signal.

Fixed step: the input is sampled at the start of every step and held over the step
(zero-order hold, what a real-time target does). The per-step values are columns of the
``p`` argument of the native ``mapaccum`` loop: no Python per step. The variables logged
at the end of a step are computed with the value held during that step (as the step
function of generated code does), so a logged input lags its table by one step.
"""

from __future__ import annotations

import difflib
import numbers
import sys
from collections.abc import Mapping
from dataclasses import dataclass

import casadi as ca
import numpy as np

from mechatron import units
from mechatron.errors import SimulationError, UnitError
from mechatron.units import to_si

__all__ = ["SAMPLES", "InputSignal", "Inputs", "resolve_inputs", "driven_parameters"]

#: Points on which a callable input is sampled for a variable-step run.
SAMPLES = 10_001

_WHAT = ("a number, a quantity string such as '3.5 V', a (t, values) table of 1-D arrays "
         "or a function of t taking a NumPy array")


@dataclass(frozen=True)
class InputSignal:
    """One external input of a run: a constant, a table or a callable (SI values)."""

    name: str
    slot: int                     # index into p
    unit: str
    value: float | None = None    # a constant
    t: np.ndarray | None = None   # a table
    v: np.ndarray | None = None
    func: object = None           # a callable f(t)

    @property
    def constant(self) -> bool:
        return self.value is not None

    def sample(self, times: np.ndarray) -> np.ndarray:
        """Values at ``times``: tables linear between points and held outside them."""
        times = np.asarray(times, dtype=float)
        if self.constant:
            return np.full(times.shape, self.value)
        if self.func is not None:
            return _call(self, times)
        return np.interp(times, self.t, self.v)

    def table(self, t0: float, t_stop: float) -> tuple[np.ndarray, np.ndarray]:
        """The table a variable-step run interpolates (callables sampled on SAMPLES)."""
        if self.func is not None:
            grid = np.linspace(t0, t_stop, SAMPLES)
            return grid, _call(self, grid)
        return self.t, self.v


class Inputs:
    """The external inputs of one run, resolved against a compiled model.

    ``drive`` is what the variable-step integrator is built for: one ``(slot, n)`` per
    non-constant input (its table length ``n``); the values themselves are data.
    """

    def __init__(self, signals: list[InputSignal], t0: float, t_stop: float):
        self.signals = signals
        self.t0, self.t_stop = t0, t_stop
        self._cached_tables = None
        self.drive = tuple((s.slot, SAMPLES if s.func is not None else s.t.size)
                           for s in signals if not s.constant)

    @property
    def _tables(self) -> dict:
        """The table of each non-constant input, by slot (callables sampled once)."""
        if self._cached_tables is None:
            self._cached_tables = {s.slot: s.table(self.t0, self.t_stop)
                                   for s in self.signals if not s.constant}
        return self._cached_tables

    def apply(self, p: np.ndarray) -> np.ndarray:
        """``p`` with each constant input in its slot (the others: their value at t0 is
        set by :meth:`columns`)."""
        p = np.array(p, dtype=float)
        for s in self.signals:
            if s.constant:
                p[s.slot] = s.value
        return p

    def columns(self, p: np.ndarray, times) -> np.ndarray:
        """``p`` at each of ``times``: array (len(p), len(times)) whose input slots hold
        the inputs' values there (the fixed-step loop, the initial point)."""
        times = np.atleast_1d(np.asarray(times, dtype=float))
        P = np.repeat(self.apply(p).reshape(-1, 1), times.size, axis=1)
        for s in self.signals:
            if not s.constant:
                P[s.slot] = s.sample(times)
        return P

    def logged_columns(self, p: np.ndarray, times) -> np.ndarray:
        """As :meth:`columns`, but callables read from the table the integrator used, so
        that the log shows what drove the model."""
        times = np.atleast_1d(np.asarray(times, dtype=float))
        P = np.repeat(self.apply(p).reshape(-1, 1), times.size, axis=1)
        for slot, (tt, vv) in self._tables.items():
            P[slot] = np.interp(times, tt, vv)
        return P

    def integrator_parameters(self, p: np.ndarray) -> np.ndarray:
        """The integrator's parameter vector: ``p``, then each table's times and values,
        in the order of ``drive`` (see :func:`driven_parameters`)."""
        parts = [self.apply(p)]
        for slot, _ in self.drive:
            tt, vv = self._tables[slot]
            parts += [tt, vv]
        return np.concatenate(parts)


def driven_parameters(n_p: int, t, P, drive):
    """``p`` with each driven slot replaced by its interpolant of time.

    ``P`` (SX or MX; MX is faster for long tables, whose slices are then copied as
    blocks) is ``[p; t_1; v_1; t_2; v_2; ...]`` (see
    :meth:`Inputs.integrator_parameters`); ``drive`` lists ``(slot, n)``. Time is clamped
    to the table's range, so the value is held constant outside it (CasADi's linear
    interpolant would extrapolate).
    """
    value = {}
    k = n_p
    for slot, n in drive:
        grid, data = P[k:k + n], P[k + n:k + 2 * n]
        k += 2 * n
        opts = {"lookup_mode": ["binary"]} if n > 64 else {}
        interp = ca.interpolant(f"input_{slot}", "linear", [n], 1, opts)
        value[slot] = interp(ca.fmin(ca.fmax(t, grid[0]), grid[n - 1]), grid, data)
    pieces, start = [], 0
    for slot in sorted(value):
        if slot > start:
            pieces.append(P[start:slot])
        pieces.append(value[slot])
        start = slot + 1
    if start < n_p:
        pieces.append(P[start:n_p])
    return ca.vertcat(*pieces)


# -------------------------------------------------------------------------- resolving
def resolve_inputs(cm, inputs, params, t0: float, t_stop: float) -> Inputs | None:
    """Check ``inputs`` against the model's external inputs and convert them to SI.

    Returns None for a model without external inputs and no ``inputs``. Raises
    ``SimulationError`` for an unknown name, a missing input or a malformed value, and
    ``UnitError`` for a value of the wrong dimension, each naming the input.
    """
    names = list(getattr(cm, "input_names", []) or [])
    if inputs is not None and not isinstance(inputs, Mapping):
        raise SimulationError(f"model '{cm.name}': inputs must be a dict "
                              "{'name': value}, e.g. inputs={'u': (t, v)}, got "
                              f"{type(inputs).__name__}.", path=cm.name)
    inputs = dict(inputs or {})
    if not names and not inputs:
        return None
    unknown = [k for k in inputs if k not in names]
    if unknown:
        if not names:
            raise SimulationError(
                f"model '{cm.name}': unknown input(s) {', '.join(map(repr, unknown))}: the "
                "model has no external inputs. Declare one on the root component, e.g. "
                "u = mt.Input('V'), or System.input('u', unit='V').", path=cm.name)
        hints = {k: difflib.get_close_matches(str(k), names, 3) for k in unknown}
        text = "; ".join(f"'{k}'" + (f" (did you mean {', '.join(v)}?)" if v else "")
                         for k, v in hints.items())
        raise SimulationError(f"model '{cm.name}': unknown input(s) {text}. External "
                              f"inputs: {', '.join(names)}.", path=cm.name)
    params = params or {}
    twice = [k for k in inputs if k in params]
    if twice:
        raise SimulationError(f"model '{cm.name}': input(s) {', '.join(twice)} given both "
                              "in params= and inputs=; give each once (inputs= for a "
                              "signal).", path=cm.name)
    missing = [n for n, d in zip(names, cm.input_defaults)
               if n not in inputs and n not in params and d != d]
    if missing:
        example = ", ".join(f"'{n}': ..." for n in missing)
        raise SimulationError(
            f"model '{cm.name}': input(s) {', '.join(missing)} have no value and no "
            f"default. Give them: simulate(..., inputs={{{example}}}) with {_WHAT}; or "
            "declare a default, mt.Input(unit, start=...).", path=cm.name,
            variables=missing)
    signals = []
    for name, slot, unit in zip(names, cm.input_index, cm.input_units):
        if name in inputs:
            signals.append(_signal(cm, name, slot, unit, inputs[name], t0, t_stop))
    return Inputs(signals, t0, t_stop)


def _is_quantity(value) -> bool:
    """Whether ``value`` is a pint quantity. Only a program that imported pint holds one:
    a run that is given none does not import it (a few tenths of a second)."""
    pint = sys.modules.get("pint")
    return pint is not None and isinstance(value, pint.Quantity)


def _signal(cm, name: str, slot: int, unit: str, value, t0: float,
            t_stop: float) -> InputSignal:
    where = f"input '{name}'"
    if (isinstance(value, (numbers.Real, str)) or _is_quantity(value)) and np.ndim(
            getattr(value, "magnitude", value)) == 0:
        x = to_si(value, unit, where)
        if not np.isfinite(x):
            raise SimulationError(f"model '{cm.name}': {where} is {x}. Give a finite "
                                  "value.", path=name)
        return InputSignal(name, slot, unit, value=x)
    if callable(value):
        sig = InputSignal(name, slot, unit, func=value)
        _call(sig, np.array([t0, t_stop]))   # checked early: shape, dimension, finite
        return sig
    if isinstance(value, (tuple, list)) and len(value) == 2:
        t = _array(value[0], "s", f"{where}: table times")
        v = _array(value[1], unit, f"{where}: table values")
        _check_table(cm.name, name, t, v)
        return InputSignal(name, slot, unit, t=t, v=v)
    raise SimulationError(f"model '{cm.name}': {where}: cannot use "
                          f"{type(value).__name__} {_short(value)} as a signal. Give "
                          f"{_WHAT}.", path=name)


def _array(data, unit: str, where: str) -> np.ndarray:
    """A 1-D float array in SI from numbers or a pint quantity array."""
    if _is_quantity(data):
        target = units.ureg.Unit(unit or "dimensionless")
        if data.dimensionality != target.dimensionality:
            raise UnitError(f"{where}: expected values in {unit or 'dimensionless'}, got "
                            f"{data.units:~} ({data.dimensionality}). Convert them, or "
                            f"give plain numbers in {unit or 'SI'}.", path=where)
        data = data.to(target).magnitude
    try:
        arr = np.asarray(data, dtype=float)
    except (TypeError, ValueError):
        raise SimulationError(f"{where}: expected numbers, got {_short(data)}. Give a 1-D "
                              "array of numbers (SI) or a pint quantity array.",
                              path=where) from None
    if arr.ndim != 1:
        raise SimulationError(f"{where}: expected a 1-D array, got shape {arr.shape}. Give "
                              "the table as (t, values) of two 1-D arrays.", path=where)
    return arr


def _check_table(model: str, name: str, t: np.ndarray, v: np.ndarray) -> None:
    where = f"model '{model}': input '{name}'"
    if t.size != v.size:
        raise SimulationError(f"{where}: the table has {t.size} times and {v.size} "
                              "values; give as many of each.", path=name)
    if t.size < 2:
        raise SimulationError(f"{where}: a table needs at least 2 points, got {t.size}. "
                              "For a constant give a number, e.g. inputs={"
                              f"'{name}': 1.0}}.", path=name)
    for label, arr in (("times", t), ("values", v)):
        bad = np.nonzero(~np.isfinite(arr))[0]
        if bad.size:
            raise SimulationError(f"{where}: the table {label} hold {bad.size} NaN/inf "
                                  f"value(s), first at index {bad[0]}. Remove or fill "
                                  "them (e.g. interpolate the gaps).", path=name)
    steps = np.diff(t)
    if np.any(steps <= 0):
        k = int(np.nonzero(steps <= 0)[0][0])
        raise SimulationError(f"{where}: the table times must increase strictly; t[{k}] = "
                              f"{t[k]:g} s is followed by t[{k + 1}] = {t[k + 1]:g} s. "
                              "Sort the table and remove repeated times (a jump needs two "
                              "distinct times, e.g. 0.999999 and 1.0).", path=name)


def _call(sig: InputSignal, times: np.ndarray) -> np.ndarray:
    where = f"input '{sig.name}'"
    try:
        out = sig.func(times)
    except Exception as exc:
        raise SimulationError(f"{where}: the function raised {type(exc).__name__}: {exc}. "
                              "It is called with a NumPy array of times and must return "
                              "an array of the same length (use np.sin, not math.sin).",
                              path=sig.name) from exc
    if isinstance(out, str):
        out = to_si(out, sig.unit, where)
    arr = np.ravel(_array(np.atleast_1d(out) if not _is_quantity(out)
                          else np.atleast_1d(out.magnitude) * out.units,
                          sig.unit, f"{where}: function values"))
    if arr.size == 1:   # a function returning a constant
        arr = np.full(times.shape, arr[0])
    if arr.shape != times.shape:
        raise SimulationError(f"{where}: the function returned {arr.size} values for "
                              f"{times.size} times. Return one value per time.",
                              path=sig.name)
    bad = np.nonzero(~np.isfinite(arr))[0]
    if bad.size:
        raise SimulationError(f"{where}: the function is not finite at t = "
                              f"{times[bad[0]]:g} s. Return finite values over the whole "
                              "simulated time.", path=sig.name)
    return np.array(arr, dtype=float)


def _short(value, limit: int = 50) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."
