"""The library catalog: every concrete component of :mod:`mechatron.library`, described from
its declarations (Simscape's library browser, Modelica's generated documentation tables).

The catalog walks every subpackage of ``mechatron.library`` (electrical, rotational,
translational, mechanisms, electromechanical, thermal, magnetic, hydraulic,
physical_signals, blocks, multibody, and any added later), imports each of its modules,
and collects the concrete (non-partial) :class:`~mechatron.Component` subclasses defined
there. A component belongs to the *section* (subpackage) that defines it; its *domains*
are those of its ports (``signal`` for causal inputs and outputs).

Use :func:`components` and :func:`sections` from Python, ``mechatron library
[--domain D] [--json]`` from the shell, and ``python -m mechatron.library.catalog --docs
DIR`` to (re)generate the domain pages ``DIR/<section>.md`` and ``DIR/README.md``.
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import pkgutil
import sys
from dataclasses import dataclass, field
from pathlib import Path

from mechatron._io import write_text
import mechatron.core.domains as core_domains
import mechatron.library as library
from mechatron.core import Component, Connector, Domain, Input, Output, Parameter

__all__ = ["PortInfo", "ParameterInfo", "ComponentInfo", "SectionInfo", "sections",
           "components", "section_names", "import_errors", "write_docs", "main"]

#: Modules of the library that hold tooling, not components.
SKIP_MODULES = ("mechatron.library.catalog", "mechatron.library.cli")


@dataclass(frozen=True)
class PortInfo:
    """A port: a connector (``kind="port"``) or a causal signal (``"input"``/``"output"``)."""

    name: str
    domain: str
    kind: str = "port"
    unit: str = ""
    doc: str = ""

    def label(self) -> str:
        if self.kind == "port":
            return f"{self.name} ({self.domain})"
        return f"{self.name} ({self.kind}, {self.unit})"


@dataclass(frozen=True)
class ParameterInfo:
    """A parameter as declared: unit, default (``None``: required), bounds, description."""

    name: str
    unit: str
    default: object
    min: float | None
    max: float | None
    doc: str

    def label(self) -> str:
        default = "(required)" if self.default is None else f"{self.default:g}" \
            if isinstance(self.default, (int, float)) else str(self.default)
        unit = "" if self.unit == "1" else f" {self.unit}"
        return f"{self.name}={default}{unit}"


@dataclass
class ComponentInfo:
    """One concrete component class, described from its declarations."""

    name: str
    qualname: str
    section: str
    domains: tuple[str, ...]
    ports: list[PortInfo]
    parameters: list[ParameterInfo]
    description: str
    cls: type = field(repr=False, compare=False, default=None)

    def as_dict(self) -> dict:
        return {"name": self.name, "class": self.qualname, "section": self.section,
                "domains": list(self.domains),
                "ports": [vars(p) for p in self.ports],
                "parameters": [vars(p) for p in self.parameters],
                "description": self.description}


@dataclass
class SectionInfo:
    """A library section (subpackage): its physical domain, if it has one of its own, the
    package docstring (sign rules, port names), and its components."""

    name: str
    module: str
    doc: str
    domain: Domain | None
    components: list[ComponentInfo]

    @property
    def domains(self) -> list[str]:
        """Every domain of the section's ports, its own first."""
        seen = [self.domain.name] if self.domain else []
        for c in self.components:
            seen.extend(d for d in c.domains if d not in seen)
        return seen

    def as_dict(self) -> dict:
        d = self.domain
        return {"name": self.name, "module": self.module, "doc": self.doc,
                "across": d.across if d else None, "through": d.through if d else None,
                "color": d.color if d else None, "domains": self.domains,
                "components": [c.as_dict() for c in self.components]}


_ERRORS: dict[str, str] = {}


def import_errors() -> dict[str, str]:
    """Modules of the library that failed to import during the last walk, with the error
    (``{}`` when all imported)."""
    return dict(_ERRORS)


def section_names() -> list[str]:
    """The subpackages of ``mechatron.library``, in the order of ``library.__all__`` then
    alphabetically for any others."""
    found = [m.name for m in pkgutil.iter_modules(library.__path__) if m.ispkg]
    order = [n for n in getattr(library, "__all__", []) if n in found]
    return order + sorted(n for n in found if n not in order)


def _modules(section: str):
    """Import the section's package and every module below it."""
    name = f"{library.__name__}.{section}"
    try:
        pkg = importlib.import_module(name)
    except Exception as exc:  # noqa: BLE001 - another section may be mid-edit
        _ERRORS[name] = f"{type(exc).__name__}: {exc}"
        return
    yield pkg
    for info in pkgutil.walk_packages(getattr(pkg, "__path__", []), prefix=name + "."):
        if info.name in SKIP_MODULES:
            continue
        try:
            yield importlib.import_module(info.name)
        except Exception as exc:  # noqa: BLE001
            _ERRORS[info.name] = f"{type(exc).__name__}: {exc}"


def _summary(cls) -> str:
    doc = inspect.cleandoc(cls.__dict__.get("__doc__") or "")
    first = doc.split("\n\n")[0].replace("\n", " ").strip()
    return first


def describe(cls) -> ComponentInfo:
    """The :class:`ComponentInfo` of one component class."""
    ports, params = [], []
    for key, template in cls._templates.items():
        if isinstance(template, Connector):
            dom = type(template).domain
            ports.append(PortInfo(key, dom.name if dom else "?", "port", "",
                                  template.doc or (type(template).__doc__ or "").strip()))
    for key, decl in cls._declarations.items():
        if isinstance(decl, Parameter):
            params.append(ParameterInfo(key, decl.unit, decl.default, decl.min, decl.max,
                                        decl.doc))
        elif isinstance(decl, (Input, Output)):
            ports.append(PortInfo(key, core_domains.SIGNAL.name,
                                  "input" if isinstance(decl, Input) else "output",
                                  decl.unit, decl.doc))
    domains = tuple(dict.fromkeys(p.domain for p in ports))
    section = cls.__module__.split(".")[2]
    return ComponentInfo(cls.__name__, f"{cls.__module__}.{cls.__qualname__}", section,
                         domains, ports, params, _summary(cls), cls)


def _known_domains(infos) -> dict[str, Domain]:
    known = {d.name: d for d in vars(core_domains).values() if isinstance(d, Domain)}
    for info in infos:
        for port in info.cls._templates.values():
            dom = type(port).domain if isinstance(port, Connector) else None
            if dom is not None:
                known.setdefault(dom.name, dom)
    return known


def sections() -> list[SectionInfo]:
    """Walk the library now and describe every section with its components."""
    _ERRORS.clear()
    result = []
    seen: set[int] = set()
    for section in section_names():
        comps = []
        pkg = None
        for module in _modules(section):
            pkg = pkg or module
            for _, obj in inspect.getmembers(module, inspect.isclass):
                if (issubclass(obj, Component) and not obj._partial and id(obj) not in seen
                        and obj.__module__.startswith(f"{library.__name__}.{section}")):
                    seen.add(id(obj))
                    comps.append(describe(obj))
        comps.sort(key=lambda c: c.name)
        doc = inspect.cleandoc(pkg.__doc__ or "") if pkg else ""
        result.append(SectionInfo(section, f"{library.__name__}.{section}", doc, None, comps))
    known = _known_domains([c for s in result for c in s.components])
    for s in result:
        s.domain = known.get(s.name)
    return result


def components(domain: str | None = None) -> list[ComponentInfo]:
    """Every concrete component (of one section, if ``domain`` is given).

    Raises
    ------
    KeyError
        If ``domain`` is not a section of the library; the message lists the valid ones.
    """
    secs = sections()
    if domain is None:
        return [c for s in secs for c in s.components]
    for s in secs:
        if s.name == domain:
            return list(s.components)
    raise KeyError(f"unknown library domain {domain!r}; valid: "
                   f"{', '.join(s.name for s in secs)}.")


# ------------------------------------------------------------------------------- docs
def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


def _bounds(p: ParameterInfo) -> str:
    lo = "" if p.min is None else f"{p.min:g}"
    hi = "" if p.max is None else f"{p.max:g}"
    return f"[{lo}, {hi}]" if (lo or hi) else ""


def section_page(s: SectionInfo, known: dict[str, Domain] | None = None) -> str:
    """The Markdown page of one section."""
    known = known or {}
    lines = [f"# {s.name.replace('_', ' ').capitalize()}", "",
             f"Module `{s.module}`. *Generated by `python -m mechatron.library.catalog "
             "--docs docs/domains` from the declarations; do not edit.*", ""]
    if s.doc:
        lines += [s.doc, ""]
    doms = [known.get(d) or (s.domain if s.domain and s.domain.name == d else None)
            for d in s.domains]
    doms = [d for d in doms if d is not None]
    if doms:
        lines += ["| domain | across | through | colour |", "|---|---|---|---|"]
        lines += [f"| {d.name} | {d.across} | {d.through} | `{d.color}` |" for d in doms]
        lines += [""]
    lines += ["Sign convention (all domains): a through variable is positive when it flows "
              "into the component at a port; the across variable of a two-port is A minus "
              "B; positive across times through is power absorbed.", ""]
    lines += [f"## Components ({len(s.components)})", ""]
    if not s.components:
        lines += ["(none yet)", ""]
        return "\n".join(lines)
    lines += ["| component | ports | parameters | description |", "|---|---|---|---|"]
    for c in s.components:
        lines.append(f"| [`{c.name}`](#{c.name.lower()}) | "
                     f"{_cell(', '.join(p.label() for p in c.ports))} | "
                     f"{_cell(', '.join(p.label() for p in c.parameters))} | "
                     f"{_cell(c.description)} |")
    lines.append("")
    for c in s.components:
        lines += [f"### {c.name}", "", f"`{c.qualname}`", ""]
        doc = inspect.cleandoc(c.cls.__dict__.get("__doc__") or "") if c.cls else ""
        if doc:
            lines += [doc, ""]
        if c.ports:
            lines += ["| port | domain | kind | unit | description |", "|---|---|---|---|---|"]
            lines += [f"| `{p.name}` | {p.domain} | {p.kind} | {p.unit} | {_cell(p.doc)} |"
                      for p in c.ports]
            lines.append("")
        if c.parameters:
            lines += ["| parameter | unit | default | bounds | description |",
                      "|---|---|---|---|---|"]
            lines += [f"| `{p.name}` | {p.unit} | "
                      f"{'(required)' if p.default is None else p.default} | "
                      f"{_bounds(p)} | {_cell(p.doc)} |" for p in c.parameters]
            lines.append("")
    return "\n".join(lines)


def write_docs(directory) -> list[Path]:
    """Write one page per section, ``<directory>/<section>.md``, and the index
    ``README.md``; return the paths written."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    secs = sections()
    known = _known_domains([c for s in secs for c in s.components])
    written = []
    for s in secs:
        path = out / f"{s.name}.md"
        write_text(path, section_page(s, known) + "\n")
        written.append(path)
    total = sum(len(s.components) for s in secs)
    index = ["# Component library by domain", "",
             "*Generated by `python -m mechatron.library.catalog --docs docs/domains`; "
             "`mechatron library` prints the same catalog.*", "",
             f"{total} components in {len(secs)} sections.", "",
             "| section | across | through | components |", "|---|---|---|---|"]
    for s in secs:
        d = s.domain
        index.append(f"| [{s.name}]({s.name}.md) | {d.across if d else '-'} | "
                     f"{d.through if d else '-'} | {len(s.components)} |")
    write_text(out / "README.md", "\n".join(index) + "\n")
    written.append(out / "README.md")
    return written


def main(argv=None) -> int:
    """``python -m mechatron.library.catalog --docs DIR``: write the domain pages."""
    parser = argparse.ArgumentParser(prog="python -m mechatron.library.catalog",
                                     description="Generate the library's domain pages.")
    parser.add_argument("--docs", metavar="DIR", required=True,
                        help="directory for <section>.md and README.md")
    args = parser.parse_args(argv)
    write_docs(args.docs)
    return 1 if _ERRORS else 0


if __name__ == "__main__":
    sys.exit(main())
