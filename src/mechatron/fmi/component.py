"""``FMUComponent``: an FMU made by any FMI tool, used as a sampled block of a model.

The block's signal ports are the FMU's real-valued inputs (:class:`~mechatron.Input`) and
outputs (:class:`~mechatron.Output`), named after the FMU's variables (a character that
cannot appear in a Python name becomes ``_``: the output ``inertia.w`` is the port
``inertia_w``); its real parameters are :class:`~mechatron.Parameter` declarations under
the same rule, with the FMU's start values as defaults, so ``params={"plant.resistor_R":
...}`` or ``FMUComponent("plant.fmu", resistor_R=...)`` set them. ``Ts`` is the
communication step and ``offset`` the first communication point (the sample time of
:mod:`mechatron.library.blocks.discrete`).

Semantics (a sampled block, as ``ZeroOrderHold`` and ``DiscreteTransferFunction``): at the
communication point ``t_k = offset + k Ts`` the block's outputs take the FMU's outputs at
``t_k`` (held until ``t_k+1``; blocks sampled at the same instant read the new values, in
signal-flow order); then the inputs are read after that tick, ``u(t_k+)``, and the FMU is
advanced over ``[t_k, t_k+1]`` with them held. An FMU output with direct feedthrough from
an input therefore reflects the input of the previous communication point (the usual
explicit co-simulation master). The stepping itself runs in
:mod:`mechatron.fmi.cosim`, between the host's integration intervals.
"""

from __future__ import annotations

import keyword
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from mechatron.core import Clock, Input, Output, Parameter, sample
from mechatron.errors import ModelError
from mechatron.library.blocks.interfaces import Sampled
from mechatron.units import check_unit

__all__ = ["FMUComponent", "FMUDescription", "describe_fmu", "port_name"]

#: Prefix of the hidden parameter that holds an output's value for the next tick.
HOLD_PREFIX = "next_"


def port_name(name: str) -> str:
    """The port or parameter name of the FMU variable ``name``: every character that
    cannot appear in a Python name becomes ``_`` (``inertia.w`` -> ``inertia_w``,
    ``der(x)`` -> ``der_x_``); a leading digit or a keyword gets a ``v_`` prefix."""
    out = re.sub(r"\W", "_", name)
    if not out or out[0].isdigit() or out[0] == "_" or keyword.iskeyword(out):
        out = "v_" + out
    return out


@dataclass
class FMUVariable:
    """One real FMU variable as the block sees it."""

    name: str                  # the FMU's name
    port: str                  # the Python name of the port or parameter
    vr: int                    # value reference
    unit: str
    start: float | None
    doc: str


@dataclass
class FMUDescription:
    """What :class:`FMUComponent` needs from an FMU's model description."""

    path: str
    fmi: str                   # "2.0" or "3.0"
    model_name: str
    kinds: tuple               # ("cs",), ("me",) or both
    inputs: list = field(default_factory=list)
    outputs: list = field(default_factory=list)
    parameters: list = field(default_factory=list)
    default_step: float | None = None


_DESCRIPTIONS: dict = {}


def _unit(v) -> str:
    unit = getattr(v, "unit", None) or getattr(getattr(v, "declaredType", None), "unit",
                                               None)
    if not unit:
        return "1"
    try:
        check_unit(unit, "FMU variable")
    except Exception:       # a unit pint does not read (a tool's own name): no check
        return "1"
    return unit


def _float(value) -> float | None:
    try:
        return float(value)
    except (TypeError, ValueError):
        return None


def describe_fmu(path) -> FMUDescription:
    """Read an FMU's model description (cached by path and modification time)."""
    p = Path(path).expanduser().resolve()
    if not p.is_file():
        raise ModelError(f"FMUComponent: no FMU file at '{path}'. Give the path of a "
                         ".fmu file (export one with `mechatron fmu NAME`).")
    key = (str(p), os.stat(p).st_mtime_ns)
    cached = _DESCRIPTIONS.get(key)
    if cached is not None:
        return cached
    try:
        from fmpy import read_model_description
    except ImportError:       # pragma: no cover - fmpy is a dependency
        raise ModelError("FMUComponent needs FMPy (pip install fmpy).") from None
    try:
        md = read_model_description(str(p), validate=False)
    except Exception as exc:
        raise ModelError(f"FMUComponent: '{path}' is not a readable FMU ({exc}).") from None
    if not md.fmiVersion.startswith(("2.", "3.")):
        raise ModelError(f"FMUComponent '{path}': FMI {md.fmiVersion} is not supported; "
                         "FMI 2.0 and 3.0 are.")
    kinds = tuple(k for k, part in (("cs", md.coSimulation), ("me", md.modelExchange))
                  if part is not None)
    desc = FMUDescription(path=str(p), fmi=md.fmiVersion[:3], model_name=md.modelName,
                          kinds=kinds)
    if md.defaultExperiment is not None:
        desc.default_step = _float(md.defaultExperiment.stepSize)
    for v in md.modelVariables:
        if v.type not in ("Real", "Float64") or getattr(v, "dimensions", None):
            continue
        item = FMUVariable(v.name, port_name(v.name), int(v.valueReference), _unit(v),
                           _float(v.start), v.description or "")
        if v.causality == "input":
            desc.inputs.append(item)
        elif v.causality == "output":
            desc.outputs.append(item)
        elif v.causality == "parameter" and v.variability in ("fixed", "tunable"):
            desc.parameters.append(item)
    _DESCRIPTIONS[key] = desc
    return desc


_CLASSES: dict = {}


def _block_class(desc: FMUDescription, outputs: tuple | None) -> type:
    """The concrete subclass of :class:`FMUComponent` for ``desc`` (cached)."""
    key = (desc.path, id(desc), outputs)
    cls = _CLASSES.get(key)
    if cls is not None:
        return cls
    chosen = desc.outputs
    if outputs is not None:
        by_name = {v.name: v for v in desc.outputs} | {v.port: v for v in desc.outputs}
        missing = [o for o in outputs if o not in by_name]
        if missing:
            raise ModelError(f"FMUComponent '{desc.path}': no output named "
                             f"{', '.join(missing)}. Outputs: "
                             f"{', '.join(v.name for v in desc.outputs) or '(none)'}.")
        chosen = [by_name[o] for o in dict.fromkeys(outputs)]
    attrs: dict = {}
    owners: dict = {}

    def declare(name, decl, what):
        if name in attrs or hasattr(FMUComponent, name):
            raise ModelError(f"FMUComponent '{desc.path}': the {what} named '{name}' "
                             f"clashes with {owners.get(name, 'a name of the block')}. "
                             "Select the outputs you need with outputs=[...].")
        attrs[name] = decl
        owners[name] = f"the {what} '{name}'"

    for v in desc.inputs:
        declare(v.port, Input(v.unit, start=v.start if v.start is not None else 0.0,
                              doc=v.doc or f"FMU input {v.name}"), "input")
    for v in chosen:
        declare(v.port, Output(v.unit, start=v.start if v.start is not None else 0.0,
                               doc=v.doc or f"FMU output {v.name}"), "output")
        declare(HOLD_PREFIX + v.port, Parameter(v.unit, default=0.0, doc=(
            f"Value of {v.name} at the coming communication point (set by the "
            "co-simulation)")), "held value")
    for v in desc.parameters:
        declare(v.port, Parameter(v.unit, default=v.start if v.start is not None else 0.0,
                                  doc=v.doc or f"FMU parameter {v.name}"), "parameter")
    attrs.update(__module__=FMUComponent.__module__, __doc__=FMUComponent.__doc__,
                 __qualname__=f"FMUComponent[{desc.model_name}]",
                 _description=desc, _outputs=chosen)
    cls = type("FMUComponent", (FMUComponent,), attrs)
    _CLASSES[key] = cls
    return cls


class FMUComponent(Sampled, partial=True):
    """An FMU as a sampled block (see :mod:`mechatron.fmi.component`).

    Parameters
    ----------
    path : path
        The ``.fmu`` file (FMI 2.0 or 3.0, co-simulation or model exchange).
    kind : {"cs", "me"}, optional
        Which interface to use when the FMU has both; default co-simulation.
        Model exchange is integrated by FMPy's CVODE over each communication step.
    outputs : list of str, optional
        The FMU outputs to give ports (by FMU name or port name); default all.
    Ts : float
        Communication step in s (default: the FMU's default experiment step, else 1e-3).
    offset : float
        First communication point in s (default 0).
    **values
        FMU parameters by port name, and start values of the outputs.

    Examples
    --------
    >>> motor = mt.FMUComponent("dc_motor.fmu", Ts=1e-3, outputs=["inertia.w"])
    """

    def __new__(cls, path=None, *args, kind: str | None = None, outputs=None, **kwargs):
        if cls is not FMUComponent:     # a copy (deepcopy builds with object.__new__)
            return super().__new__(cls)
        if path is None:
            raise TypeError("FMUComponent() needs the path of a .fmu file.")
        desc = describe_fmu(path)
        chosen = None if outputs is None else tuple(outputs)
        return super().__new__(_block_class(desc, chosen))

    def __init__(self, path=None, *, kind: str | None = None, outputs=None, **kwargs):
        desc = type(self)._description
        if kind is None:
            kind = "cs" if "cs" in desc.kinds else "me"
        if kind not in ("cs", "me"):
            raise ModelError(f"FMUComponent '{desc.path}': kind must be 'cs' "
                             f"(co-simulation) or 'me' (model exchange), got {kind!r}.")
        if kind not in desc.kinds:
            raise ModelError(f"FMUComponent '{desc.path}': the FMU provides no "
                             f"{'co-simulation' if kind == 'cs' else 'model exchange'} "
                             f"interface (it has {', '.join(desc.kinds)}).")
        if "Ts" not in kwargs and desc.default_step:
            kwargs["Ts"] = desc.default_step
        super().__init__(**kwargs)
        self.kind = kind

    def equations(self):
        held = {getattr(self, v.port): getattr(self, HOLD_PREFIX + v.port)
                for v in type(self)._outputs}
        if not held:
            return []
        return [sample(Clock(self.Ts, self.offset), output=held)]

    def external_block(self) -> dict:
        """What the co-simulation (:mod:`mechatron.fmi.cosim`) needs to step this block;
        kept in ``CompiledModel.report["external_blocks"]``."""
        desc = type(self)._description
        return {"type": "fmu", "path": self.path, "file": desc.path, "kind": self.kind,
                "fmi": desc.fmi,
                "inputs": [(v.port, v.name, v.vr) for v in desc.inputs],
                "outputs": [(v.port, v.name, v.vr) for v in type(self)._outputs],
                "parameters": [(v.port, v.name, v.vr) for v in desc.parameters]}
