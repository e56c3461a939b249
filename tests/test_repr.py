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
