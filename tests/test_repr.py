"""Notebook display: components, compiled models and results show their parameters,
sizes, solver profile, final values and a plot, with every text escaped."""

import pytest

import mechatron as mt
from mechatron.library import electrical as el


class Tricky(mt.Component):
    """A <b>tag</b> & an ampersand in the doc."""

    R = mt.Parameter("Ohm", default="2 kohm", doc="Resistance <not a tag>")
    p = el.Pin(doc="Positive pin")
    n = el.Pin(doc="Negative pin")
    r = el.Resistor(R=R)

    def equations(self):
        return [mt.connect(self.p, self.r.p), mt.connect(self.r.n, self.n)]


def test_a_component_lists_parameters_ports_and_parts_escaped():
    html = Tricky()._repr_html_()
    assert "&lt;b&gt;tag&lt;/b&gt; &amp; an ampersand" in html and "<b>tag</b>" not in html
    assert "2 kohm" in html and "Resistance &lt;not a tag&gt;" in html
    assert ">p<" in html and ">Pin<" in html and ">electrical<" in html
    assert ">r<" in html and ">Resistor<" in html
    # a passed-on parameter shows its expression
    assert ">R<" in Tricky().r._repr_html_()


def test_a_compiled_model_and_a_result_show_sizes_profile_values_and_a_plot():
    model = mt.models.get("dc_motor").build("acausal")
    cm = mt.compile_model(model)
    html = cm._repr_html_()
    assert "2 states, 0 algebraic" in html and "inertia.w" in html and ">flatten<" in html
    res = mt.simulate(cm, 0.05)
    html = res._repr_html_()
    assert f"{len(res.names)} variables" in html and f">{res.stats.solver}<" in html
    assert f"{res.final('source.v'):.6g}" in html
    assert html.count("data:image/png;base64,") == 1


def _parse_svg(text):
    import xml.etree.ElementTree as ET
    root = ET.fromstring(text)
    assert root.tag.endswith("svg")
    return root


def _texts(root):
    return {"".join(e.itertext()).strip() for e in root.iter() if e.tag.endswith("text")}


@pytest.mark.parametrize("graphviz", [True, False])
def test_a_model_draws_its_network_as_svg(graphviz, monkeypatch):
    """The DC motor's diagram names every top-level part; without Graphviz the own layout
    draws one curve per two-port connection and one junction per larger set, in the
    colour of each connection's domain, and a legend of the domains."""
    import shutil
    from mechatron.report.diagram import Diagram
    model = mt.models.get("dc_motor").build("acausal")
    diagram = Diagram.of(model)
    if graphviz and shutil.which("dot") is None:
        pytest.skip("Graphviz is not installed")
    if not graphviz:
        monkeypatch.setattr(shutil, "which", lambda name: None)
    root = _parse_svg(model._repr_svg_())
    texts = " ".join(_texts(root))
    for part in diagram.nodes:
        assert part in texts
    if not graphviz:
        curves = [e for e in root.iter() if e.tag.endswith("path")]
        junctions = [e for e in root.iter() if e.tag.endswith("circle")
                     and e.get("r") == "4" and not list(e)]
        two = [c for c in diagram.connections if len(c) == 2]
        assert len(curves) == len(two)
        assert len(junctions) == len(diagram.connections) - len(two)
        assert sorted(c.get("stroke") for c in curves) == sorted(c[0][3] for c in two)
        for name in diagram.domains:
            assert name in texts


def test_a_part_alone_is_one_box_with_its_ports():
    root = _parse_svg(el.Resistor()._repr_svg_())
    texts = _texts(root)
    assert {"Resistor", "p", "n"} <= texts
    assert sum(e.tag.endswith("circle") for e in root.iter()) == 2    # the two pins


def test_a_result_plots_itself_as_svg_with_units():
    res = mt.simulate(mt.models.get("dc_motor").build("ode"), 0.05)
    svg = res._repr_svg_()
    _parse_svg(svg)
    # matplotlib writes its text as paths, with the strings in comments/ids: the axis
    # labels carry the units
    assert "rad/s" in svg and "[A]" in svg
