"""Every database entry: its default experiment meets its expected values, and its
variants agree within the entry's stated tolerance."""

import json

import numpy as np
import pytest

import mechatron as mt
from mechatron.cli import main
from mechatron.models.compare import compare_variants, relative

ENTRIES = mt.models.list()
NAMES = [e.name for e in ENTRIES]


def test_models_json_lists_every_entry(capsys):
    assert main(["models", "--json"]) == 0
    listed = json.loads(capsys.readouterr().out)
    names = [m["name"] for m in (listed["models"] if isinstance(listed, dict) else listed)]
    assert sorted(names) == sorted(NAMES)


@pytest.fixture(scope="module", params=NAMES)
def comparison(request):
    return compare_variants(mt.models.get(request.param))


def test_entry_is_documented(comparison):
    entry = comparison.entry
    assert entry.description and entry.tags
    for name, info in entry.parameters.items():
        assert info.unit and info.doc and info.source, f"{entry.name}.{name}"
    for variant in entry.variants:
        assert set(entry.output_paths(variant)) <= set(entry.output_units)


def test_default_experiment_meets_expected_values(comparison):
    entry = comparison.entry
    res = comparison.results[comparison.reference]
    assert entry.expected, f"{entry.name} has no expected values"
    for label, ref in entry.expected.items():
        got = res.final(entry.output_paths(comparison.reference)[label])
        assert relative(abs(got - ref), abs(ref)) <= entry.expected_tolerance, \
            f"{entry.name}.{label}: {got!r} vs expected {ref!r}"


def test_variants_agree(comparison):
    entry = comparison.entry
    for variant, per_label in comparison.deviations.items():
        assert not comparison.missing[variant], (entry.name, variant)
        for label, dev in per_label.items():
            assert dev["max_rel"] <= entry.variant_tolerance, \
                f"{entry.name}: {variant}.{label} deviates {dev['max_rel']:.2e}"
