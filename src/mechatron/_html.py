"""Rich display in notebooks: ``_repr_html_`` of components, compiled models and results,
``_repr_svg_`` of components (the network diagram) and results (a plot).

Every text is escaped; nothing here imports a numerical package at module level, so the
modeling language can use it.
"""

from __future__ import annotations

import html

__all__ = ["table", "component_html", "compiled_html", "result_html", "component_svg",
           "diagram_svg", "result_svg"]

_STYLE = ("border-collapse:collapse;font-size:12px;margin:4px 0;"
          "font-family:system-ui,sans-serif")
_CELL = "padding:2px 8px;border-bottom:1px solid #ddd;text-align:left"


def _e(value) -> str:
    return html.escape(str(value), quote=True)


def table(headers, rows) -> str:
    """An HTML table with escaped cells."""
    head = "".join(f'<th style="{_CELL}">{_e(h)}</th>' for h in headers)
    body = "".join("<tr>" + "".join(f'<td style="{_CELL}">{_e(c)}</td>' for c in row)
                   + "</tr>" for row in rows)
    return f'<table style="{_STYLE}"><tr>{head}</tr>{body}</table>'


def _title(text: str, sub: str = "") -> str:
    extra = f' <span style="color:#666">{_e(sub)}</span>' if sub else ""
    return f"<div style=\"font-family:system-ui,sans-serif\"><b>{_e(text)}</b>{extra}</div>"


def component_html(component) -> str:
    """A component: its class and doc line, parameters (value as given, unit, doc),
    ports and parts."""
    from mechatron.core.component import Connector
    from mechatron.core.declarations import Parameter
    cls = type(component)
    doc = (cls.__doc__ or "").strip().splitlines()
    out = [_title(f"{cls.__name__} '{component.path or component.name or '(top)'}'",
                  doc[0] if doc else "")]
    params = [(k, component._values.get(k, d.default), d.unit, d.doc)
              for k, d in cls._declarations.items() if isinstance(d, Parameter)]
    if params:
        out.append(table(["parameter", "value", "unit", "description"],
                         [(k, getattr(v, "text", v), u, d) for k, v, u, d in params]))
    ports = [(k, type(p).__name__, getattr(type(p).domain, "name", ""), p.doc)
             for k, p in component._children.items() if isinstance(p, Connector)]
    if ports:
        out.append(table(["port", "connector", "domain", "description"], ports))
    parts = [(k, type(c).__name__) for k, c in component._children.items()
             if not isinstance(c, Connector)]
    if parts:
        out.append(table(["part", "class"], parts))
    return "".join(out)


def compiled_html(cm) -> str:
    """A compiled model: sizes, the states and the compile passes' timings."""
    out = [_title(f"CompiledModel '{cm.name}'",
                  f"{cm.nx} states, {cm.nz} algebraic, {len(cm.param_names)} parameters, "
                  f"{len(cm.names)} logged variables, {cm.nr} event relations")]
    out.append(table(["state", "unit"],
                     [(n, cm.units[cm.names.index(n)] if n in cm.names else "")
                      for n in cm.state_names[:50]]))
    timings = (cm.report or {}).get("timings", {})
    if timings:
        out.append(table(["pass", "time (s)"], [(k, f"{v:.3g}") for k, v in
                                                timings.items()]))
    return "".join(out)


def result_html(res, max_rows: int = 12, plotted: int = 3) -> str:
    """A simulation log: the solver profile, the final values of its first variables and
    a plot of the first few that change."""
    import base64
    import io

    import numpy as np
    t = res.t
    out = [_title(f"SimResult '{res.model_name}'" if res.model_name else "SimResult",
                  f"{len(res.names)} variables, {t.size} points, "
                  f"t = {t[0]:g} .. {t[-1]:g} s")]
    st = res.stats
    if st is not None:
        out.append(table(["solver", "steps", "rejected", "rhs evals", "events", "wall (s)"],
                         [(st.solver, st.steps, st.rejected_steps, st.rhs_evals,
                           sum(st.events.values()), f"{st.wall_time:.3g}")]))
    names = list(res.names)
    out.append(table(["variable", f"value at t = {t[-1]:g} s", "unit"],
                     [(n, f"{res.final(n):.6g}", res.units.get(n, ""))
                      for n in names[:max_rows]]
                     + ([(f"... {len(names) - max_rows} more", "", "")]
                        if len(names) > max_rows else [])))
    varying = [n for n in names if np.ptp(res[n]) > 0][:plotted]
    if varying and t.size > 1:
        fig = res.plot(*varying)
        fig.set_size_inches(6.0, 1.0 + 1.6 * len(fig.axes))
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=80)
        data = base64.b64encode(buf.getvalue()).decode("ascii")
        out.append(f'<img alt="{_e(", ".join(varying))}" '
                   f'src="data:image/png;base64,{data}"/>')
    return "".join(out)


# ------------------------------------------------------------------------------ SVG
def component_svg(component) -> str:
    """The network of a component as SVG: Graphviz's drawing of
    :class:`mechatron.report.diagram.Diagram` when ``dot`` is installed, else
    :func:`diagram_svg`'s own layout. A component that cannot be flattened on its own (a
    library part with open pins) is drawn as one box with its ports."""
    import shutil
    import subprocess
    try:
        from mechatron.report.diagram import Diagram
        diagram = Diagram.of(component)
    except Exception:             # not a valid network by itself: draw the part alone
        diagram = None
    if diagram is None or not diagram.nodes:
        return _single_svg(component)
    if shutil.which("dot") is not None:
        try:
            proc = subprocess.run(["dot", "-Tsvg"], input=diagram.dot(), text=True,
                                  capture_output=True, timeout=20, check=True)
            svg = proc.stdout
            return svg[svg.index("<svg"):]
        except (OSError, subprocess.SubprocessError, ValueError):
            pass
    return diagram_svg(diagram)


_BOX_W, _BOX_H, _GAP_X, _GAP_Y, _MARGIN = 130, 46, 70, 60, 20


def _svg_text(x, y, text, size=11, weight="normal", anchor="middle", colour="#222") -> str:
    return (f'<text x="{x:.1f}" y="{y:.1f}" font-size="{size}" font-weight="{weight}" '
            f'text-anchor="{anchor}" fill="{colour}" font-family="Helvetica,sans-serif">'
            f'{_e(text)}</text>')


def diagram_svg(diagram) -> str:
    """A schematic without Graphviz: the parts as boxes on a grid in declaration order,
    each port a dot in its domain's colour on the box's lower edge, a connection of two
    ports a line, of three or more a junction dot at their centre; a legend of the
    domains."""
    import math
    nodes = list(diagram.nodes.values())
    cols = max(1, math.ceil(math.sqrt(len(nodes))))
    pos, ports = {}, {}
    for k, node in enumerate(nodes):
        x = _MARGIN + (k % cols) * (_BOX_W + _GAP_X)
        y = _MARGIN + 24 + (k // cols) * (_BOX_H + _GAP_Y)
        pos[node.name] = (x, y)
        names = list(node.ports)
        for j, port in enumerate(names):
            ports[(node.name, port)] = (x + _BOX_W * (j + 1) / (len(names) + 1), y + _BOX_H)
        ports[(node.name, "")] = (x + _BOX_W / 2, y + _BOX_H / 2)
    rows = math.ceil(len(nodes) / cols)
    width = 2 * _MARGIN + cols * _BOX_W + (cols - 1) * _GAP_X
    legend_y = _MARGIN + 24 + rows * (_BOX_H + _GAP_Y)
    height = legend_y + 18 * len(diagram.domains) + _MARGIN
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'viewBox="0 0 {width} {height}">',
           _svg_text(width / 2, _MARGIN + 4, diagram.name, 13, "bold")]
    for ends in diagram.connections:
        points = [ports.get((e[0], e[1]), ports.get((e[0], ""))) for e in ends]
        colour = _e(ends[0][3])
        if len(points) == 2:
            (x1, y1), (x2, y2) = points
            out.append(f'<path d="M{x1:.1f},{y1:.1f} C{x1:.1f},{y1 + 30:.1f} '
                       f'{x2:.1f},{y2 + 30:.1f} {x2:.1f},{y2:.1f}" fill="none" '
                       f'stroke="{colour}" stroke-width="2"/>')
            continue
        cx = sum(p[0] for p in points) / len(points)
        cy = max(p[1] for p in points) + 25
        for x, y in points:
            out.append(f'<line x1="{x:.1f}" y1="{y:.1f}" x2="{cx:.1f}" y2="{cy:.1f}" '
                       f'stroke="{colour}" stroke-width="2"/>')
        out.append(f'<circle cx="{cx:.1f}" cy="{cy:.1f}" r="4" fill="{colour}"/>')
    for node in nodes:
        x, y = pos[node.name]
        if node.kind == "port":
            out.append(f'<circle cx="{x + _BOX_W / 2:.1f}" cy="{y + _BOX_H / 2:.1f}" r="12" '
                       'fill="white" stroke="#444"/>')
            out.append(_svg_text(x + _BOX_W / 2, y + _BOX_H / 2 + 4, node.name, 9))
            continue
        out.append(f'<rect x="{x}" y="{y}" width="{_BOX_W}" height="{_BOX_H}" rx="6" '
                   'fill="white" stroke="#444"/>')
        out.append(_svg_text(x + _BOX_W / 2, y + 17, node.name, 11, "bold"))
        out.append(_svg_text(x + _BOX_W / 2, y + 31, node.kind, 9, colour="#555"))
        for port, colour in node.ports.items():
            px, py = ports[(node.name, port)]
            out.append(f'<circle cx="{px:.1f}" cy="{py:.1f}" r="4" fill="{_e(colour)}">'
                       f'<title>{_e(node.name)}.{_e(port)}</title></circle>')
    for k, (name, colour) in enumerate(diagram.domains.items()):
        y = legend_y + 18 * k
        out.append(f'<rect x="{_MARGIN}" y="{y}" width="22" height="10" '
                   f'fill="{_e(colour)}"/>')
        out.append(_svg_text(_MARGIN + 30, y + 9, name, 10, anchor="start"))
    out.append("</svg>")
    return "\n".join(out)


def _single_svg(component) -> str:
    """One component as a box with its ports (no network to draw)."""
    from mechatron.core.component import Connector
    cls = type(component)
    ports = [(k, getattr(type(p).domain, "color", "#888"))
             for k, p in component._children.items() if isinstance(p, Connector)]
    width = max(_BOX_W, 34 * len(ports) + 20) + 2 * _MARGIN
    height = _BOX_H + 2 * _MARGIN + 16
    x, y = _MARGIN, _MARGIN
    w = width - 2 * _MARGIN
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
           f'viewBox="0 0 {width} {height}">',
           f'<rect x="{x}" y="{y}" width="{w}" height="{_BOX_H}" rx="6" fill="white" '
           'stroke="#444"/>',
           _svg_text(x + w / 2, y + 17, component.path or component.name or cls.__name__,
                     11, "bold"),
           _svg_text(x + w / 2, y + 31, cls.__name__, 9, colour="#555")]
    for j, (port, colour) in enumerate(ports):
        px = x + w * (j + 1) / (len(ports) + 1)
        out.append(f'<circle cx="{px:.1f}" cy="{y + _BOX_H}" r="4" fill="{_e(colour)}"/>')
        out.append(_svg_text(px, y + _BOX_H + 16, port, 9))
    out.append("</svg>")
    return "\n".join(out)


def result_svg(res, plotted: int = 4) -> str | None:
    """A simulation log as an SVG plot of its first few variables that change (states
    first), with quantity names and units; None when nothing changes."""
    import io

    import numpy as np
    names = list(getattr(res, "state_names", None) or []) + list(res.names)
    seen, varying = set(), []
    for n in names:
        if n in res and n not in seen and res.t.size > 1 and np.ptp(res[n]) > 0:
            varying.append(n)
            seen.add(n)
        if len(varying) == plotted:
            break
    if not varying:
        return None
    fig = res.plot(*varying)
    fig.set_size_inches(6.0, 1.0 + 1.6 * len(fig.axes))
    buf = io.StringIO()
    fig.savefig(buf, format="svg")
    svg = buf.getvalue()
    return svg[svg.index("<svg"):]
