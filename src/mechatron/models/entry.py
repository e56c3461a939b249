"""What a database entry is."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from mechatron.errors import ModelError
from mechatron.units import to_si

__all__ = ["ModelEntry", "Experiment", "ParameterInfo"]


@dataclass(frozen=True)
class ParameterInfo:
    """A model parameter: SI unit, default, one-line description, provenance."""

    unit: str
    default: float
    doc: str
    source: str = ""


@dataclass(frozen=True)
class Experiment:
    """The default experiment: stop time, solver, tolerances, outputs of interest."""

    t_stop: float
    solver: str = "auto"
    rtol: float = 1e-6
    atol: float = 1e-8
    dt: float | None = None


@dataclass
class ModelEntry:
    """One model of the database.

    ``build(variant=..., **params)`` returns a model instance; parameters are given by name
    (numbers in SI or quantity strings). ``outputs`` maps labels to instance paths, per
    variant. ``expected`` maps labels to reference final values of the default experiment.

    ``reference_inputs`` maps a variant with external inputs (``simulate(inputs=...)``,
    FMU inputs, HIL) to a function ``(values, t_stop) -> inputs`` giving the signals that
    reproduce the built-in sources of the other variants (``values``: the parameters in
    SI); a variant not listed runs on its inputs' start values, which then must do so.
    ``driven_variants`` are variants whose inputs replace a controller of the others (an
    open-loop plant for an outside controller): no fixed signal reproduces the closed
    loop, so the variant comparison leaves them out (their tests close the loop).
    """

    name: str
    description: str
    parameters: dict[str, ParameterInfo]
    variants: dict[str, Callable[..., object]]
    outputs: dict[str, dict[str, str]]           # variant -> label -> path
    output_units: dict[str, str]
    experiment: Experiment
    expected: dict[str, float] = field(default_factory=dict)
    expected_tolerance: float = 1e-6
    #: Largest deviation allowed between variants, relative to the largest |value| of the
    #: output in the reference (first) variant, on the default experiment.
    variant_tolerance: float = 1e-6
    tags: tuple[str, ...] = ()
    default_variant: str = ""
    reference_inputs: dict[str, Callable[..., dict]] = field(default_factory=dict)
    driven_variants: tuple[str, ...] = ()

    def __post_init__(self):
        if not self.default_variant:
            self.default_variant = next(iter(self.variants))

    def values(self, **params) -> dict[str, float]:
        """Parameter values in SI: defaults with ``params`` applied (unit-checked)."""
        unknown = sorted(set(params) - set(self.parameters))
        if unknown:
            raise TypeError(f"model '{self.name}': unknown parameter(s) "
                            f"{', '.join(unknown)}. Valid names: "
                            f"{', '.join(self.parameters)}.")
        out = {}
        for key, info in self.parameters.items():
            raw = params.get(key, info.default)
            out[key] = to_si(raw, info.unit, f"{self.name}.{key}")
        return out

    def build(self, variant: str | None = None, **params):
        """A fresh model instance of ``variant`` (default: the first) with ``params``."""
        variant = variant or self.default_variant
        if variant not in self.variants:
            raise ModelError(f"model '{self.name}': no variant '{variant}'. Variants: "
                             f"{', '.join(self.variants)}.", path=self.name)
        return self.variants[variant](**self.values(**params))

    def inputs_for(self, variant: str | None = None, t_stop: float | None = None,
                   **params) -> dict | None:
        """The external-input signals of ``variant`` that reproduce the built-in sources
        of the other variants (see ``reference_inputs``), or None when its inputs' start
        values do."""
        fn = self.reference_inputs.get(variant or self.default_variant)
        if fn is None:
            return None
        return fn(self.values(**params),
                  self.experiment.t_stop if t_stop is None else t_stop)

    def output_paths(self, variant: str | None = None) -> dict[str, str]:
        return self.outputs[variant or self.default_variant]

    def __repr__(self) -> str:
        return f"<ModelEntry '{self.name}': variants {', '.join(self.variants)}>"
