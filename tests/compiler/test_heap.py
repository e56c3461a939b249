"""The C heap kept while a compile runs (mechatron.compiler.heap): inside the block glibc
maps no block of its own and trims nothing; afterwards what was freed goes back."""

import numpy as np
import pytest

import mechatron as mt
from mechatron.compiler import heap, pipeline
from mechatron.errors import ModelError
from mechatron.library import electrical as el

lib = heap._glibc()
pytestmark = pytest.mark.skipif(lib is None, reason="glibc's malloc with its defaults only")

BIG = 96 << 20          # above glibc's largest dynamic mmap threshold (32 MiB)


def mapped() -> int:
    """Bytes glibc holds in mappings of their own (one per large block)."""
    return lib.mallinfo2().hblkhd


def free_in_heap() -> int:
    return lib.mallinfo2().fordblks


def resident() -> int:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096


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


def test_compile_model_runs_inside_the_block(monkeypatch):
    depth = []
    compile_ = pipeline._compile

    def spy(*args, **kwargs):
        depth.append(heap._depth)
        return compile_(*args, **kwargs)

    monkeypatch.setattr(pipeline, "_compile", spy)
    mt.compile_model(mt.models.get("dc_motor").build())
    assert depth == [1] and heap._depth == 0


def test_a_compile_that_fails_leaves_malloc_as_a_finished_one():
    m = mt.System("loose")
    m.add("r", el.Resistor(R=1.0))              # its pins connected to nothing
    with pytest.raises(ModelError, match="is not connected"):
        mt.compile_model(m)
    assert heap._depth == 0
    a = np.ones(BIG // 8)
    assert mapped() >= BIG, "large blocks are mappings of their own again"
    del a
