"""`compile_model` as a whole (mechatron.compiler.pipeline): what a compile leaves behind."""

import gc
from collections import Counter

import pytest

import mechatron as mt
from tests.compiler.test_flatten_templates import ladder, stop_and_springs
from tests.compiler.test_folding import deep_ladder, two_drives

MODELS = {
    "templates": lambda: ladder(20),               # classes used 20 times: templates
    "hybrid": stop_and_springs,                    # pre(), impacts, templates beside
    "subsystems": deep_ladder,                     # subsystem ports folded into nodes
    "subsystem_drives": two_drives,
    "database_bldc": lambda: mt.models.get("bldc_motor").build(),   # inverter, Hall
}


@pytest.mark.parametrize("name", list(MODELS))
def test_a_compile_leaves_no_reference_cycles(name):
    """What a compile makes and drops is freed by reference counts as it goes, not left
    to the cyclic garbage collector, which is paused while compiling. The template
    equations and the folding of subsystem ports once held themselves in cycles: at
    10^5 equations the collector's first pass after the compile took 1.5 s, and until
    then the compile's garbage held its memory."""
    build = MODELS[name]
    mt.compile_model(build())       # a first compile imports modules (their classes
    model = build()                 # are cycles of their own), this one is measured
    gc.collect()
    enabled = gc.isenabled()
    gc.disable()
    try:
        mt.compile_model(model)
        gc.set_debug(gc.DEBUG_SAVEALL)
        found = gc.collect()
        kinds = Counter(type(o).__name__ for o in gc.garbage)
    finally:
        gc.set_debug(0)
        gc.garbage.clear()
        if enabled:
            gc.enable()
    assert found == 0, f"{found} objects in cycles, e.g. {kinds.most_common(6)}"
