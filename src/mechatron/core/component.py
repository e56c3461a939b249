"""Components, connectors and the programmatic builder.

A *connector* is a port: a small set of across and through variables of one domain. A
*component* declares parameters, variables, ports and sub-components as class attributes
and returns its equations from ``equations()``. Equations add up along the class hierarchy
like Modelica's ``extends``: the compiler calls every class's own ``equations`` in the
order of the MRO, so a subclass can neither forget nor drop its parent's equations.

A model is a component whose equations include ``connect(...)``; :class:`System` builds one
programmatically for repeated structures.
"""

from __future__ import annotations

import copy
import numbers

from mechatron.core.declarations import (Across, Declaration, Input, Output, Parameter,
                                         Start, Through, Variable)
from mechatron.core.domain import Domain
from mechatron.errors import ModelError

__all__ = ["Element", "Connector", "Component", "System", "SignalRef", "Connect"]


class SignalRef:
    """A reference to a signal port (an :class:`Input` or :class:`Output` of an instance),
    as returned by attribute access outside compilation; used by ``connect``."""

    __slots__ = ("owner", "name")

    def __init__(self, owner: "Element", name: str):
        self.owner = owner
        self.name = name

    @property
    def declaration(self) -> Declaration:
        return type(self.owner)._declarations[self.name]

    def path(self) -> str:
        return _join(self.owner.path, self.name)

    def __repr__(self) -> str:
        return f"<signal {self.path() or self.name}>"


class Connect:
    """A connection between ports, as returned by :func:`connect`."""

    __slots__ = ("ports",)

    def __init__(self, ports):
        self.ports = tuple(ports)

    def __repr__(self) -> str:
        return f"connect({', '.join(map(repr, self.ports))})"


def _join(prefix: str, name: str) -> str:
    return f"{prefix}.{name}" if prefix else name


def _kind(item) -> str:
    if isinstance(item, Declaration):
        return f"{type(item).__name__} ({item.kind})"
    if isinstance(item, Connector):
        return f"port ({type(item).__name__})"
    return f"part ({type(item).__name__})"


def _check_shadowing(cls, klass, key, new, old, old_owner) -> None:
    """A name declared again in a subclass must keep its kind: a parameter may get a new
    default, but a variable may not hide an inherited port (nor a port a parameter)."""
    if old is None or old is new:
        return
    same = (isinstance(new, Declaration) and isinstance(old, Declaration)
            and type(new) is type(old)) or \
        (isinstance(new, Element) and isinstance(old, Element)
         and type(new) is type(old))
    if same:
        return
    raise TypeError(f"{cls.__name__}: '{key}' is declared as a {_kind(new)} in "
                    f"{klass.__name__}, which would hide the {_kind(old)} '{key}' declared "
                    f"in {old_owner.__name__}. Rename one of them.")


class Element:
    """Common base of connectors and components: declarations, sub-elements, a path."""

    _declarations: dict[str, Declaration] = {}
    _templates: dict[str, "Element"] = {}
    _partial = True

    def __init_subclass__(cls, partial: bool = False, **kwargs):
        super().__init_subclass__(**kwargs)
        cls._partial = partial
        decls: dict[str, Declaration] = {}
        templates: dict[str, Element] = {}
        where: dict[str, type] = {}     # name -> the class that declared it last
        for klass in reversed(cls.__mro__):
            own = [(k, v) for k, v in vars(klass).items() if isinstance(v, Declaration)]
            for key, value in sorted(own, key=lambda kv: kv[1].order):
                _check_shadowing(cls, klass, key, value, decls.get(key) or
                                 templates.get(key), where.get(key))
                decls[key] = value
                where[key] = klass
            for key, value in vars(klass).items():
                if isinstance(value, Element):
                    _check_shadowing(cls, klass, key, value, decls.get(key) or
                                     templates.get(key), where.get(key))
                    templates[key] = value
                    where[key] = klass
        cls._declarations = decls
        cls._templates = templates

    def __init__(self, *, doc: str = "", **kwargs):
        self.doc = doc
        self._name = ""
        self._parent: Element | None = None
        self._values: dict[str, object] = {}
        self._starts: dict[str, Start] = {}
        self._syms: dict | None = None
        self._children: dict[str, Element] = {}
        for key, template in type(self)._templates.items():
            self._adopt(key, copy.deepcopy(template))
        for key, value in kwargs.items():
            self._set(key, value)

    # -- construction -------------------------------------------------------------------
    def __set_name__(self, owner, name):
        self._name = name

    def _adopt(self, name: str, child: "Element") -> "Element":
        child._name = name
        child._parent = self
        self._children[name] = child
        self.__dict__[name] = child
        return child

    def _set(self, key: str, value) -> None:
        decl = type(self)._declarations.get(key)
        if isinstance(decl, Parameter):
            # a parameter of the enclosing class passed on: Resistor(R=R)
            self._values[key] = value._expr() if isinstance(value, Parameter) else value
        elif isinstance(decl, Variable) and not isinstance(decl, (Input,)):
            if isinstance(value, Start):
                self._starts[key] = value
            elif isinstance(value, (numbers.Real, str)) or hasattr(value, "magnitude"):
                self._starts[key] = Start(value, "high")
            else:
                raise TypeError(f"{type(self).__name__}({key}=...): a start value must be "
                                f"a number, a quantity or mt.Start, got {value!r}.")
        else:
            decls = type(self)._declarations.items()
            params = [k for k, d in decls if isinstance(d, Parameter)]
            starts = [k for k, d in decls if isinstance(d, Variable)
                      and not isinstance(d, Input)]
            raise TypeError(f"{type(self).__name__}() got an unexpected keyword '{key}'. "
                            f"Valid names: {', '.join(params) or '(no parameters)'}; "
                            f"start values: {', '.join(starts) or '(none)'}.")

    def __deepcopy__(self, memo):
        clone = object.__new__(type(self))
        memo[id(self)] = clone
        for key, value in self.__dict__.items():
            if key == "_parent":
                clone.__dict__[key] = None
            elif key in ("_syms",):
                clone.__dict__[key] = None
            else:
                clone.__dict__[key] = copy.deepcopy(value, memo)
        for name, child in clone._children.items():
            child._parent = clone
        return clone

    # -- identity -----------------------------------------------------------------------
    @property
    def name(self) -> str:
        return self._name

    @property
    def path(self) -> str:
        """Full instance path from the model root, e.g. ``"motor.emf.A"``."""
        cached = self.__dict__.get("_path_cache")
        if cached is not None:
            return cached
        if self._parent is None:
            return ""
        return _join(self._parent.path, self._name)

    def describe(self) -> str:
        """``"Resistor 'r1'"``: the class and the path, for messages."""
        return f"{type(self).__name__} '{self.path or self._name or '(top)'}'"

    def __repr__(self) -> str:
        return f"<{type(self).__name__} {self.path or self._name or '(top)'}>"

    def _repr_html_(self) -> str:
        """Notebook display: parameters with values and units, ports, parts."""
        from mechatron._html import component_html
        return component_html(self)

    def _repr_svg_(self) -> str:
        """Notebook display: the network diagram (parts, ports, connections coloured by
        domain); Graphviz draws it when installed."""
        from mechatron._html import component_svg
        return component_svg(self)

    # -- symbols (bound by the compiler) -------------------------------------------------
    def _symbol(self, name: str):
        if self._syms is not None:
            return self._syms[name]
        decl = type(self)._declarations[name]
        if isinstance(decl, (Input, Output)):
            return SignalRef(self, name)
        raise ModelError(f"{self.describe()}: '{name}' has a value only while the model "
                         "compiles. Use it inside equations(); read results from a "
                         "SimResult.", path=_join(self.path, name))

    @property
    def time(self):
        """The simulation time symbol (only inside ``equations()``)."""
        from mechatron.core.context import current
        return current().time


class Connector(Element, partial=True):
    """A port of one domain: its across and through variables."""

    domain: Domain | None = None

    def __init_subclass__(cls, domain: Domain | None = None, **kwargs):
        super().__init_subclass__(**kwargs)
        if domain is not None:
            cls.domain = domain
        for key, decl in cls._declarations.items():
            if not isinstance(decl, (Across, Through)):
                raise ModelError(f"connector {cls.__name__}: '{key}' must be an Across or "
                                 f"Through declaration, got {type(decl).__name__}.")

    @classmethod
    def across_names(cls) -> list[str]:
        return [k for k, d in cls._declarations.items() if isinstance(d, Across)]

    @classmethod
    def through_names(cls) -> list[str]:
        return [k for k, d in cls._declarations.items() if isinstance(d, Through)]


class Component(Element, partial=True):
    """Base of every component and model.

    Subclasses declare :class:`~mechatron.Parameter`, :class:`~mechatron.Variable`, ports
    (connector instances) and sub-components as class attributes and return equations (and
    ``connect`` calls) from :meth:`equations`. Keyword arguments of the constructor set
    parameter values and variable start values; an unknown keyword raises ``TypeError``.

    Class keywords: ``partial=True`` for abstract bases (never instantiated in a model),
    ``reference=True`` for references (ground) of a domain.
    """

    _reference = False

    def __init_subclass__(cls, reference: bool = False, **kwargs):
        super().__init_subclass__(**kwargs)
        cls._reference = reference

    def equations(self) -> list:
        """Equations of this class (not of its parents), written with ``==``."""
        return []

    def initial_equations(self) -> list:
        """Equations that hold at the initial time only (Modelica's ``initial equation``),
        e.g. ``mt.der(self.w) == 0`` for a steady start (see ``mt.steady_state``). They
        replace start values: a state's start value becomes a guess unless it was given
        with priority high. Like ``equations()``, they add up along the class hierarchy."""
        return []

    def time_scales(self) -> list:
        """Shortest intervals (expressions of parameters, s) this component switches on,
        e.g. a pulse's on and off times. Variable-step solvers keep their steps below half
        the smallest, so that no switching interval can be stepped over unseen."""
        return []

    @property
    def components(self) -> dict[str, "Component"]:
        return {k: v for k, v in self._children.items() if isinstance(v, Component)}

    @property
    def ports(self) -> dict[str, Connector]:
        return {k: v for k, v in self._children.items() if isinstance(v, Connector)}


class System(Component):
    """A model assembled programmatically, for repeated structures.

    >>> m = System("ladder")
    >>> r = m.add("r1", Resistor(R=1))
    >>> m.connect(r.n, c.p)
    """

    def __init__(self, name: str = "model", *, doc: str = ""):
        super().__init__(doc=doc)
        self._name = name
        self._connects: list[Connect] = []
        self._extra: list = []
        self._initial: list = []

    def add(self, name: str, element: Element) -> Element:
        """Add a sub-component (or port) under ``name`` and return it."""
        if not name.isidentifier():
            raise ModelError(f"System '{self._name}': '{name}' is not a valid name; use "
                             "letters, digits and underscores.")
        if name in self._children or name in type(self)._declarations:
            raise ModelError(f"System '{self._name}': a part named '{name}' exists already.")
        if hasattr(type(self), name) or name.startswith("_"):
            raise ModelError(f"System '{self._name}': '{name}' is the name of a System "
                             "method or attribute; choose another name for the part.")
        if not isinstance(element, Element):
            raise TypeError(f"System.add: expected a Component, got {element!r}.")
        if element._parent is not None:
            raise ModelError(f"System '{self._name}': {element!r} belongs to "
                             f"'{element._parent.path or element._parent._name}' already.")
        return self._adopt(name, element)

    def input(self, name: str, unit: str = "1", *, start: float | None = None,
              doc: str = "") -> SignalRef:
        """Declare an external input of this model (``mt.Input`` on the root component)
        and return it for ``connect``; give its signal with ``simulate(..., inputs=...)``.

        ``start`` is its default value (used when ``inputs`` omits it). The System's class
        becomes a subclass holding the declaration (same name), so an instance with inputs
        is not picklable; the compiled model is.
        """
        if not name.isidentifier() or name.startswith("_"):
            raise ModelError(f"System '{self._name}': '{name}' is not a valid input name; "
                             "use letters, digits and underscores.")
        if name in self._children or name in type(self)._declarations or \
                hasattr(type(self), name):
            raise ModelError(f"System '{self._name}': the name '{name}' is taken already "
                             "(a part, an input or a System method); choose another.")
        cls = type(self)
        self.__class__ = type(cls.__name__, (cls,), {
            "__module__": cls.__module__, "__doc__": cls.__doc__,
            name: Input(unit, start=start, doc=doc)})
        return SignalRef(self, name)

    def connect(self, *ports) -> None:
        """Connect two or more ports (or a signal output to inputs)."""
        if len(ports) < 2:
            raise ModelError(f"System '{self._name}': connect needs at least two ports.")
        self._connects.append(Connect(ports))

    def add_equation(self, equation) -> None:
        """Add an equation written with ``==`` over the parts' variables."""
        self._extra.append(equation)

    def add_initial_equation(self, equation) -> None:
        """Add an equation that holds at the initial time only (see
        :meth:`Component.initial_equations`)."""
        self._initial.append(equation)

    def equations(self):
        return list(self._connects) + [eq() if callable(eq) else eq for eq in self._extra]

    def initial_equations(self):
        return [eq() if callable(eq) else eq for eq in self.__dict__.get("_initial", [])]
