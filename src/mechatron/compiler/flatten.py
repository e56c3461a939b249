"""Passes 1 and 2: flatten the instance tree, bind symbols, collect equations, turn
connections into equations, and check the model's topology.

The result is a :class:`FlatModel`: every parameter and variable by instance path with its
CasADi symbol, every equation as a residual with its origin, and the alias pairs that
connections imply (handed to alias elimination rather than written as equations).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca

from mechatron.core.component import Component, Connect, Connector, Element, SignalRef
from mechatron.core.context import BuildContext
from mechatron.core.declarations import (Across, Input, Output, Parameter, Start, Through,
                                         Variable)
from mechatron.core.domains import SIGNAL
from mechatron.core.events import EventAction
from mechatron.errors import ConnectError, ModelError, ParameterError, UnitError
from mechatron.units import dimensionality, to_si

__all__ = ["FlatModel", "FlatVariable", "FlatParameter", "FlatEquation", "flatten"]


@dataclass
class FlatParameter:
    name: str
    sym: ca.SX
    value: float
    unit: str
    doc: str
    owner: str
    bounds: tuple = (None, None)
    #: an external input of the model (a signal Input of the root component): a slot of
    #: ``p`` that ``simulate(inputs=...)`` fills with a signal of time
    is_input: bool = False


@dataclass
class FlatVariable:
    name: str
    sym: ca.SX
    unit: str
    doc: str
    kind: str          # "variable", "across", "through", "input", "output"
    owner: str         # path of the owning component (for ports: the component)
    start: float | None = None
    priority: str = "none"
    hint: str = ""     # what to try when this variable is left unmatched
    state_select: str = "default"   # "avoid" / "default" / "prefer" (state selection hint)


@dataclass
class FlatEquation:
    residual: ca.SX
    origin: object     # "r1: v == R*i" or "connect(r1.n, c1.p)"; str() formats it
    owner: str = ""    # path of the component the equation belongs to


@dataclass
class FlatModel:
    name: str
    context: BuildContext
    parameters: dict[str, FlatParameter] = field(default_factory=dict)
    variables: dict[str, FlatVariable] = field(default_factory=dict)
    equations: list[FlatEquation] = field(default_factory=list)
    aliases: list[tuple[str, str, float, str]] = field(default_factory=list)
    components: dict[str, str] = field(default_factory=dict)  # path -> class name
    time_scales: list = field(default_factory=list)           # SX of parameters
    #: Each connection set as a list of (port path, Domain, is_output); ``is_output`` is
    #: True for a signal output driving the set. For diagrams and reports.
    connection_sets: list = field(default_factory=list)
    #: Event actions (``mt.sample``/``mt.when``) as (EventAction, owner path).
    events: list = field(default_factory=list)
    #: Discrete variables (see _discrete_declarations): name -> "real"/"integer"/"boolean".
    discrete: dict = field(default_factory=dict)
    #: Equations of ``initial_equations()``, holding at the initial time only.
    initial_equations: list = field(default_factory=list)

    @property
    def time(self) -> ca.SX:
        return self.context.time


def _walk(root: Element):
    """Every element, parents first; each one's path is cached for the build."""
    root._path_cache = ""
    stack = [root]
    while stack:
        el = stack.pop()
        yield el
        children = list(el._children.values())
        for child in children:
            child._path_cache = _join(el._path_cache, child._name)
        stack.extend(reversed(children))


class _Origin:
    """Where an equation comes from; formatted only when a message needs it."""

    __slots__ = ("where", "lhs", "rhs")

    def __init__(self, where, lhs, rhs):
        self.where, self.lhs, self.rhs = where, lhs, rhs

    def __str__(self) -> str:
        return f"{self.where}: {_short(self.lhs)} == {_short(self.rhs)}"

    __repr__ = __str__


def _as_equations(items):
    out = []
    stack = [items]
    while stack:
        item = stack.pop()
        if isinstance(item, (list, tuple)):
            stack.extend(reversed(item))
        elif item is None:
            continue
        else:
            out.append(item)
    return out


def flatten(model: Component, name: str | None = None) -> FlatModel:
    """Flatten ``model``: bind symbols, collect equations and connections, validate.

    All problems with values, connections and references are collected and raised once.
    """
    if not isinstance(model, Component):
        raise TypeError(f"compile_model: expected a Component instance, got {model!r}.")
    name = name or model._name or type(model).__name__
    flat = FlatModel(name=name, context=BuildContext())
    problems = _Problems()
    elements = list(_walk(model))
    for el in elements:
        if isinstance(el, Component) and el._partial and el is not model:
            problems.append(f"{el.describe()}: {type(el).__name__} is a partial class "
                            "(an interface); use a concrete component.")
        if isinstance(el, Component):
            flat.components[el.path] = type(el).__name__
    _bind_symbols(flat, elements, problems)
    _external_inputs(flat, model)
    try:
        with flat.context:
            connects = _collect_equations(flat, elements, problems)
            _discrete_declarations(flat, elements, problems)
        _connections(flat, model, elements, connects, problems)
    finally:
        for el in elements:
            el._syms = None
            el._path_cache = None
    if problems:
        raise problems.error_class()(_summary(name, problems), problems=list(problems),
                                     path=name)
    return flat


class _Problems(list):
    """Messages collected by the validators, each with the error class it belongs to;
    ``append`` records a model problem, ``add`` one of a given class."""

    def __init__(self):
        super().__init__()
        self.kinds: list[type] = []

    def append(self, message: str) -> None:
        self.add(ModelError, message)

    def add(self, kind: type, message: str) -> None:
        super().append(message)
        self.kinds.append(kind)

    def error_class(self) -> type:
        """UnitError if every problem is a unit problem, ParameterError if every one is
        about values, ConnectError if any connection failed, else ModelError."""
        kinds = set(self.kinds)
        if kinds == {UnitError}:
            return UnitError
        if kinds <= {UnitError, ParameterError}:
            return ParameterError
        return ConnectError if ConnectError in kinds else ModelError


def _summary(name: str, problems: list[str]) -> str:
    if len(problems) == 1:
        return problems[0]
    return f"model '{name}': {len(problems)} problems:\n  " + "\n  ".join(problems)


def _bind_symbols(flat: FlatModel, elements, problems) -> None:
    ctx = flat.context
    for el in elements:
        syms = {}
        owner = el._parent if isinstance(el, Connector) else el
        owner_path = owner.path if owner is not None else ""
        for key, decl in type(el)._declarations.items():
            path = f"{el.path}.{key}" if el.path else key
            sym = ca.SX.sym(path)
            syms[key] = sym
            if isinstance(decl, Parameter):
                raw = el._values.get(key, decl.default)
                value = float("nan")
                if raw is None:
                    problems.add(ParameterError,
                                 f"{el.describe()}: parameter {key} has no value and no "
                                 f"default. Give one, e.g. {type(el).__name__}({key}=...).")
                else:
                    try:
                        value = to_si(raw, decl.unit, path)
                    except UnitError as exc:
                        problems.add(UnitError, str(exc))
                    else:
                        _check_range(el, key, decl, value, problems)
                flat.parameters[path] = FlatParameter(path, sym, value, decl.unit, decl.doc,
                                                      owner_path, (decl.min, decl.max))
            else:
                kind = ("across" if isinstance(decl, Across) else
                        "through" if isinstance(decl, Through) else
                        "input" if isinstance(decl, Input) else
                        "output" if isinstance(decl, Output) else "variable")
                start, priority = decl.start, decl.priority
                given = el._starts.get(key)
                if isinstance(given, Start):
                    try:
                        start = to_si(given.value, decl.unit, path)
                    except UnitError as exc:
                        problems.add(UnitError, str(exc))
                    priority = given.priority
                flat.variables[path] = FlatVariable(path, sym, decl.unit, decl.doc, kind,
                                                    owner_path, start, priority,
                                                    _domain_hint(el, decl),
                                                    getattr(decl, "state_select", "default"))
                ctx.unknowns[path] = sym
        el._syms = syms


def _external_inputs(flat: FlatModel, model: Component) -> None:
    """The root component's own signal inputs are the model's external inputs (as a
    top-level ``input`` of Modelica or a root Inport of Simulink). Each one gets a
    parameter slot ``p_u`` (named like the input; its default is the input's start value,
    0 without one, which ``simulate`` then asks for) and the equation ``u == p_u``; ``u``
    stays a logged variable."""
    for key, decl in type(model)._declarations.items():
        if not isinstance(decl, Input):
            continue
        var = flat.variables[key]
        default = var.start if var.start is not None else 0.0
        # a distinct symbol name: symbols are looked up by name in later passes
        sym = ca.SX.sym(f"{key}#input")
        flat.parameters[key] = FlatParameter(key, sym, float(default), var.unit, var.doc,
                                             "", (None, None), is_input=True)
        flat.equations.append(FlatEquation(var.sym - sym, f"{key} == external input {key}",
                                           ""))


def _domain_hint(el, decl) -> str:
    if isinstance(el, Connector):
        return _hint(el) or (type(el).domain.hint if type(el).domain else "")
    return ""


def _check_range(el, key, decl, value, problems) -> None:
    if value != value:
        problems.add(ParameterError, f"{el.describe()}: {key} is NaN.")
    if decl.min is not None and value < decl.min:
        problems.add(ParameterError,
                     f"{el.describe()}: {key} must be >= {decl.min:g}, got {value:g}.")
    if decl.max is not None and value > decl.max:
        problems.add(ParameterError,
                     f"{el.describe()}: {key} must be <= {decl.max:g}, got {value:g}.")


def _collect_equations(flat: FlatModel, elements, problems) -> list[tuple[Connect, str]]:
    connects = []
    for el in elements:
        if not isinstance(el, Component):
            continue
        where = el.path or flat.name
        # parents first, each class's own equations once
        for klass in reversed(type(el).__mro__):
            own = vars(klass).get("equations")
            if own is None or klass is Component:
                continue
            try:
                items = own(el)
            except ModelError:
                raise
            except Exception as exc:
                raise ModelError(f"{el.describe()}: {klass.__name__}.equations() failed: "
                                 f"{type(exc).__name__}: {exc}", path=where) from exc
            if klass is type(el):
                flat.time_scales.extend(ca.SX(s) for s in el.time_scales())
            for k, item in enumerate(_as_equations(items)):
                if isinstance(item, Connect):
                    connects.append((item, where))
                    continue
                if isinstance(item, EventAction):
                    flat.events.append((item, el.path))
                    continue
                _add_equation(flat, el, klass, k, item, problems)
    _discrete_states(flat, problems)
    pending = [eq for eq in flat.equations if eq.residual is None]
    if pending:
        res = ca.vertcat(*[eq.origin.lhs for eq in pending]) - \
            ca.vertcat(*[eq.origin.rhs for eq in pending])
        for eq, r in zip(pending, ca.vertsplit(res)):
            eq.residual = r
    return connects


def _discrete_states(flat: FlatModel, problems) -> None:
    """Check the targets of event actions; a target not differentiated anywhere is a
    discrete state: constant between events, ``der(v) == 0``."""
    ctx = flat.context
    by_sym = {v.sym.name(): v for v in flat.variables.values()}
    done: set[str] = set()
    for action, owner in flat.events:
        for var, _ in action.outputs + action.updates:
            name = var.name() if var.is_scalar() and var.is_symbolic() else None
            fv = by_sym.get(name) if name else None
            if fv is None or fv.kind == "input":
                problems.append(f"{owner or flat.name}: an event action assigns "
                                f"{str(var)[:40]}, which is not a variable of the model. "
                                "Assign a Variable or Output of the component.")
                continue
            if name in done or name in ctx.derivative:
                continue
            done.add(name)
            flat.equations.append(FlatEquation(
                ctx.der_symbol(name), f"{owner or flat.name}: der({name}) == 0 "
                "(discrete state, changed only by events)", owner))


def _add_equation(flat, el, klass, k, item, problems) -> None:
    where = el.path or flat.name
    if isinstance(item, (bool, int, float)) or not isinstance(item, (ca.SX, ca.DM)):
        problems.append(f"{el.describe()}: equation {k + 1} of {klass.__name__} is "
                        f"{item!r}, not an equation. Write equations with == between "
                        "expressions of variables.")
        return
    if not isinstance(item, ca.SX):
        item = ca.SX(item)
    for j in range(item.numel()):
        e = item if item.is_scalar() else item[j]
        if not e.is_op(ca.OP_EQ):
            problems.append(f"{el.describe()}: equation {k + 1} of {klass.__name__} is not "
                            f"an equation ({str(e)[:60]}). Write it with ==.")
            continue
        lhs, rhs = e.dep(0), e.dep(1)
        # the residual lhs - rhs is formed in bulk once all equations are in
        flat.equations.append(FlatEquation(None, _Origin(where, lhs, rhs), el.path))


def _short(expr, limit: int = 80) -> str:
    text = str(expr)
    return text if len(text) <= limit else text[:limit - 3] + "..."


class _UnionFind:
    def __init__(self):
        self.parent: dict[int, int] = {}

    def find(self, a: int) -> int:
        self.parent.setdefault(a, a)
        root = a
        while self.parent[root] != root:
            root = self.parent[root]
        while self.parent[a] != root:
            self.parent[a], a = root, self.parent[a]
        return root

    def union(self, a: int, b: int) -> None:
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self.parent[rb] = ra


def _port_path(p) -> str:
    if isinstance(p, SignalRef):
        return p.path()
    return p.path


def _resolve(flat: FlatModel, port, sym_owner):
    """A Connector, a SignalRef, or a bound signal symbol -> Connector or SignalRef."""
    if isinstance(port, (Connector, SignalRef)):
        return port
    if isinstance(port, ca.SX) and port.is_scalar() and port.is_symbolic():
        ref = sym_owner.get(port.name())
        if ref is not None:
            return ref
    return None


def _connections(flat: FlatModel, model, elements, connects, problems) -> None:
    sym_owner: dict[str, SignalRef] = {}
    for el in elements:
        for key, decl in type(el)._declarations.items():
            if isinstance(decl, (Input, Output)):
                sym_owner[f"{el.path}.{key}" if el.path else key] = SignalRef(el, key)
    uf = _UnionFind()
    ports: dict[int, object] = {}
    tried: set[int] = set()   # ports of a failed connect: not reported again as unconnected
    for con, where in connects:
        resolved = []
        for p in con.ports:
            r = _resolve(flat, p, sym_owner)
            if r is None:
                problems.append(f"{where}: connect() takes ports, got {p!r}. Pass a port "
                                "such as r1.p or a signal such as src.y.")
                continue
            resolved.append(r)
        for a, b in zip(resolved, resolved[1:]):
            msg = _compatible(a, b)
            if msg:
                problems.add(ConnectError, msg)
                tried.update((_key(a), _key(b)))
                continue
            ka = _key(a)
            kb = _key(b)
            ports[ka], ports[kb] = a, b
            uf.union(ka, kb)
    groups: dict[int, list] = {}
    for k, p in ports.items():
        groups.setdefault(uf.find(k), []).append(p)
    connected: set[int] = set(ports) | tried
    for group in groups.values():
        group.sort(key=_port_path)
        flat.connection_sets.append([_set_member(p) for p in group])
        if isinstance(group[0], SignalRef):
            _signal_set(flat, group, problems, model)
        else:
            _physical_set(flat, group)
    for el in elements:
        if isinstance(el, Connector) and id(el) not in connected and el._parent is not model:
            problems.append(f"port '{el.path}' ({el.domain}) is not connected. Connect it, "
                            "or remove the component. "
                            f"{_hint(el)}".rstrip())
        if isinstance(el, Component):
            for key, decl in type(el)._declarations.items():
                if isinstance(decl, Input) and _sigkey(el, key) not in connected \
                        and el is not model:   # the root's inputs are external inputs
                    problems.append(f"signal input '{_join(el.path, key)}' is not connected. "
                                    "Connect a source, e.g. blocks.Constant.")
    _check_references(flat, model, elements, uf, ports, problems)


def _set_member(p) -> tuple:
    if isinstance(p, SignalRef):
        return (_port_path(p), SIGNAL, isinstance(p.declaration, Output))
    return (_port_path(p), type(p).domain, False)


def _join(a, b):
    return f"{a}.{b}" if a else b


def _hint(port: Connector) -> str:
    for decl in type(port)._declarations.values():
        if isinstance(decl, Across) and decl.hint:
            return decl.hint
    return ""


def _key(p) -> int:
    return _sigkey(p.owner, p.name) if isinstance(p, SignalRef) else id(p)


def _sigkey(owner, name) -> int:
    return hash((id(owner), name)) & 0x7FFFFFFFFFFFFFF | 1 << 62


def _compatible(a, b) -> str:
    if isinstance(a, SignalRef) != isinstance(b, SignalRef):
        sig, phys = (a, b) if isinstance(a, SignalRef) else (b, a)
        return (f"cannot connect signal '{sig.path()}' with physical port '{phys.path}' "
                f"({phys.domain}). Use a converter between signals and physical "
                "quantities (e.g. a controlled source or a sensor).")
    if isinstance(a, Connector) and type(a).domain is not type(b).domain:
        return (f"cannot connect '{a.path}' ({type(a).domain}) with '{b.path}' "
                f"({type(b).domain}): ports belong to different domains.")
    if isinstance(a, Connector) and type(a) is not type(b) and (
            type(a).across_names() != type(b).across_names()):
        return (f"cannot connect '{a.path}' ({type(a).__name__}) with '{b.path}' "
                f"({type(b).__name__}): the connectors carry different variables.")
    return ""


def _signal_set(flat: FlatModel, group: list[SignalRef], problems, model=None) -> None:
    # an external input (a signal Input of the root component) drives its set
    outputs = [g for g in group if isinstance(g.declaration, Output)
               or (g.owner is model and isinstance(g.declaration, Input))]
    paths = ", ".join(g.path() for g in group)
    if not outputs:
        problems.append(f"signals {paths} are connected without an output to drive them. "
                        "Connect a source or a block output.")
        return
    if len(outputs) > 1:
        external = any(isinstance(o.declaration, Input) for o in outputs)
        problems.append(f"signal outputs {', '.join(o.path() for o in outputs)} are "
                        "connected together; an input can be driven by one output only"
                        + (" (an input of the model's root component is an external "
                           "input: it drives what it is connected to)." if external
                           else "."))
        return
    src = outputs[0].path()
    unit = outputs[0].declaration.unit
    for g in group:
        if g is not outputs[0]:
            if not _units_compatible(unit, g.declaration.unit):
                problems.add(UnitError,
                             f"cannot connect signal '{src}' ({unit}) to '{g.path()}' "
                             f"({g.declaration.unit}): the units have different "
                             f"dimensions ({dimensionality(unit)} vs "
                             f"{dimensionality(g.declaration.unit)}). Convert with a "
                             "physical_signals.PSGain with units, or pass a plain "
                             "signal through PhysicalToSignal/SignalToPhysical.")
                continue
            flat.aliases.append((g.path(), src, 1.0, f"connect({src}, {g.path()})"))


def _units_compatible(a: str, b: str) -> bool:
    """Signal units match if their dimensions agree; a dimensionless signal (a plain
    causal signal, unit "1") connects to any unit."""
    da, db = dimensionality(a), dimensionality(b)
    return not da or not db or da == db


def _physical_set(flat: FlatModel, group: list[Connector]) -> None:
    names = ", ".join(p.path for p in group)
    origin = f"connect({names})"
    cls = type(group[0])
    first = group[0].path
    for a in cls.across_names():
        for p in group[1:]:
            flat.aliases.append((f"{p.path}.{a}", f"{first}.{a}", 1.0, origin))
    for t in cls.through_names():
        if len(group) == 2:
            flat.aliases.append((f"{group[1].path}.{t}", f"{first}.{t}", -1.0, origin))
        else:
            total = sum((flat.variables[f"{p.path}.{t}"].sym for p in group[1:]),
                        flat.variables[f"{first}.{t}"].sym)
            flat.equations.append(FlatEquation(total, f"{origin}: sum of {t} == 0"))


def _check_references(flat, model, elements, uf: _UnionFind, ports, problems) -> None:
    """Every network of a domain that needs a reference must contain one."""
    net = _UnionFind()
    members: dict[int, list[Connector]] = {}
    for el in elements:
        if not isinstance(el, Component):
            continue
        by_domain: dict[object, list[int]] = {}
        for port in el.ports.values():
            root = uf.find(id(port))
            by_domain.setdefault(type(port).domain, []).append(root)
        for roots in by_domain.values():
            for r in roots[1:]:
                net.union(roots[0], r)
    for k, p in ports.items():
        if isinstance(p, Connector):
            members.setdefault(net.find(uf.find(k)), []).append(p)
    for root, plist in members.items():
        domain = type(plist[0]).domain
        if domain is None or not domain.needs_reference:
            continue
        owners = sorted({p._parent.path for p in plist if p._parent is not None})
        if any(p._parent is not None and p._parent._reference for p in plist):
            continue
        problems.append(f"{domain.name} network of {', '.join(owners)} has no reference. "
                        f"{domain.hint or 'Add a reference component to it.'}")


# -- hybrid declarations (mt.Discrete, initial_equations); kept apart from the passes above

def _discrete_declarations(flat: FlatModel, elements, problems) -> None:
    """Record the discrete variables with their kind and collect initial equations.

    A ``Discrete`` declaration is a discrete state even if no action assigns it (then it
    keeps its start value: ``der(v) == 0``); an action target that is not differentiated
    anywhere is a discrete Real (its ``der(v) == 0`` was added by ``_discrete_states``).
    """
    from mechatron.core.declarations import Discrete
    ctx = flat.context
    for eq in flat.equations:
        if isinstance(eq.origin, str) and eq.origin.endswith("changed only by events)"):
            name = ctx.integral.get(eq.residual.name()) if eq.residual.is_symbolic() else None
            if name:
                flat.discrete[name] = "real"
    for el in elements:
        for key, decl in type(el)._declarations.items():
            if not isinstance(decl, Discrete):
                continue
            path = _join(el.path, key)
            sym_name = flat.variables[path].sym.name()
            if sym_name not in flat.discrete and sym_name in ctx.derivative:
                problems.append(f"{el.describe()}: '{key}' is a Discrete variable and is "
                                "differentiated. Declare it as a Variable, or remove der().")
                continue
            if sym_name not in flat.discrete:
                flat.equations.append(FlatEquation(
                    ctx.der_symbol(sym_name), f"{el.path or flat.name}: der({sym_name}) == 0 "
                    "(discrete variable, changed only by events)", el.path))
            flat.discrete[sym_name] = decl.discrete_kind
    for el in elements:
        if not isinstance(el, Component):
            continue
        for klass in reversed(type(el).__mro__):
            own = vars(klass).get("initial_equations")
            if own is None or klass is Component:
                continue
            try:
                items = own(el)
            except ModelError:
                raise
            except Exception as exc:
                raise ModelError(f"{el.describe()}: {klass.__name__}.initial_equations() "
                                 f"failed: {type(exc).__name__}: {exc}",
                                 path=el.path) from exc
            for k, item in enumerate(_as_equations(items)):
                before = len(flat.equations)
                _add_equation(flat, el, klass, k, item, problems)
                for eq in flat.equations[before:]:
                    eq.residual = eq.origin.lhs - eq.origin.rhs
                    flat.initial_equations.append(eq)
                del flat.equations[before:]
