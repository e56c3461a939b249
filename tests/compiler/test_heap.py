"""The C heap kept while a compile runs (mechatron.compiler.heap): inside the block glibc
maps no block of its own and trims nothing, and Python's arenas handed back are listed
and given out again; afterwards what was freed goes back."""

import os
import subprocess
import sys

import numpy as np
import pytest

import mechatron as mt
from mechatron.compiler import heap, pipeline
from mechatron.errors import ModelError
from mechatron.library import electrical as el

lib = heap._glibc()
glibc_only = pytest.mark.skipif(lib is None, reason="glibc's malloc with its defaults only")
helper = heap._arena_helper()
arenas_only = pytest.mark.skipif(helper is None or not os.path.exists("/proc/self/statm"),
                                 reason="CPython, a C compiler and /proc only")

BIG = 96 << 20          # above glibc's largest dynamic mmap threshold (32 MiB)


def mapped() -> int:
    """Bytes glibc holds in mappings of their own (one per large block)."""
    return lib.mallinfo2().hblkhd


def free_in_heap() -> int:
    return lib.mallinfo2().fordblks


def resident() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


@glibc_only
def test_a_large_block_comes_from_the_heap_inside_and_is_handed_back_after():
    outside = np.ones(BIG // 8)
    assert mapped() >= BIG, "outside the block a large block is a mapping of its own"
    del outside
    with heap.kept_heap():
        before = mapped()
        inside = np.ones(BIG // 8)
        assert mapped() == before, "inside the block it comes from the heap"
        del inside
        assert free_in_heap() >= BIG, "and stays in the heap when freed"
        kept = resident()
    assert kept - resident() >= BIG // 2, "after the block the freed memory goes back"
    assert heap._depth == 0


@glibc_only
def test_nested_blocks_restore_only_when_the_last_one_ends():
    with heap.kept_heap():
        with heap.kept_heap():
            pass
        before = mapped()
        a = np.ones(BIG // 8)
        assert mapped() == before, "the outer block still keeps the heap"
        del a
    assert heap._depth == 0
    b = np.ones(BIG // 8)
    assert mapped() >= BIG
    del b


@glibc_only
def test_the_heap_is_left_alone_when_the_user_says_so(monkeypatch):
    monkeypatch.setattr(heap, "_libc", False)        # looked up again
    monkeypatch.setenv("MECHATRON_KEEP_HEAP", "0")
    assert heap._glibc() is None
    with heap.kept_heap():
        a = np.ones(BIG // 8)
        assert mapped() >= BIG, "nothing was changed"
        del a
    monkeypatch.setattr(heap, "_libc", False)
    monkeypatch.delenv("MECHATRON_KEEP_HEAP")
    monkeypatch.setenv("GLIBC_TUNABLES", "glibc.malloc.trim_threshold=1000000")
    assert heap._glibc() is None, "malloc tuned by the user: their choice stands"


def seen_by_compiles(monkeypatch, read) -> list:
    """What ``read()`` gives inside each compile from now on (a list filled as they run)."""
    seen = []
    compile_ = pipeline._compile

    def spy(*args, **kwargs):
        seen.append(read())
        return compile_(*args, **kwargs)

    monkeypatch.setattr(pipeline, "_compile", spy)
    return seen


@glibc_only
def test_compile_model_runs_inside_the_block(monkeypatch):
    depth = seen_by_compiles(monkeypatch, lambda: heap._depth)
    mt.compile_model(mt.models.get("dc_motor").build())
    assert depth == [1] and heap._depth == 0


@glibc_only
def test_a_compile_that_fails_leaves_malloc_as_a_finished_one():
    m = mt.System("loose")
    m.add("r", el.Resistor(R=1.0))              # its pins connected to nothing
    with pytest.raises(ModelError, match="is not connected"):
        mt.compile_model(m)
    assert heap._depth == 0
    a = np.ones(BIG // 8)
    assert mapped() >= BIG, "large blocks are mappings of their own again"
    del a


# -- Python's arenas -------------------------------------------------------------------
SMALL = 400_000     # objects: tuples and floats, some 40 MB of arenas


def counts() -> dict:
    return heap.arena_counts()


@arenas_only
def test_arenas_handed_back_in_the_block_are_given_out_again_and_all_handed_back_after():
    with heap.kept_heap(arenas=True):
        junk = [(k, float(k)) for k in range(SMALL)]
        del junk                        # every arena it filled is empty again
        listed, start = counts()["listed"], counts()
        assert listed >= 20, "the arenas emptied are listed, not handed back"
        held = resident()
        again = [(k, float(k)) for k in range(SMALL)]
        now = counts()
        assert now["reused"] - start["reused"] >= listed // 2, "and are given out again"
        assert resident() - held < (10 << 20), "no fresh memory for the same objects"
        assert sum(a for a, _ in again) == SMALL * (SMALL - 1) // 2
        assert all(b == float(a) for a, b in again), "objects in reused arenas intact"
        del again
        inside = resident()
    assert counts()["listed"] == 0
    assert inside - resident() >= (20 << 20), "after the block the arenas go back"


@arenas_only
def test_outside_a_block_arenas_go_back_at_once():
    junk = [(k, float(k)) for k in range(SMALL)]
    del junk
    assert counts()["listed"] == 0


TWICE = """
from mechatron.compiler import heap
first = heap._arena_helper()
heap._arenas = False                    # looked up and installed again
assert heap._arena_helper() is not None
with heap.kept_heap(arenas=True):
    junk = [(k, float(k)) for k in range(400_000)]
    del junk
    again = [(k, float(k)) for k in range(400_000)]
    assert len(again) == 400_000
print(heap.arena_counts()["listed"])
"""


@arenas_only
def test_the_allocator_installed_twice_stays_one():
    # installed again (as after a reload of the module), CPython's allocator stays
    # behind it, not the helper behind itself, which would call itself without end: run
    # apart, so that such a fault fails the test instead of hanging it
    proc = subprocess.run([sys.executable, "-c", TWICE], capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.split() == ["0"]


@arenas_only
def test_a_large_model_keeps_the_arenas_while_it_compiles_and_a_small_one_does_not(
        monkeypatch):
    keeping = seen_by_compiles(monkeypatch, lambda: heap._keeping)
    motor = mt.models.get("dc_motor").build()
    mt.compile_model(motor)
    monkeypatch.setattr(pipeline, "ARENAS_FROM", 10)
    mt.compile_model(motor)
    assert keeping == [False, True] and not heap._keeping and counts()["listed"] == 0


@arenas_only
def test_a_large_compile_that_fails_hands_the_arenas_back(monkeypatch):
    monkeypatch.setattr(pipeline, "ARENAS_FROM", 1)
    m = mt.System("loose")
    m.add("r", el.Resistor(R=1.0))              # its pins connected to nothing
    with pytest.raises(ModelError, match="is not connected"):
        mt.compile_model(m)
    assert not heap._keeping and counts()["listed"] == 0 and heap._depth == 0


def test_elements_are_counted_until_there_are_enough():
    m = mt.System("counted")
    gnd = m.add("gnd", el.ElectricalReference())          # one port
    for k in range(3):
        r = m.add(f"r{k}", el.Resistor(R=1.0))            # two pins each
        m.connect(r.p, gnd.port)
        m.connect(r.n, gnd.port)
    # 4 components, 7 ports
    assert pipeline._at_least(m, 11) and not pipeline._at_least(m, 12)


def test_no_compiler_leaves_the_arenas_to_python(monkeypatch):
    from mechatron.solvers import native
    monkeypatch.setattr(heap, "_arenas", False)
    monkeypatch.setattr(native, "compiler", lambda: None)
    assert heap._arena_helper() is None
    with heap.kept_heap(arenas=True):
        assert not heap._keeping
    monkeypatch.setattr(heap, "_arenas", False)
    monkeypatch.setenv("MECHATRON_KEEP_HEAP", "0")
    assert heap._arena_helper() is None, "nor when the user says so"
