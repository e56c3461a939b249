"""Rich display in notebooks: ``_repr_html_`` of components, compiled models and results.

Every text is escaped; nothing here imports a numerical package at module level, so the
modeling language can use it.
"""

from __future__ import annotations

import html

__all__ = ["table", "component_html", "compiled_html", "result_html"]

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
