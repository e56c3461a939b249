"""Measured data sets: time, inputs, outputs and their units, from CSV, Parquet or pandas.

An :class:`Experiment` is one measurement run. Its signals are bound to a model by label:
``inputs`` drive model parameters (a logged voltage drives ``source.V``), ``outputs`` are
compared with logged model variables. Each experiment may also fix parameters for its run
(``params``, e.g. a locked rotor) and give initial states (``x0``).

Every check names the file, the column and the row (rows are counted as in the file: the
header is row 1, the first data row is row 2; for a DataFrame, the index label):

* a missing column (with the columns that exist),
* NaN or infinite values,
* a time axis that is not strictly increasing,
* a unit that pint does not know, or whose dimension differs from the model's,
* a sample rate the model cannot follow (checked when a problem is set up, see
  :func:`mechatron.estimation.discretize.choose_substeps`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mechatron._io import atomic_path
from mechatron.errors import DataError, UnitError
from mechatron.units import to_si

__all__ = ["Experiment", "load_experiment", "unit_factor"]

_HEADER_UNIT = re.compile(r"^\s*(?P<name>.*?)\s*\[(?P<unit>[^\]]*)\]\s*$")


def unit_factor(unit: str, model_unit: str, where: str) -> float:
    """Factor converting a value in ``unit`` to ``model_unit`` (SI); DataError on a
    dimension mismatch."""
    if unit == model_unit or not unit:
        return 1.0
    try:
        return to_si(f"1 {unit}", model_unit, where)
    except UnitError as exc:
        raise DataError(f"{where}: unit '{unit}' does not match the model's '{model_unit}' "
                        f"({exc}). Give the column's unit in `units` or convert the data.",
                        path=where) from None


@dataclass
class Experiment:
    """One measured run.

    Attributes
    ----------
    name : str
    t : array (N,)
        Sample times in s, strictly increasing.
    inputs, outputs : dict label -> array (N,)
        Signals in the units of ``units``.
    units : dict label -> str
        Unit of each signal (pint syntax); ``""`` means "the model's unit".
    params : dict
        Parameters fixed for this run (model path -> value), e.g. ``{"locked": 1}``.
    x0 : dict
        Initial states (state name -> value); the others start from the model's start values.
    hold : "zoh" or "linear"
        Inputs between samples: held (a DAC) or linearly interpolated.
    sigma : dict label -> float
        Noise standard deviation of an output (sets its weight 1/sigma^2); by default the
        weight is ``1 / (range of the signal)^2`` so that signals count alike.
    source : str
        File the data came from, for messages.
    rows : array (N,)
        File row (or index label) of each sample, for messages.
    """

    name: str
    t: np.ndarray
    inputs: dict = field(default_factory=dict)
    outputs: dict = field(default_factory=dict)
    units: dict = field(default_factory=dict)
    params: dict = field(default_factory=dict)
    x0: dict = field(default_factory=dict)
    hold: str = "zoh"
    sigma: dict = field(default_factory=dict)
    source: str = "<arrays>"
    rows: np.ndarray | None = None

    def __post_init__(self):
        self.t = np.asarray(self.t, dtype=float).ravel()
        n = self.t.size
        if self.rows is None:
            self.rows = np.arange(n) + 2 if self.source.endswith(".csv") else np.arange(n)
        self.inputs = {k: np.asarray(v, dtype=float).ravel() for k, v in self.inputs.items()}
        self.outputs = {k: np.asarray(v, dtype=float).ravel()
                        for k, v in self.outputs.items()}
        if self.hold not in ("zoh", "linear"):
            raise DataError(f"{self.source}: experiment '{self.name}': hold must be 'zoh' "
                            f"or 'linear', got {self.hold!r}.", path=self.source)
        self.validate()

    # ------------------------------------------------------------------------------------
    def where(self, column: str, k: int | None = None) -> str:
        text = f"{self.source}: column '{column}'"
        if k is not None:
            text += f", row {self.rows[k]}"
        return text

    def validate(self) -> None:
        """Collect every problem of the data and raise one :class:`DataError`."""
        problems = []
        n = self.t.size
        if n < 2:
            problems.append(f"{self.source}: experiment '{self.name}' has {n} sample(s); "
                            "at least 2 are needed.")
        for label, arr in [("t", self.t)] + list(self.inputs.items()) \
                + list(self.outputs.items()):
            if arr.size != n:
                problems.append(f"{self.where(label)}: {arr.size} values for {n} times.")
                continue
            bad = np.flatnonzero(~np.isfinite(arr))
            if bad.size:
                problems.append(f"{self.where(label, bad[0])}: value is "
                                f"{arr[bad[0]]} ({bad.size} non-finite value(s) in all). "
                                "Remove or interpolate the gap.")
        if n >= 2 and np.all(np.isfinite(self.t)):
            dt = np.diff(self.t)
            bad = np.flatnonzero(dt <= 0)
            if bad.size:
                k = bad[0] + 1
                problems.append(f"{self.where('t', k)}: time {self.t[k]:g} s does not "
                                f"increase (previous {self.t[k - 1]:g} s; {bad.size} such "
                                "row(s)). Sort the data or drop duplicate samples.")
        for label, sigma in self.sigma.items():
            try:
                value = float(sigma)
            except (TypeError, ValueError):
                value = math.nan
            if not (math.isfinite(value) and value > 0):
                problems.append(f"{self.source}: experiment '{self.name}': sigma of "
                                f"'{label}' is a noise level and must be > 0, got {sigma!r}.")
        for label, unit in self.units.items():
            try:
                to_si(f"1 {unit}", unit, label) if unit else None
            except UnitError:
                problems.append(f"{self.where(label)}: unknown unit '{unit}'.")
        if problems:
            raise DataError(" ".join(problems), problems=problems, path=self.source)

    def select(self, rows=None, t_range=None, *, name: str | None = None) -> "Experiment":
        """The samples of a row range and/or a time range, as a new experiment (the times
        stay as measured; messages keep the file's row numbers).

        ``rows = (start, stop)`` counts data rows from 0, ``stop`` excluded (as a Python
        slice; either may be None, a negative number counts from the end);
        ``t_range = (t0, t1)`` keeps ``t0 <= t <= t1`` (s). Fit on the first 400 rows and
        validate on the rest: ``select(rows=(0, 400))`` and ``select(rows=(400, None))``.
        """
        keep = np.ones(self.n, dtype=bool)
        what = []
        if rows is not None:
            start, stop = (list(rows) + [None, None])[:2]
            idx = np.zeros(self.n, dtype=bool)
            idx[slice(start, stop)] = True
            keep &= idx
            what.append(f"rows {start}:{stop}")
        if t_range is not None:
            t0, t1 = t_range
            keep &= (self.t >= (-math.inf if t0 is None else t0)) & \
                (self.t <= (math.inf if t1 is None else t1))
            what.append(f"t in [{t0}, {t1}] s")
        if keep.sum() < 2:
            raise DataError(f"{self.source}: experiment '{self.name}': {' and '.join(what)} "
                            f"keep {int(keep.sum())} of {self.n} samples; at least 2 are "
                            "needed. Check the range.", path=self.source)
        return Experiment(name or self.name, t=self.t[keep],
                          inputs={k: v[keep] for k, v in self.inputs.items()},
                          outputs={k: v[keep] for k, v in self.outputs.items()},
                          units=dict(self.units), params=dict(self.params),
                          x0=dict(self.x0), hold=self.hold, sigma=dict(self.sigma),
                          source=self.source, rows=self.rows[keep])

    # ------------------------------------------------------------------------------------
    @property
    def n(self) -> int:
        return self.t.size

    @property
    def sample_time(self) -> float:
        return float(np.median(np.diff(self.t)))

    def signal(self, label: str) -> np.ndarray:
        if label in self.outputs:
            return self.outputs[label]
        if label in self.inputs:
            return self.inputs[label]
        raise DataError(f"{self.source}: experiment '{self.name}' has no signal '{label}'; "
                        f"it has {', '.join([*self.inputs, *self.outputs])}.",
                        path=self.source)

    def to_pandas(self):
        import pandas as pd
        cols = {"t": self.t, **self.inputs, **self.outputs}
        return pd.DataFrame(cols)

    def save(self, path) -> Path:
        """Write the data as CSV (``t`` first; ``name [unit]`` headers) or Parquet."""
        path = Path(path)
        df = self.to_pandas()
        df.columns = [f"{c} [{self.units.get(c, 's' if c == 't' else '')}]"
                      if self.units.get(c, "s" if c == "t" else "") else c
                      for c in df.columns]
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(path) as tmp:
            if path.suffix == ".parquet":
                df.to_parquet(tmp, index=False)
            else:
                df.to_csv(tmp, index=False, float_format="%.10g")
        return path

    # ------------------------------------------------------------------------------------
    @classmethod
    def from_frame(cls, df, *, time: str = "t", inputs=None, outputs=None, units=None,
                   name: str | None = None, source: str = "<DataFrame>", **kwargs):
        """An experiment from a pandas DataFrame.

        ``inputs`` / ``outputs`` map labels to column names (a list means label = column).
        Columns named ``"v [V]"`` carry their unit; ``units`` (column or label -> unit)
        overrides it. A missing column is an error listing the columns that exist.
        """
        inputs = _as_map(inputs)
        outputs = _as_map(outputs)
        units = dict(units or {})
        header_units, by_name = {}, {}
        for col in df.columns:
            mt_ = _HEADER_UNIT.match(str(col))
            if mt_:
                by_name[mt_.group("name")] = col
                header_units[mt_.group("name")] = mt_.group("unit")
            else:
                by_name[str(col)] = col
        problems = []
        is_csv = source.endswith(".csv")
        rows = (np.arange(len(df)) + 2) if is_csv else np.asarray(df.index)

        def column(label, col):
            if col not in by_name:
                problems.append(f"{source}: no column '{col}' (for '{label}'); columns: "
                                f"{', '.join(map(str, df.columns))}.")
                return None
            raw = df[by_name[col]]
            try:
                return np.asarray(raw, dtype=float)
            except (TypeError, ValueError):
                values = raw.astype(str).to_numpy()
                k = next(i for i, v in enumerate(values) if not _is_number(v))
                problems.append(f"{source}: column '{col}', row {rows[k]}: "
                                f"'{values[k]}' is not a number.")
                return None

        t = column("time", time)
        ins = {lab: column(lab, col) for lab, col in inputs.items()}
        outs = {lab: column(lab, col) for lab, col in outputs.items()}
        if problems:
            raise DataError(" ".join(problems), problems=problems, path=source)
        unit_of = {}
        for lab, col in [("t", time), *inputs.items(), *outputs.items()]:
            unit_of[lab] = units.get(lab, units.get(col, header_units.get(col, "")))
        tu = unit_of.pop("t") or "s"
        if tu != "s":
            t = t * unit_factor(tu, "s", f"{source}: column '{time}'")
        return cls(name=name or Path(source).stem, t=t, inputs=ins, outputs=outs,
                   units=unit_of, source=source, rows=rows, **kwargs)

    @classmethod
    def from_csv(cls, path, **kwargs):
        """An experiment from a CSV file (see :meth:`from_frame` for the arguments)."""
        import pandas as pd
        path = Path(path)
        if not path.exists():
            raise DataError(f"{path}: no such file.", path=str(path))
        try:
            df = pd.read_csv(path)
        except pd.errors.EmptyDataError:
            raise DataError(f"{path}: the file is empty; expected a header row (t and the "
                            "signals) and rows of numbers.", path=str(path)) from None
        except (pd.errors.ParserError, UnicodeDecodeError) as exc:
            raise DataError(f"{path}: cannot read it as CSV ({exc}).",
                            path=str(path)) from None
        return cls.from_frame(df, source=str(path), **kwargs)

    @classmethod
    def from_parquet(cls, path, **kwargs):
        """An experiment from a Parquet file (see :meth:`from_frame`)."""
        import pandas as pd
        path = Path(path)
        if not path.exists():
            raise DataError(f"{path}: no such file.", path=str(path))
        try:
            df = pd.read_parquet(path)
        except Exception as exc:    # pyarrow raises several types for a broken file
            raise DataError(f"{path}: cannot read it as Parquet ({exc}).",
                            path=str(path)) from None
        return cls.from_frame(df, source=str(path), **kwargs)


def load_experiment(path, **kwargs) -> Experiment:
    """:meth:`Experiment.from_csv` or :meth:`Experiment.from_parquet` by file suffix."""
    path = Path(path)
    if path.suffix == ".parquet":
        return Experiment.from_parquet(path, **kwargs)
    if path.suffix in (".csv", ".txt"):
        return Experiment.from_csv(path, **kwargs)
    raise DataError(f"{path}: unknown data format '{path.suffix}'; give a .csv or "
                    ".parquet file.", path=str(path))


def _as_map(spec) -> dict:
    if spec is None:
        return {}
    if isinstance(spec, dict):
        return dict(spec)
    return {c: c for c in spec}


def _is_number(text: str) -> bool:
    try:
        float(text)
        return True
    except ValueError:
        return False
