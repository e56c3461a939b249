"""Schematic of a model: its parts as boxes with their ports, connections drawn in the
colour of their domain (Simscape's line colours), a legend of the domains used.

The drawing is made by Graphviz (``dot``). :func:`diagram_dot` returns the DOT source
(no Graphviz needed); :func:`write_diagram` renders it to SVG, PNG or PDF.

What is drawn: the model's top-level parts (a composite part is one box, its inside is not
drawn), each with the ports that take part in a connection; a connection between two ports
is one line; a connection of three or more ports meets at a junction dot. Signal
connections are arrows from the output to the inputs.
"""

from __future__ import annotations

import html
import shutil
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from mechatron._io import atomic_path, write_text
from mechatron.compiler.flatten import flatten
from mechatron.core.component import Component
from mechatron.errors import ModelError

__all__ = ["Diagram", "diagram_dot", "write_diagram", "FORMATS", "DOT_HINT"]

#: Output formats of :func:`write_diagram`, by file suffix.
FORMATS = {".svg": "svg", ".png": "png", ".pdf": "pdf", ".dot": "dot"}

DOT_HINT = ("Graphviz's `dot` is not installed: install it (Debian: apt-get install "
            "graphviz; `make demo` does it when run as root), or write --out FILE.dot "
            "and render it elsewhere.")


@dataclass
class _Node:
    name: str
    kind: str                                   # class name
    ports: dict[str, str] = field(default_factory=dict)   # port name -> colour


@dataclass
class Diagram:
    """The parts, connections and domains of a model, ready to be drawn."""

    name: str
    nodes: dict[str, _Node]
    #: Each connection: a list of (node, port, domain name, colour, is_output).
    connections: list[list[tuple[str, str, str, str, bool]]]
    domains: dict[str, str]                     # domain name -> colour, in order of use

    @classmethod
    def of(cls, model: Component, name: str | None = None) -> Diagram:
        flat = flatten(model, name)
        nodes: dict[str, _Node] = {}
        for path, kind in flat.components.items():
            if path and "." not in path:
                nodes[path] = _Node(path, kind)
        connections = []
        domains: dict[str, str] = {}
        for members in flat.connection_sets:
            ends = []
            for port_path, domain, is_output in members:
                head, _, rest = port_path.partition(".")
                node, port = (head, rest) if rest else ("", head)
                if node not in nodes:           # a port of the model itself
                    node = port_path
                    nodes.setdefault(node, _Node(node, "port"))
                    port = ""
                ends.append((node, port, domain.name, domain.color, is_output))
            if len({e[0] for e in ends}) < 2:
                continue                        # inside one composite part
            for node, port, dname, colour, _ in ends:
                if port:
                    nodes[node].ports[port] = colour
                domains.setdefault(dname, colour)
            connections.append(ends)
        return cls(flat.name, nodes, connections, domains)

    def dot(self) -> str:
        """The DOT source of the schematic."""
        out = [f'digraph "{_esc(self.name)}" {{',
               '  graph [rankdir=LR, splines=true, nodesep=0.35, ranksep=0.6, '
               f'fontname="Helvetica", label="{_esc(self.name)}", labelloc=t];',
               '  node [fontname="Helvetica", fontsize=10];',
               '  edge [penwidth=2, dir=none];']
        for node in self.nodes.values():
            out.append(f'  "{_esc(node.name)}" [{_node_label(node)}];')
        for k, ends in enumerate(self.connections):
            colour = ends[0][3]
            if len(ends) == 2:
                a, b = ends
                if b[4] and not a[4]:
                    a, b = b, a
                arrow = ', dir=forward, arrowsize=0.7' if a[4] else ''
                out.append(f'  {_end(a)} -> {_end(b)} [color="{colour}"{arrow}];')
                continue
            junction = f"junction{k}"
            out.append(f'  "{junction}" [shape=point, width=0.09, color="{colour}"];')
            signal = any(e[4] for e in ends)
            for e in ends:
                if signal and not e[4]:     # junction -> input, with an arrow
                    out.append(f'  "{junction}" -> {_end(e)} [color="{colour}", '
                               'dir=forward, arrowsize=0.7];')
                else:
                    out.append(f'  {_end(e)} -> "{junction}" [color="{colour}"];')
        if self.domains:
            rows = "".join(
                f'<TR><TD BGCOLOR="{c}" WIDTH="24"> </TD><TD ALIGN="LEFT">{_esc(d)}</TD></TR>'
                for d, c in self.domains.items())
            out.append('  subgraph cluster_legend { label="domains"; fontsize=10; '
                       'style=rounded; color="#999999";')
            out.append(f'    legend [shape=plaintext, label=<<TABLE BORDER="0" '
                       f'CELLSPACING="2">{rows}</TABLE>>]; }}')
        out.append("}")
        return "\n".join(out) + "\n"


def _esc(text: str) -> str:
    return html.escape(str(text), quote=True)


def _node_label(node: _Node) -> str:
    if node.kind == "port":
        return f'shape=circle, width=0.25, label="{_esc(node.name)}", fontsize=9'
    ports = "".join(f'<TD PORT="{_esc(p)}" BGCOLOR="{c}"><FONT COLOR="white" '
                    f'POINT-SIZE="8">{_esc(p)}</FONT></TD>' for p, c in node.ports.items())
    port_row = f"<TR>{ports}</TR>" if ports else ""
    span = max(len(node.ports), 1)
    return ('shape=plaintext, label=<<TABLE BORDER="1" CELLBORDER="0" CELLSPACING="1" '
            f'STYLE="ROUNDED"><TR><TD COLSPAN="{span}"><B>{_esc(node.name)}</B></TD></TR>'
            f'<TR><TD COLSPAN="{span}"><FONT POINT-SIZE="8">{_esc(node.kind)}</FONT>'
            f'</TD></TR>{port_row}</TABLE>>')


def _end(e) -> str:
    node, port = e[0], e[1]
    return f'"{_esc(node)}":"{_esc(port)}"' if port else f'"{_esc(node)}"'


def diagram_dot(model: Component, name: str | None = None) -> str:
    """DOT source of the schematic of ``model`` (flattened and validated first)."""
    return Diagram.of(model, name).dot()


def write_diagram(model: Component, path: str | Path, name: str | None = None) -> Path:
    """Render the schematic of ``model`` to ``path`` (.svg, .png, .pdf or .dot)."""
    path = Path(path)
    fmt = FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise ModelError(f"diagram: cannot write '{path}': use one of "
                         f"{', '.join(FORMATS)}.")
    source = diagram_dot(model, name)
    if fmt == "dot":
        return write_text(path, source)
    dot = shutil.which("dot")
    if dot is None:
        raise FileNotFoundError(DOT_HINT)
    with atomic_path(path) as tmp:
        run = subprocess.run([dot, f"-T{fmt}", "-o", str(tmp)], input=source.encode(),
                             capture_output=True, timeout=60)
        if run.returncode != 0:
            raise ModelError(f"diagram: Graphviz failed on '{path}': "
                             f"{run.stderr.decode(errors='replace').strip()}")
    return path
