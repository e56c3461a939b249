"""The registry of database entries: `get` imports the module of the entry it is asked
for, not the whole database."""

from tests.test_import import _run     # code run in a fresh interpreter, its JSON back


def test_the_index_names_the_module_that_registers_each_built_in_entry():
    found = _run("""
import importlib, json
from mechatron.models import registry
found = {}
for module in registry.BUILTIN_MODULES:
    before = set(registry._REGISTRY)
    importlib.import_module(f"mechatron.models.{module}")
    found.update((name, module) for name in set(registry._REGISTRY) - before)
print(json.dumps([found, registry._MODULE_OF]))
""")
    registered, index = found
    assert index == registered


def test_get_imports_that_entry_alone_and_list_every_one():
    out = _run("""
import json, sys
import mechatron as mt
entry = mt.models.get("msd_vertical")
alone = sorted(m for m in sys.modules if m.startswith("mechatron.models.")
               and m.rsplit(".", 1)[1] not in ("entry", "registry", "compare", "msd"))
names = [e.name for e in mt.models.list()]
again = mt.models.get("msd_vertical") is entry
try:
    mt.models.get("msd_vertikal")
except Exception as exc:
    message = str(exc)
print(json.dumps([entry.name, alone, len(names), again, message]))
""")
    name, alone, n_listed, again, message = out
    assert name == "msd_vertical" and alone == [] and again
    assert n_listed >= 29
    assert "no model 'msd_vertikal' in the database; did you mean msd_vertical" in message
