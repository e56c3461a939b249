"""Schematics: every connection drawn once, in its domain's colour, with a legend."""

import re
import shutil

import pytest

import mechatron as mt
from mechatron.cli import main
from mechatron.core.domains import ELECTRICAL, ROTATIONAL
from mechatron.library import blocks
from mechatron.library import electrical as el
from mechatron.report import Diagram, diagram_dot, write_diagram

needs_dot = pytest.mark.skipif(shutil.which("dot") is None,
                               reason="Graphviz `dot` not installed (make test installs it "
                                      "when run as root)")


def test_dc_motor_diagram_has_every_part_and_connection():
    entry = mt.models.get("dc_motor")
    d = Diagram.of(entry.build("acausal"))
    assert set(d.nodes) == {"source", "resistor", "inductor", "emf", "inertia", "damper",
                            "ground", "fixed"}
    # 4 electrical nets and 2 mechanical ones, as the model connects them
    colours = sorted(ends[0][3] for ends in d.connections)
    assert colours.count(ELECTRICAL.color) == 4
    assert colours.count(ROTATIONAL.color) == 2
    assert d.domains == {"electrical": ELECTRICAL.color, "rotational": ROTATIONAL.color}
    # the emf touches both domains through its four ports
    assert d.nodes["emf"].ports == {"p": ELECTRICAL.color, "n": ELECTRICAL.color,
                                    "A": ROTATIONAL.color, "B": ROTATIONAL.color}


def test_signal_connections_are_arrows_from_the_output():
    m = mt.System("drive")
    src = m.add("src", blocks.Step())
    v = m.add("v", el.ControlledVoltageSource())
    r = m.add("r", el.Resistor())
    g = m.add("g", el.ElectricalReference())
    m.connect(src.y, v.u)
    m.connect(v.p, r.p)
    m.connect(r.n, v.n, g.port)
    dot = diagram_dot(m)
    assert re.search(r'"src":"y" -> "v":"u" \[color="#000000", dir=forward', dot)


@needs_dot
def test_svg_is_written_with_domain_colours(tmp_path):
    path = write_diagram(mt.models.get("dc_motor").build("acausal"), tmp_path / "d.svg")
    svg = path.read_text()
    assert svg.lstrip().startswith("<?xml") and "<svg" in svg
    assert ELECTRICAL.color.lower() in svg.lower() and ROTATIONAL.color.lower() in svg.lower()


@needs_dot
def test_cli_diagram(tmp_path, capsys):
    out = tmp_path / "dc.svg"
    assert main(["diagram", "dc_motor", "--out", str(out)]) == 0
    assert out.stat().st_size > 1000
    assert "wrote" in capsys.readouterr().out


def test_cli_diagram_refuses_an_equation_variant_and_a_bad_suffix(tmp_path, capsys):
    assert main(["diagram", "dc_motor", "--variant", "ode", "--out",
                 str(tmp_path / "d.svg")]) == 2
    assert "written as equations" in capsys.readouterr().err
    assert main(["diagram", "dc_motor", "--out", str(tmp_path / "d.txt")]) == 2
    assert ".svg" in capsys.readouterr().err
