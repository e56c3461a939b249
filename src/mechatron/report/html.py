"""One self-contained HTML page per database model: description, schematic, parameter
table, plots of the default experiment with its expected values, the variants compared,
and the solver profile. Images are embedded (inline SVG and base64 PNG), so the page is a
single file that opens anywhere.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import io
import shutil
from importlib import resources
from pathlib import Path
from string import Template

from mechatron._io import write_text
import mechatron
from mechatron.models.compare import Comparison, compare_variants, relative
from mechatron.models.entry import ModelEntry
from mechatron.report.diagram import DOT_HINT, Diagram

__all__ = ["render_report", "write_report", "diagram_variant"]


def _template() -> Template:
    text = resources.files("mechatron.report").joinpath("templates/report.html").read_text()
    return Template(text)


def _png(fig) -> str:
    import matplotlib.pyplot as plt
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _e(x) -> str:
    return html.escape(str(x))


def _num(x: float) -> str:
    return f"{x:.6g}"


def diagram_variant(entry: ModelEntry) -> str | None:
    """The first variant of ``entry`` that is a network of parts (the one to draw)."""
    for v in entry.variants:
        if entry.build(v).components:
            return v
    return None


def _diagram_svg(entry: ModelEntry) -> str:
    variant = diagram_variant(entry)
    if variant is None:
        return "<p>Every variant of this model is written as equations: no network to draw.</p>"
    source = Diagram.of(entry.build(variant), entry.name).dot()
    dot = shutil.which("dot")
    if dot is None:
        return f"<p>{_e(DOT_HINT)}</p><pre>{_e(source)}</pre>"
    import subprocess
    run = subprocess.run([dot, "-Tsvg"], input=source.encode(), capture_output=True,
                         timeout=60, check=False)
    if run.returncode != 0:
        return f"<p>Graphviz failed: {_e(run.stderr.decode(errors='replace'))}</p>"
    svg = run.stdout.decode()
    svg = svg[svg.index("<svg"):]                 # drop the XML prolog and doctype
    return f"<figcaption>variant '{_e(variant)}'</figcaption>{svg}"


def _rows(rows) -> str:
    out = []
    for row in rows:
        cells = []
        for cell in row:
            cls, text = cell if isinstance(cell, tuple) else ("", cell)
            cells.append(f'<td class="{cls}">{_e(text)}</td>' if cls else f"<td>{_e(text)}</td>")
        out.append("<tr>" + "".join(cells) + "</tr>")
    return "\n".join(out)


def _profile(cmp: Comparison) -> list:
    rows = []
    for name, r in cmp.results.items():
        st = r.stats
        events = sum(st.events.values()) if st.events else 0
        rows.append([name, st.solver, ("num", f"{st.steps:,}"),
                     ("num", f"{st.rejected_steps:,}"), ("num", f"{st.rhs_evals:,}"),
                     ("num", f"{st.jac_evals:,}"), ("num", f"{events:,}"),
                     ("num", f"{st.wall_time * 1e3:.2f} ms"),
                     ("num", "-" if st.compile_time is None
                      else f"{st.compile_time * 1e3:.1f} ms")])
    return rows


def render_report(entry: ModelEntry, cmp: Comparison | None = None) -> str:
    """The HTML text of ``entry``'s report (simulates its variants unless ``cmp`` is
    given)."""
    cmp = cmp or compare_variants(entry)
    ref = cmp.reference
    res = cmp.results[ref]
    values = entry.values()
    params = [[k, ("num", _num(values[k])), info.unit, info.doc, info.source]
              for k, info in entry.parameters.items()]

    import matplotlib.pyplot as plt
    paths = entry.output_paths(ref)
    fig, axes = plt.subplots(len(paths), 1, figsize=(8.0, 2.2 * len(paths)), sharex=True,
                             squeeze=False, layout="constrained")
    for axis, (label, path) in zip(axes[:, 0], paths.items()):
        axis.plot(res.t, res[path])
        axis.set_ylabel(f"{label} [{entry.output_units.get(label, '') or '1'}]")
        axis.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("t [s]")
    fig.suptitle(f"{entry.name} ({ref}): default experiment")
    plot = _png(fig)

    expected = []
    for label, ref_value in entry.expected.items():
        if label not in paths:
            continue
        got = res.final(paths[label])
        err = relative(abs(got - ref_value), abs(ref_value))
        ok = err <= entry.expected_tolerance
        expected.append([label, ("num", _num(got)), ("num", _num(ref_value)),
                         ("ok" if ok else "bad", f"{err:.2e}"),
                         ("num", f"{entry.expected_tolerance:g}")])

    comparison = []
    for v, per in cmp.deviations.items():
        for label, d in per.items():
            ok = d["max_rel"] <= entry.variant_tolerance
            comparison.append([v, label, entry.output_units.get(label, ""),
                               ("num", f"{d['max_abs']:.3e}"),
                               ("ok" if ok else "bad", f"{d['max_rel']:.3e}"),
                               ("num", f"{entry.variant_tolerance:g}")])
    if len(cmp.results) > 1:
        text = (f"Every variant on {len(res.t)} common output points, compared with the "
                f"reference variant '{ref}'; deviations relative to the largest |value| "
                "of the reference.")
    else:
        text = "This model has one variant."
    exp = entry.experiment
    exp_text = (f"t_stop = {exp.t_stop:g} s, solver {exp.solver}"
                + (f", dt {exp.dt:g} s" if exp.dt else
                   f", rtol {exp.rtol:g}, atol {exp.atol:g}"))
    return _template().substitute(
        name=_e(entry.name), description=_e(entry.description),
        tags="".join(f"<span>{_e(t)}</span>" for t in entry.tags),
        diagram=_diagram_svg(entry), parameter_rows=_rows(params), experiment=_e(exp_text),
        plot=plot, expected_rows=_rows(expected), comparison_text=_e(text),
        comparison_rows=_rows(comparison), comparison_plot=_png(cmp.figure()),
        profile_rows=_rows(_profile(cmp)), version=_e(mechatron.__version__),
        date=_dt.date.today().isoformat())


def write_report(entry: ModelEntry, path: str | Path) -> Path:
    """Write ``entry``'s report to ``path`` (an ``.html`` file)."""
    path = Path(path)
    if path.suffix.lower() not in (".html", ".htm"):
        raise ValueError(f"report: '{path}' must end in .html.")
    if not path.parent.exists():
        raise FileNotFoundError(f"report: the folder '{path.parent}' does not exist; "
                                "create it first.")
    return write_text(path, render_report(entry))
