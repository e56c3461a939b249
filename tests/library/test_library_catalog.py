"""The library catalog, ``mechatron library`` and the generated domain pages."""

import inspect
import json
import pkgutil

import pytest

import mechatron as mt
import mechatron.library as library
from mechatron.cli import main
from mechatron.library import catalog
from mechatron.library import rotational as rot


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def concrete_classes_by_hand():
    """An independent walk: every concrete Component subclass reachable as an attribute
    of a library package or module, by module name."""
    found = set()
    for info in pkgutil.walk_packages(library.__path__, prefix="mechatron.library."):
        if info.name in catalog.SKIP_MODULES:
            continue
        module = __import__(info.name, fromlist=["_"])
        for obj in vars(module).values():
            if (inspect.isclass(obj) and issubclass(obj, mt.Component) and not obj._partial
                    and obj.__module__.startswith("mechatron.library.")):
                found.add(f"{obj.__module__}.{obj.__qualname__}")
    return found


def test_catalog_finds_every_concrete_component_once():
    names = [c.qualname for c in catalog.components()]
    assert len(names) == len(set(names))
    assert set(names) == concrete_classes_by_hand()
    assert catalog.import_errors() == {}


def test_catalog_describes_ports_parameters_and_domains_from_declarations():
    by_name = {c.name: c for c in catalog.components("rotational")}
    gear = by_name["LossyGear"]
    assert [(p.name, p.domain) for p in gear.ports] == [("A", "rotational"),
                                                         ("B", "rotational"),
                                                         ("S", "rotational")]
    eta = next(p for p in gear.parameters if p.name == "eta")
    assert (eta.unit, eta.default, eta.min, eta.max) == ("1", 0.9, 0, 1)
    assert eta.doc == rot.LossyGear.eta.doc
    src = by_name["IdealTorqueSource"]
    assert src.domains == ("rotational", "signal")
    assert ("tau_in", "input", "N*m") in [(p.name, p.kind, p.unit) for p in src.ports]
    assert by_name["Inertia"].description.startswith("Rotating inertia")
    screw = {c.name: c for c in catalog.components("mechanisms")}["LeadScrew"]
    assert screw.domains == ("rotational", "translational")


def test_unknown_domain_in_python_lists_the_valid_ones():
    with pytest.raises(KeyError, match="valid: electrical, rotational"):
        catalog.components("rotatonal")


def test_cli_library_lists_every_component_by_domain(capsys):
    code, out, err = run(capsys, "library")
    assert code == 0, err
    for c in catalog.components():
        assert c.name in out
    assert "rotational (" in out and "across angular velocity w (rad/s)" in out
    assert "J=0.001 kg*m^2" in out                     # parameters with units, defaults
    assert f"{len(catalog.components())} components" in out


def test_cli_library_domain_filter_and_json(capsys):
    code, out, err = run(capsys, "library", "--domain", "mechanisms", "--json")
    assert code == 0, err
    data = json.loads(out)
    assert [d["name"] for d in data["domains"]] == ["mechanisms"]
    comps = {c["name"]: c for c in data["domains"][0]["components"]}
    assert set(comps) == {"LeadScrew", "RackAndPinion", "WheelAndAxle"}
    lead = next(p for p in comps["LeadScrew"]["parameters"] if p["name"] == "lead")
    assert (lead["unit"], lead["default"]) == ("m", 5e-3)
    assert data["count"] == 3
    code, out, _ = run(capsys, "library", "--domain", "translational")
    assert "LeadScrew" not in out and "PreloadedSpring" in out


def test_cli_library_unknown_domain_is_a_usage_error(capsys):
    code, out, err = run(capsys, "library", "--domain", "nuclear")
    assert code == 2 and out == ""
    assert err.startswith("error: --domain nuclear")
    assert "rotational" in err and "mechanisms" in err and "electrical" in err


def test_docs_generator_writes_a_page_per_domain_with_every_component(tmp_path):
    written = catalog.write_docs(tmp_path)
    secs = catalog.sections()
    assert {p.name for p in written} == {f"{s.name}.md" for s in secs} | {"README.md"}
    for s in secs:
        page = (tmp_path / f"{s.name}.md").read_text()
        for c in s.components:
            assert f"### {c.name}" in page
            for p in c.parameters:
                assert f"`{p.name}`" in page
        if s.domain is not None:
            assert s.domain.across in page and s.domain.color in page
    rot_page = (tmp_path / "rotational.md").read_text()
    assert "through = torque tau" in rot_page         # the package docstring's sign rules
    index = (tmp_path / "README.md").read_text()
    assert all(f"({s.name}.md)" in index for s in secs)


def test_docs_generator_as_a_module(tmp_path):
    assert catalog.main(["--docs", str(tmp_path / "d")]) == 0
    assert (tmp_path / "d" / "mechanisms.md").exists()
