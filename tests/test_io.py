"""Tests of all-or-nothing writing, `mechatron._io`, and of the writers that use it: an
interrupted write (an exception, Ctrl-C, a full disk) leaves the previous file and no
temporary file behind."""

from __future__ import annotations

import errno
import os
import stat

import numpy as np
import pytest

import mechatron as mt
from mechatron import _io
from mechatron._io import atomic_dir, atomic_path, save_figure, write_text
from mechatron.results import SimResult


def _listing(folder) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def _log(scale: float = 1.0) -> SimResult:
    t = np.linspace(0.0, 1.0, 201)
    values = np.vstack([scale * np.sin(2 * np.pi * t), scale * t ** 2])
    return SimResult(t, values, ["a.x", "a.y"], ["m", "m/s"], model_name="toy")


def _full_disk(*args, **kwargs):
    raise OSError(errno.ENOSPC, "No space left on device")


# ------------------------------------------------------------------------------ helper
@pytest.mark.parametrize("interrupt", [RuntimeError("writer failed"), KeyboardInterrupt(),
                                       OSError(errno.ENOSPC, "No space left on device")])
def test_an_interrupted_write_keeps_the_old_file_and_leaves_nothing(tmp_path, interrupt):
    target = tmp_path / "result.txt"
    target.write_text("previous result\n")
    with pytest.raises(type(interrupt)):
        with atomic_path(target) as tmp:
            assert tmp.parent == tmp_path and tmp.suffix == ".txt"
            tmp.write_text("half of the new")
            raise interrupt
    assert target.read_text() == "previous result\n"
    assert _listing(tmp_path) == ["result.txt"]


def test_a_complete_write_replaces_the_file_and_keeps_its_permissions(tmp_path):
    target = tmp_path / "result.txt"
    target.write_text("old")
    os.chmod(target, 0o640)
    assert write_text(target, "new ü") == target
    assert target.read_text(encoding="utf-8") == "new ü"
    assert stat.S_IMODE(os.stat(target).st_mode) == 0o640
    assert _listing(tmp_path) == ["result.txt"]


def test_a_new_file_gets_the_permissions_of_the_umask(tmp_path):
    umask = os.umask(0o027)
    try:
        _io._umask.cache_clear()
        write_text(tmp_path / "new.txt", "x")
    finally:
        os.umask(umask)
        _io._umask.cache_clear()
    assert stat.S_IMODE(os.stat(tmp_path / "new.txt").st_mode) == 0o640


def test_a_relative_path_is_written_in_the_current_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    write_text("plain.txt", "x")
    assert _listing(tmp_path) == ["plain.txt"]


def test_a_folder_is_replaced_whole_or_not_at_all(tmp_path):
    out = tmp_path / "gen"
    out.mkdir()
    (out / "old.c").write_text("old")
    with pytest.raises(KeyboardInterrupt):
        with atomic_dir(out) as tmp:
            (tmp / "new.c").write_text("new")
            raise KeyboardInterrupt
    assert _listing(out) == ["old.c"] and _listing(tmp_path) == ["gen"]
    with atomic_dir(out) as tmp:
        (tmp / "new.c").write_text("new")
    assert _listing(out) == ["new.c"] and _listing(tmp_path) == ["gen"]
    assert stat.S_IMODE(os.stat(out).st_mode) & 0o700 == 0o700


# ----------------------------------------------------------------------- the writers
@pytest.mark.parametrize("suffix", [".csv", ".parquet"])
def test_simlog_save_interrupted_keeps_the_previous_log(tmp_path, monkeypatch, suffix):
    path = tmp_path / f"run{suffix}"
    _log(1.0).save(path)
    if suffix == ".csv":
        monkeypatch.setattr(np, "savetxt", _full_disk)
    else:
        import pyarrow.parquet as pq
        monkeypatch.setattr(pq, "write_table", _full_disk)
    with pytest.raises(OSError, match="No space"):
        _log(2.0).save(path)
    monkeypatch.undo()
    back = SimResult.load(path)
    np.testing.assert_array_equal(back["a.x"], _log(1.0)["a.x"])   # the old values
    assert _listing(tmp_path) == [path.name]
    _log(2.0).save(path)
    np.testing.assert_array_equal(SimResult.load(path)["a.x"], _log(2.0)["a.x"])


def test_plot_interrupted_keeps_the_previous_figure(tmp_path, monkeypatch):
    from matplotlib.figure import Figure
    path = tmp_path / "plot.png"
    _log().plot("a.x", path=path)
    before = path.read_bytes()
    assert before.startswith(b"\x89PNG")

    def broken(self, fname, **kw):
        with open(fname, "wb") as fh:
            fh.write(b"\x89PNG half")
        raise KeyboardInterrupt
    monkeypatch.setattr(Figure, "savefig", broken)
    with pytest.raises(KeyboardInterrupt):
        _log().plot("a.y", path=path)
    assert path.read_bytes() == before and _listing(tmp_path) == ["plot.png"]
    monkeypatch.undo()
    fig = Figure()
    fig.subplots().plot([0, 1], [1, 0])
    save_figure(fig, tmp_path / "plot.svg")
    assert (tmp_path / "plot.svg").read_text().lstrip().startswith("<?xml")


def test_estimation_data_save_is_all_or_nothing(tmp_path, monkeypatch):
    import pandas as pd
    from mechatron.estimation.data import Experiment
    t = np.linspace(0.0, 1.0, 11)
    exp = Experiment(t=t, inputs={"u": np.ones_like(t)}, outputs={"y": t.copy()},
                     units={"u": "V", "y": "A"}, name="step")
    path = exp.save(tmp_path / "step.csv")
    before = path.read_text()
    monkeypatch.setattr(pd.DataFrame, "to_csv", _full_disk)
    with pytest.raises(OSError):
        exp.save(path)
    assert path.read_text() == before and _listing(tmp_path) == ["step.csv"]


def test_compiled_model_save_is_all_or_nothing(tmp_path, monkeypatch):
    """An interrupted save keeps the model saved before; a damaged file is a DataError
    that names it, not a raw unpickling error."""
    import pickle
    from mechatron.errors import DataError
    cm = mt.compile_model(_rc())
    path = cm.save(tmp_path / "rc.mtm")
    before = path.read_bytes()

    def half_written(obj, fh, protocol=None):
        fh.write(before[:len(before) // 2])
        raise KeyboardInterrupt
    monkeypatch.setattr(pickle, "dump", half_written)
    with pytest.raises(KeyboardInterrupt):
        cm.save(path)
    monkeypatch.undo()
    assert path.read_bytes() == before and _listing(tmp_path) == ["rc.mtm"]
    back = mt.CompiledModel.load(path)
    assert back.names == cm.names and back.state_names == cm.state_names
    damaged = tmp_path / "half.mtm"
    damaged.write_bytes(before[:len(before) // 2])
    with pytest.raises(DataError, match="half.mtm: not a readable saved CompiledModel"):
        mt.CompiledModel.load(damaged)


def _rc():
    from mechatron.library import electrical as el
    m = mt.System("rc")
    src = m.add("src", el.DCVoltageSource(V=1.0))
    r = m.add("r", el.Resistor(R=1e3))
    c = m.add("c", el.Capacitor(C=1e-6))
    g = m.add("g", el.ElectricalReference())
    m.connect(src.p, r.p)
    m.connect(r.n, c.p)
    m.connect(src.n, c.n, g.port)
    return m


def test_generated_c_interrupted_leaves_no_folder(tmp_path, monkeypatch):
    from mechatron.codegen.c import generator
    calls = []
    real = generator.render

    def render(template, **values):
        calls.append(template)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(template, **values)
    monkeypatch.setattr(generator, "render", render)
    with pytest.raises(KeyboardInterrupt):
        generator.generate_c(_rc(), tmp_path / "rc_c", solver="rk4", dt=1e-5, name="rc")
    assert _listing(tmp_path) == []
    monkeypatch.undo()
    code = generator.generate_c(_rc(), tmp_path / "rc_c", solver="rk4", dt=1e-5, name="rc")
    assert _listing(tmp_path) == ["rc_c"]
    assert sorted(p.name for p in code.files.values()) == _listing(tmp_path / "rc_c")
    assert all(p.parent == tmp_path / "rc_c" for p in code.files.values())


def test_fmu_export_that_fails_keeps_the_previous_fmu(tmp_path, monkeypatch):
    import shutil
    if shutil.which("cc") is None and shutil.which("gcc") is None:
        pytest.skip("no C compiler")
    from mechatron.codegen.fmu import export
    path = tmp_path / "rc.fmu"
    path.write_bytes(b"previous FMU")

    def compile_fails(src, sources, library):
        raise export.CodegenError("compiling the FMU binary failed: disk full")
    monkeypatch.setattr(export, "_compile", compile_fails)
    with pytest.raises(export.CodegenError):
        export.export_fmu(_rc(), path, dt=1e-5, name="rc")
    assert path.read_bytes() == b"previous FMU" and _listing(tmp_path) == ["rc.fmu"]


def test_diagram_interrupted_keeps_the_previous_file(tmp_path, monkeypatch):
    from mechatron.report import diagram
    path = tmp_path / "rc.svg"
    path.write_text("<svg>previous</svg>")

    def dot_interrupted(cmd, **kwargs):       # Graphviz writes half a file, then Ctrl-C
        with open(cmd[cmd.index("-o") + 1], "w") as fh:
            fh.write("<svg>half")
        raise KeyboardInterrupt
    monkeypatch.setattr(diagram.shutil, "which", lambda name: "/usr/bin/dot")
    monkeypatch.setattr(diagram.subprocess, "run", dot_interrupted)
    with pytest.raises(KeyboardInterrupt):
        diagram.write_diagram(_rc(), path)
    assert path.read_text() == "<svg>previous</svg>" and _listing(tmp_path) == ["rc.svg"]


def test_a_folder_that_cannot_be_written_is_named_not_the_temporary_file(tmp_path):
    missing = tmp_path / "no" / "such" / "folder"
    with pytest.raises(FileNotFoundError) as info:
        write_text(missing / "x.txt", "x")
    assert info.value.filename == str(missing / "x.txt")
    with pytest.raises(FileNotFoundError) as info:
        with atomic_dir(missing / "gen"):
            pass
    assert info.value.filename == str(missing / "gen")
    # a full disk while writing: the error names the destination too
    with pytest.raises(OSError) as info:
        with atomic_path(tmp_path / "big.bin"):
            raise OSError(errno.ENOSPC, "No space left on device", "/tmp/whatever")
    assert info.value.errno == errno.ENOSPC and info.value.filename == str(tmp_path / "big.bin")
    assert _listing(tmp_path) == []


def test_leftovers_of_a_killed_writer_are_removed_when_old(tmp_path):
    import time
    stale = tmp_path / f"{_io.TEMP_PREFIX}result-abc123.txt"
    fresh = tmp_path / f"{_io.TEMP_PREFIX}result-def456.txt"
    other = tmp_path / f"{_io.TEMP_PREFIX}other-abc123.txt"
    stale_dir = tmp_path / f"{_io.TEMP_PREFIX}gen-xyz"
    for p in (stale, fresh, other):
        p.write_text("half")
    (stale_dir / "sub").mkdir(parents=True)
    old = time.time() - 2 * _io.STALE_AFTER
    for p in (stale, other, stale_dir):
        os.utime(p, (old, old))
    write_text(tmp_path / "result.txt", "new")
    # the old leftover of this name goes; a young one (a writer at work?) and the
    # leftovers of other names stay
    assert _listing(tmp_path) == sorted([fresh.name, other.name, stale_dir.name,
                                         "result.txt"])
    with atomic_dir(tmp_path / "gen") as tmp:
        (tmp / "a.c").write_text("")
    assert stale_dir.name not in _listing(tmp_path)
