"""The simulation log ("simlog"): every variable of a simulated model, by instance path.

A solver returns a :class:`SimResult`. It holds the output times, one row of values per
model variable (``"motor.inertia.w"``, ``"r1.p.v"``), the unit of each, and a
:class:`SolverStats` profile of the run. It can be read by name, interpolated, narrowed to
a subtree of the model, turned into a :class:`pandas.DataFrame`, saved to and loaded from
CSV or Parquet, and plotted.

Values are SI floats, as everywhere at run time. The arrays handed out are read-only views
of the log; copy them (``res["x"].copy()``) to modify them.

File formats
------------
CSV
    One header row: ``t`` followed by the instance paths, in the order of
    :attr:`SimResult.names`; then one row per time point, every number written with
    ``%.17g`` so that a round trip is exact. Units are not stored (a plain CSV file is what
    spreadsheets and other tools read); :meth:`SimResult.load` gives them as ``""``.
Parquet
    One float64 column per variable after the ``t`` column. Each field carries its
    ``unit`` (and ``description``, if any) in its field metadata; the schema metadata key
    ``mechatron`` holds the model name and the solver statistics as JSON.
"""

from __future__ import annotations

import csv
import dataclasses
import difflib
import io
import json
import os
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from mechatron._io import atomic_path, save_figure
from mechatron.errors import DataError, UnknownVariableError

if TYPE_CHECKING:  # imported lazily at run time: they are only needed to export or plot
    import pandas
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["SimResult", "SolverStats", "UnknownVariableError"]

#: File suffixes understood by :meth:`SimResult.save` and :meth:`SimResult.load`.
SUFFIXES = (".csv", ".parquet")

_METADATA_KEY = b"mechatron"
_FORMAT_VERSION = 1
_N_SUGGESTIONS = 5
#: A log computed on demand is computed whole, once, on the first read of a variable it
#: did not store when it has at most this many values (8 MB); a larger one computes the
#: variables read (and keeps them).
_SMALL_LOG = 1 << 20


@dataclass
class SolverStats:
    """Profile of one simulation run.

    Parameters
    ----------
    solver : str
        Name of the method that ran, e.g. ``"RK4"``, ``"BDF"``, ``"cvodes"``.
    steps : int, optional
        Accepted time steps.
    rejected_steps : int, optional
        Steps rejected by the error or Newton convergence test.
    rhs_evals : int, optional
        Evaluations of the right-hand side (state derivative or DAE residual).
    jac_evals : int, optional
        Evaluations of the Jacobian.
    events : dict of str to int, optional
        Number of events fired, by the instance path of the component that owns the
        event indicator (e.g. ``{"bldc.inverter.q3": 12}``).
    wall_time : float, optional
        Wall-clock time of the simulation, in s.
    compile_time : float or None, optional
        Wall-clock time of compiling the model for this run, in s (with
        ``solver="rodas4"``, building or loading its C library included); ``None`` when
        nothing was compiled for the run.
    solver_reason : str, optional
        Why this solver ran: what ``solver="auto"`` found (events, algebraic unknowns,
        the stiffness probe's figures), or that it was asked for.
    unconverged_steps : int, optional
        Steps of an implicit fixed-step method whose Newton iteration had not converged
        after the fixed iteration count (only counted with ``newton="count"``, the
        real-time setting; otherwise such a step is an error).

    Notes
    -----
    The fields can also be read by name, ``stats["solver"]``.
    """

    solver: str
    steps: int = 0
    rejected_steps: int = 0
    rhs_evals: int = 0
    jac_evals: int = 0
    events: dict[str, int] = field(default_factory=dict)
    wall_time: float = 0.0
    compile_time: float | None = None
    solver_reason: str = ""
    unconverged_steps: int = 0

    def __getitem__(self, key: str) -> Any:
        if key not in {f.name for f in dataclasses.fields(self)}:
            raise KeyError(key)
        return getattr(self, key)

    def as_dict(self) -> dict[str, Any]:
        """Return the statistics as a plain, JSON-serialisable dictionary.

        Returns
        -------
        dict
            One key per field; ``events`` is a copy, so changing it leaves the
            statistics untouched.
        """
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> SolverStats:
        """Build statistics from the output of :meth:`as_dict`.

        Parameters
        ----------
        data : mapping
            Field names to values. Unknown keys raise :class:`TypeError`.

        Returns
        -------
        SolverStats
        """
        data = dict(data)
        data["events"] = dict(data.get("events") or {})
        return cls(**data)


class SimResult:
    """The simulation log: output times and every model variable, by instance path.

    Built by the solvers; users read it. The arrays are not copied: the caller must not
    modify them afterwards.

    Parameters
    ----------
    t : array_like of float, shape (n_t,)
        Output times in s, non-decreasing (a time repeats at an event, once for the value
        before and once for the value after it). At least one point.
    values : array_like of float, shape (n_vars, n_t)
        One row per variable, in the order of `names`, in SI units.
    names : sequence of str
        Instance path of each variable, e.g. ``"motor.inertia.w"``. Unique.
    units : sequence of str
        Unit of each variable, pint-style (``"V"``, ``"rad/s"``, ``"N*m"``); ``""`` for a
        dimensionless variable.
    stats : SolverStats, optional
        Profile of the run; ``None`` when unknown (e.g. a log loaded from CSV).
    model_name : str, optional
        Name of the simulated model, used in messages and plot titles.
    descriptions : mapping of str to str, optional
        One-line description of some or all variables, by instance path.
    stored : sequence of int, optional
        Selective logging: the rows of `names` that `values` holds, in its order (then
        `values` has shape (len(stored), n_t)). The other variables are computed by
        `source` when first read.
    source : callable, optional
        With `stored`: ``source(rows) -> array (len(rows), n_t)`` computes variables by
        their rows in `names` (see :class:`mechatron.solvers.logging.OutputColumns`).

    Attributes
    ----------
    stats : SolverStats or None
        Profile of the run.
    model_name : str
        Name of the simulated model.

    Raises
    ------
    DataError
        If shapes disagree, a name repeats, or the time axis is not finite and
        non-decreasing.

    Examples
    --------
    >>> res = SimResult([0.0, 0.5, 1.0], [[0.0, 1.0, 2.0]], ["j.w"], ["rad/s"])
    >>> res["j.w"]
    array([0., 1., 2.])
    >>> res.at(0.25, "j.w")
    0.5
    """

    __slots__ = ("_t", "_values", "_names", "_units", "_descriptions", "_index",
                 "_pos", "_source", "_computed",
                 "stats", "model_name", "initialization", "event_times")

    def __init__(self, t: Any, values: Any, names: Sequence[str], units: Sequence[str],
                 *, stats: SolverStats | None = None, model_name: str = "",
                 descriptions: Mapping[str, str] | None = None,
                 stored: Sequence[int] | None = None, source: Any = None):
        self.model_name = str(model_name)
        self.initialization: list[dict] = []   # start-value targets and whether they held
        self.event_times: dict[str, float] = {}  # component -> time of its last event
        where = self._where()
        t = np.asarray(t, dtype=float)
        values = np.asarray(values, dtype=float)
        names = [str(n) for n in names]
        units = [str(u) for u in units]
        if t.ndim != 1 or t.size == 0:
            raise DataError(f"{where}: the time axis must be a non-empty 1-D array, "
                            f"got shape {t.shape}.")
        n_rows = len(names) if stored is None else len(stored)
        if values.size == 0 and not n_rows:
            values = values.reshape(0, t.size)
        if values.ndim != 2 or values.shape != (n_rows, t.size):
            raise DataError(f"{where}: values must have shape (n_vars, n_t) = "
                            f"({n_rows}, {t.size}), got {values.shape}. "
                            f"One row per {'variable' if stored is None else 'stored row'}, "
                            "one column per time point.")
        if stored is not None and source is None:
            raise DataError(f"{where}: {len(names) - len(stored)} variable(s) not stored "
                            "and no source to compute them. Pass source=, or all values.")
        if len(units) != len(names):
            raise DataError(f"{where}: {len(names)} names but {len(units)} units.")
        if not np.all(np.isfinite(t)):
            raise DataError(f"{where}: the time axis holds {np.count_nonzero(~np.isfinite(t))} "
                            f"non-finite value(s).")
        backwards = np.flatnonzero(np.diff(t) < 0)
        if backwards.size:
            k = int(backwards[0])
            raise DataError(f"{where}: the time axis must be non-decreasing, got "
                            f"t[{k}] = {float(t[k])!r} > t[{k + 1}] = {float(t[k + 1])!r} "
                            f"({backwards.size} decrease(s) in all).")
        index = {name: row for row, name in enumerate(names)}
        if len(index) != len(names):
            seen: set[str] = set()
            repeated = sorted({n for n in names if n in seen or seen.add(n)})
            raise DataError(f"{where}: {len(names) - len(index)} repeated variable name(s): "
                            f"{', '.join(repeated)}.", variables=repeated)
        descriptions = dict(descriptions or {})
        strays = [n for n in descriptions if n not in index]
        if strays:
            raise DataError(f"{where}: description(s) given for unknown variable(s): "
                            f"{', '.join(strays)}.", variables=strays)
        # Read-only views: no copy of the data, and the log cannot be changed through them.
        self._t = t.view()
        self._t.flags.writeable = False
        self._values = values.view()
        self._values.flags.writeable = False
        self._names = names
        self._units = units
        self._descriptions = {n: str(d) for n, d in descriptions.items()}
        self._index = index
        self._source = source if stored is not None else None
        self._pos = None if stored is None else {int(r): k for k, r in enumerate(stored)}
        self._computed: dict[int, np.ndarray] = {}
        self.stats = stats

    # ----------------------------------------------------------------------- reading
    @property
    def t(self) -> np.ndarray:
        """numpy.ndarray: Output times in s, shape (n_t,), read-only."""
        return self._t

    @property
    def values(self) -> np.ndarray:
        """numpy.ndarray: All values, shape (n_vars, n_t), rows in the order of `names`.

        For a selectively logged run this computes every variable (memory: variables x
        time points); read variables by name to compute only those."""
        if self._pos is None:
            return self._values
        # the source computes the stored rows too, to the same bits (they are the states
        # it computes from, or the same function): one pass over every variable
        out = self._compute(list(range(len(self._names))))
        out.flags.writeable = False
        return out

    @property
    def logged(self) -> list[str]:
        """list of str: The variables the run stored; every other one of `names` is
        computed from them (and the states) when first read. All of `names` for a
        fully logged run."""
        if self._pos is None:
            return list(self._names)
        return [self._names[r] for r in sorted(self._pos)]

    @property
    def nbytes(self) -> int:
        """int: Bytes held by the log (stored and computed values, and the trajectory
        an on-demand log computes from)."""
        extra = getattr(self._source, "nbytes", 0) if self._source is not None else 0
        return int(self._values.nbytes + sum(a.nbytes for a in self._computed.values())
                   + self._t.nbytes + extra)

    @property
    def names(self) -> list[str]:
        """list of str: Instance path of every logged variable, in log order."""
        return list(self._names)

    @property
    def units(self) -> dict[str, str]:
        """dict of str to str: Unit of every variable, by instance path."""
        return dict(zip(self._names, self._units))

    @property
    def descriptions(self) -> dict[str, str]:
        """dict of str to str: One-line description of every variable (``""`` if none)."""
        return {n: self._descriptions.get(n, "") for n in self._names}

    def __getitem__(self, name: str) -> np.ndarray:
        """Return the values of one variable over `t`, read-only, shape (n_t,).

        Raises
        ------
        UnknownVariableError
            (a :class:`KeyError`) if no variable has this name; the message suggests the
            closest names.
        """
        if not isinstance(name, str):
            raise TypeError(f"{self._where()}: variables are looked up by instance path "
                            f"(str), got {type(name).__name__}. Use select(...) for several.")
        row = self._index.get(name)
        if row is None:
            raise self._unknown(name)
        return self._row(row)

    def __contains__(self, name: object) -> bool:
        return isinstance(name, str) and name in self._index

    def __len__(self) -> int:
        """Number of time points."""
        return self._t.size

    def __repr__(self) -> str:
        model = f" {self.model_name!r}" if self.model_name else ""
        return (f"<SimResult{model}: {len(self._names)} variables, {self._t.size} time "
                f"points, t = {self._t[0]:g} .. {self._t[-1]:g} s>")

    def _repr_html_(self) -> str:
        """Notebook display: the solver profile, final values and a plot."""
        from mechatron._html import result_html
        return result_html(self)

    def _repr_svg_(self) -> str | None:
        """Notebook display: a plot of the first variables that change, with units."""
        from mechatron._html import result_svg
        return result_svg(self)

    def final(self, name: str) -> float:
        """Return the value of a variable at the last time point.

        Parameters
        ----------
        name : str
            Instance path of the variable.

        Returns
        -------
        float
        """
        return float(self[name][-1])

    def at(self, t: Any, name: str) -> float | np.ndarray:
        """Return a variable at given times, by linear interpolation.

        Parameters
        ----------
        t : float or array_like of float
            Time(s) in s, within ``[t[0], t[-1]]``.
        name : str
            Instance path of the variable.

        Returns
        -------
        float or numpy.ndarray
            A float for a scalar `t`, else an array of the shape of `t`. At a time that
            the log holds twice (an event), the value after the event.

        Raises
        ------
        DataError
            If a time lies outside the logged range (no extrapolation) or is NaN.
        """
        y = self[name]
        tq = np.asarray(t, dtype=float)
        t0, t1 = self._t[0], self._t[-1]
        outside = ~((tq >= t0) & (tq <= t1))  # also catches NaN
        if np.any(outside):
            bad = tq[outside] if tq.ndim else tq
            raise DataError(f"{name}: cannot interpolate at t = {float(np.ravel(bad)[0])!r} s, "
                            f"outside the logged range [{t0:g}, {t1:g}] s "
                            f"({np.count_nonzero(outside)} time(s) outside). "
                            f"The log is not extrapolated.", path=name)
        out = np.interp(tq, self._t, y)
        return float(out) if tq.ndim == 0 else out

    def select(self, *names_or_prefixes: str) -> SimResult:
        """Return a new log with only some variables.

        Parameters
        ----------
        *names_or_prefixes : str
            Instance paths of variables, or of components: ``"motor.inertia"`` selects
            every variable beneath it (``"motor.inertia.w"``, ``"motor.inertia.phi"``...).

        Returns
        -------
        SimResult
            Variables in the order of the arguments (a component's variables in log
            order), each once; same times, statistics and model name.

        Raises
        ------
        UnknownVariableError
            If an argument names neither a variable nor a component with logged variables.
        """
        rows = self._resolve(names_or_prefixes, "select")
        stats = None if self.stats is None else SolverStats.from_dict(self.stats.as_dict())
        names = [self._names[r] for r in rows]
        return SimResult(self._t, self._rows(rows), names, [self._units[r] for r in rows],
                         stats=stats, model_name=self.model_name,
                         descriptions={n: self._descriptions[n] for n in names
                                       if n in self._descriptions})

    # ---------------------------------------------------------------------- exports
    def to_pandas(self) -> pandas.DataFrame:
        """Return the log as a DataFrame.

        Returns
        -------
        pandas.DataFrame
            Index ``t`` (the output times), one float column per variable in log order.
            ``df.attrs`` holds ``"units"`` (dict by name) and ``"model_name"``.
        """
        import pandas as pd

        df = pd.DataFrame(self.values.T, index=pd.Index(self._t, name="t"),
                          columns=pd.Index(self._names, dtype=object), copy=True)
        df.attrs["units"] = self.units
        df.attrs["model_name"] = self.model_name
        return df

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the log to a CSV or Parquet file, chosen by the suffix.

        Parameters
        ----------
        path : str or path-like
            Destination, ending in ``.csv`` or ``.parquet``. See the module docstring for
            what each format holds; CSV does not keep units.

        Returns
        -------
        pathlib.Path
            The path written.

        Raises
        ------
        DataError
            If the suffix is not one of ``.csv``, ``.parquet``.
        """
        path = Path(path)
        suffix = _check_suffix(path, "save a simlog as")
        if suffix == ".csv":
            self._save_csv(path)
        else:
            self._save_parquet(path)
        return path

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> SimResult:
        """Read a log written by :meth:`save` (or any file of the same layout).

        Parameters
        ----------
        path : str or path-like
            A ``.csv`` or ``.parquet`` file whose first column is ``t``.

        Returns
        -------
        SimResult
            From CSV: units ``""``, no statistics, no model name. From Parquet: units,
            descriptions, statistics and model name as saved.

        Raises
        ------
        DataError
            If the suffix is not supported, the first column is not ``t``, or a value is
            not a number.
        FileNotFoundError
            If the file does not exist.
        """
        path = Path(path)
        suffix = _check_suffix(path, "load a simlog from")
        if suffix == ".csv":
            return cls._load_csv(path)
        return cls._load_parquet(path)

    def _save_csv(self, path: Path) -> None:
        table = np.empty((self._t.size, len(self._names) + 1))
        table[:, 0] = self._t
        table[:, 1:] = self.values.T
        with atomic_path(path) as tmp, open(tmp, "w", newline="", encoding="utf-8") as fh:
            csv.writer(fh, lineterminator="\n").writerow(["t", *self._names])
            np.savetxt(fh, table, fmt="%.17g", delimiter=",")

    @classmethod
    def _load_csv(cls, path: Path) -> SimResult:
        with open(path, newline="", encoding="utf-8") as fh:
            header = next(csv.reader(fh), None)
            if not header or header[0].strip() != "t":
                got = "an empty file" if not header else repr(header[0])
                raise DataError(f"{path}: the first column must be 't' (time in s), got "
                                f"{got}.", path=str(path))
            names = [h.strip() for h in header[1:]]
            rows = fh.read()
        if not rows.strip():
            raise DataError(f"{path}: no data under the header; a simlog has at least one "
                            "row of numbers.", path=str(path))
        try:
            table = np.loadtxt(io.StringIO(rows), dtype=float, delimiter=",", ndmin=2)
        except ValueError as exc:
            raise DataError(f"{path}: not a table of numbers under the header: {exc}",
                            path=str(path)) from exc
        if table.shape[1] != len(header):
            raise DataError(f"{path}: {len(header)} columns in the header but "
                            f"{table.shape[1]} in the data.", path=str(path))
        return cls(table[:, 0], table[:, 1:].T, names, [""] * len(names))

    def _save_parquet(self, path: Path) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        fields = [pa.field("t", pa.float64(), metadata={"unit": "s"})]
        columns = [pa.array(self._t)]
        values = self.values
        for row, name in enumerate(self._names):
            meta = {"unit": self._units[row]}
            if name in self._descriptions:
                meta["description"] = self._descriptions[name]
            fields.append(pa.field(name, pa.float64(), metadata=meta))
            columns.append(pa.array(np.ascontiguousarray(values[row])))
        info = {"format": _FORMAT_VERSION, "model_name": self.model_name,
                "stats": None if self.stats is None else self.stats.as_dict()}
        schema = pa.schema(fields, metadata={_METADATA_KEY: json.dumps(info)})
        with atomic_path(path) as tmp:
            pq.write_table(pa.Table.from_arrays(columns, schema=schema), tmp)

    @classmethod
    def _load_parquet(cls, path: Path) -> SimResult:
        import pyarrow.parquet as pq

        if not path.exists():
            raise FileNotFoundError(f"{path}: no such file.")
        table = pq.ParquetFile(path).read()  # one file; a variable may be named "t"
        schema = table.schema
        if not schema.names or schema.names[0] != "t":
            got = repr(schema.names[0]) if schema.names else "no column"
            raise DataError(f"{path}: the first column must be 't' (time in s), got {got}.",
                            path=str(path))
        names, units, descriptions = schema.names[1:], [], {}
        values = np.empty((len(names), table.num_rows))
        for i, f in enumerate(schema):
            try:
                column = np.asarray(table.column(i).to_numpy(), dtype=float)
            except (TypeError, ValueError) as exc:
                raise DataError(f"{path}: column {f.name!r} is not numeric ({f.type}).",
                                path=str(path)) from exc
            if i == 0:
                t = column
                continue
            values[i - 1] = column
            meta = f.metadata or {}
            units.append(meta.get(b"unit", b"").decode())
            if b"description" in meta:
                descriptions[f.name] = meta[b"description"].decode()
        info = json.loads((schema.metadata or {}).get(_METADATA_KEY, b"{}"))
        stats = info.get("stats")
        return cls(t, values, names, units, model_name=info.get("model_name", ""),
                   stats=None if stats is None else SolverStats.from_dict(stats),
                   descriptions=descriptions)

    # ----------------------------------------------------------------------- plotting
    def plot(self, *names: str, path: str | os.PathLike[str] | None = None,
             ax: Axes | Sequence[Axes] | None = None) -> Figure:
        """Plot variables over time, one subplot per unit.

        Variables that share a unit share an axis, so that what is compared is
        comparable. No window is opened (no ``pyplot``): the figure is returned, and
        written to `path` if one is given.

        Parameters
        ----------
        *names : str
            Instance paths of variables or components (a component plots every variable
            beneath it). At least one.
        path : str or path-like, optional
            Write the figure here; the suffix chooses the format (PNG by default).
        ax : matplotlib.axes.Axes or sequence of Axes, optional
            Draw into existing axes, one per unit group in order of first appearance,
            instead of a new figure.

        Returns
        -------
        matplotlib.figure.Figure

        Raises
        ------
        TypeError
            If no name is given.
        UnknownVariableError
            If a name matches no variable.
        DataError
            If `ax` does not hold one axes per unit group.
        """
        if not names:
            raise TypeError(f"{self._where()}: plot() needs at least one variable name or "
                            f"component prefix, e.g. plot({self._example()!r}). "
                            f"SimResult.names lists all {len(self._names):,} variables.")
        rows = self._resolve(names, "plot")
        groups: dict[str, list[int]] = {}
        for r in rows:
            groups.setdefault(self._units[r], []).append(r)

        if ax is None:
            from matplotlib.figure import Figure  # no pyplot: no global state, no window

            fig = Figure(figsize=(8.0, 1.0 + 2.4 * len(groups)), layout="constrained")
            axes = list(fig.subplots(len(groups), 1, sharex=True, squeeze=False)[:, 0])
        else:
            axes = [ax] if not isinstance(ax, Sequence | np.ndarray) else list(np.ravel(ax))
            if len(axes) != len(groups):
                raise DataError(f"{self._where()}: {len(groups)} unit group(s) "
                                f"({', '.join(_unit_label(u) for u in groups)}) to plot, but "
                                f"{len(axes)} axes given. Pass one axes per unit, or no ax.")
            fig = axes[0].figure

        for axis, (unit, group) in zip(axes, groups.items()):
            for r, y in zip(group, self._rows(group)):
                axis.plot(self._t, y, label=self._names[r])
            axis.set_ylabel(axis_label(unit, [self._names[r] for r in group]))
            axis.grid(True, alpha=0.3)
            axis.legend(loc="best", fontsize="small")
        axes[-1].set_xlabel("t [s]")
        if self.model_name:
            fig.suptitle(self.model_name)
        if path is not None:
            save_figure(fig, path, dpi=100)
        return fig

    def animate(self, path: str | os.PathLike[str], **options: Any) -> Path:
        """Write an animation (``.gif``, or ``.mp4`` with ffmpeg) of the planar mechanism
        in this log; see :func:`mechatron.viz.animate` for the options.

        Returns
        -------
        pathlib.Path
            The file written.
        """
        from mechatron.viz import animate

        return animate(self, path, **options)

    @classmethod
    def _of_model(cls, t: np.ndarray, values: np.ndarray, names: list[str],
                  units: list[str], index: dict[str, int], descriptions: dict[str, str],
                  *, stats: SolverStats | None, model_name: str,
                  stored: Sequence[int] | None = None, source: Any = None,
                  stored_at: dict[int, int] | None = None) -> SimResult:
        """A log from a compiled model's run, without the checks of the constructor:
        the names, units and index come from the compiled model (unique, checked when it
        was compiled) and are shared, not copied, between its results; so is
        ``stored_at``, the place of each stored row (``{row: k}`` of ``stored``, which a
        log only reads), when given."""
        self = cls.__new__(cls)
        self.model_name = str(model_name)
        self.initialization = []
        self.event_times = {}
        self._t = np.asarray(t, dtype=float).view()
        self._t.flags.writeable = False
        self._values = values.view()
        self._values.flags.writeable = False
        self._names, self._units, self._index = names, units, index
        self._descriptions = descriptions
        self._source = source if stored is not None else None
        self._pos = None if stored is None else stored_at if stored_at is not None \
            else {int(r): k for k, r in enumerate(stored)}
        self._computed = {}
        self.stats = stats
        return self

    # ------------------------------------------------------------------------ helpers
    def _row(self, r: int) -> np.ndarray:
        """Values of row ``r`` of `names` (read-only), computed and kept if not stored."""
        if self._pos is None:
            return self._values[r]
        k = self._pos.get(r)
        if k is not None:
            return self._values[k]
        y = self._computed.get(r)
        if y is None:
            n = len(self._names)
            if n * self._t.size <= _SMALL_LOG:      # small: compute the rest at once
                missing = [j for j in range(n) if j not in self._pos
                           and j not in self._computed]
            else:
                missing = [r]
            for j, row in zip(missing, self._compute(missing)):
                row.flags.writeable = False
                self._computed[j] = row
            y = self._computed[r]
        return y

    def _rows(self, rows: Iterable[int]) -> np.ndarray:
        """Values of several rows of `names`, shape (len(rows), n_t), a new array (the
        rows not stored or kept are computed together, not kept)."""
        rows = list(rows)
        if self._pos is None:
            return self._values[rows]
        out = np.empty((len(rows), self._t.size))
        missing = []
        for k, r in enumerate(rows):
            j = self._pos.get(r)
            if j is not None:
                out[k] = self._values[j]
            elif r in self._computed:
                out[k] = self._computed[r]
            else:
                missing.append(k)
        if missing:
            out[missing] = self._compute([rows[k] for k in missing])
        return out

    def _keep(self, rows: list[int]) -> None:
        """Compute the rows not stored (one call) and keep them: the variables a
        selectively logged run was asked to log."""
        if self._pos is None:
            return
        rows = [r for r in dict.fromkeys(rows) if r not in self._pos
                and r not in self._computed]
        if rows:
            for r, y in zip(rows, self._compute(rows)):
                y.flags.writeable = False
                self._computed[r] = y

    def _compute(self, rows: list[int]) -> np.ndarray:
        values = np.asarray(self._source(rows), dtype=float)
        if values.shape != (len(rows), self._t.size):
            raise DataError(f"{self._where()}: the source of the log's computed variables "
                            f"returned shape {values.shape} for {len(rows)} row(s) of "
                            f"{self._t.size} points.")
        return values

    def _where(self) -> str:
        return f"simlog of {self.model_name!r}" if self.model_name else "simlog"

    def _example(self) -> str:
        return self._names[0] if self._names else "motor.inertia.w"

    def _resolve(self, selectors: Iterable[str], verb: str) -> list[int]:
        """Rows of the variables named or beneath the components named, each once."""
        rows: list[int] = []
        seen: set[int] = set()
        selectors = list(selectors)
        if not selectors:
            raise TypeError(f"{self._where()}: {verb}() needs at least one variable name or "
                            f"component prefix, e.g. {verb}({self._example()!r}).")
        for sel in selectors:
            if not isinstance(sel, str):
                raise TypeError(f"{self._where()}: {verb}() takes instance paths (str), "
                                f"got {type(sel).__name__}.")
            row = self._index.get(sel)
            matched = [row] if row is not None else self._beneath(sel)
            if not matched:
                raise self._unknown(sel)
            for r in matched:
                if r not in seen:
                    seen.add(r)
                    rows.append(r)
        return rows

    def _beneath(self, prefix: str) -> list[int]:
        start = prefix.rstrip(".") + "."
        return [r for r, n in enumerate(self._names) if n.startswith(start)]

    def _unknown(self, name: str) -> UnknownVariableError:
        n = len(self._names)
        beneath = self._beneath(name)
        if beneath:
            shown = ", ".join(self._names[r] for r in beneath[:_N_SUGGESTIONS])
            more = ", ..." if len(beneath) > _N_SUGGESTIONS else ""
            return UnknownVariableError(
                f"{name}: a component, not a variable; it has {len(beneath):,} logged "
                f"variable(s) ({shown}{more}). Use select({name!r}) to get them together.",
                path=name, variables=[self._names[r] for r in beneath])
        tail = "." + name
        close = [x for x in self._names if x.endswith(tail)][:_N_SUGGESTIONS]
        close += [x for x in difflib.get_close_matches(name, self._names, n=_N_SUGGESTIONS)
                  if x not in close]
        close = close[:_N_SUGGESTIONS]
        hint = (f"Closest: {', '.join(close)}." if close else
                "No close match; SimResult.names lists them all.")
        return UnknownVariableError(
            f"{name}: no such variable among the {n:,} variables logged in the "
            f"{self._where()}. {hint}",
            path=name, variables=close)


def _check_suffix(path: Path, action: str) -> str:
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        got = repr(suffix) if suffix else "a file without suffix"
        raise DataError(f"{path}: cannot {action} {got}; allowed suffixes: "
                        f"{', '.join(SUFFIXES)}.", path=str(path))
    return suffix


def _unit_label(unit: str) -> str:
    return f"[{unit}]" if unit else "[1]"


#: The quantity an axis of several variables in one unit shows (plots label every axis
#: with a quantity and its unit).
QUANTITIES = {"V": "voltage", "A": "current", "C": "charge", "Wb": "flux linkage",
              "T": "flux density", "H": "inductance", "F": "capacitance",
              "Ohm": "resistance", "W": "power", "J": "energy", "K": "temperature",
              "N": "force", "N*m": "torque", "Pa": "pressure", "m": "position",
              "m/s": "velocity", "m/s^2": "acceleration", "rad": "angle",
              "rad/s": "angular velocity", "rad/s^2": "angular acceleration",
              "kg": "mass", "s": "time", "Hz": "frequency", "m^3/s": "flow rate",
              "": "dimensionless", "1": "dimensionless"}


def axis_label(unit: str, names: Sequence[str]) -> str:
    """``"quantity [unit]"`` for an axis showing ``names``, all in ``unit``: the
    variable's name when there is one, their common last segment (``w`` of ``a.w`` and
    ``b.w``), else the quantity the unit measures."""
    leaves = {n.rsplit(".", 1)[-1] for n in names}
    if len(names) == 1:
        quantity = names[0]
    elif len(leaves) == 1:
        quantity = leaves.pop()
    else:
        quantity = QUANTITIES.get(unit, "value")
    return f"{quantity} {_unit_label(unit)}"

