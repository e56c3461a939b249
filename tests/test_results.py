"""Tests of the simulation log, `mechatron.results`."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from mechatron.errors import DataError, MechatronError
from mechatron.results import SimResult, SolverStats, UnknownVariableError

NAMES = ["motor.inertia.w", "motor.inertia.phi", "motor.emf.tau", "r1.p.v", "r1.n.v",
         "r1.i", "ctrl.e"]
UNITS = ["rad/s", "rad", "N*m", "V", "V", "A", ""]


@pytest.fixture
def stats() -> SolverStats:
    return SolverStats("RK4", steps=100, rejected_steps=3, rhs_evals=400, jac_evals=7,
                       events={"motor.stop": 2}, wall_time=0.0125, compile_time=0.5)


@pytest.fixture
def res(stats: SolverStats) -> SimResult:
    # Awkward floats (not exactly representable in short decimal) and a repeated event time.
    rng = np.random.default_rng(42)
    t = np.concatenate([np.linspace(0.0, 0.3, 31), [0.3], np.linspace(0.31, 1.0, 70)])
    values = rng.standard_normal((len(NAMES), t.size)) * np.pi * 1e-3
    values[0] = 1.0 - np.exp(-t / 0.1)  # a first-order step response
    values[0, 32:] += 0.25              # the jump after the event at t = 0.3
    return SimResult(t, values, NAMES, UNITS, stats=stats, model_name="dc_motor",
                     descriptions={"motor.inertia.w": "Angular velocity"})


# ---------------------------------------------------------------------------- construction
def test_construction_and_basic_reading(res: SimResult):
    assert len(res) == 102
    assert res.t.shape == (102,)
    assert res.names == NAMES
    assert res.units == dict(zip(NAMES, UNITS))
    assert res.values.shape == (len(NAMES), 102)
    assert "r1.p.v" in res
    assert "r1.p" not in res
    assert 3 not in res
    assert res.model_name == "dc_motor"
    assert res.descriptions["motor.inertia.w"] == "Angular velocity"
    assert res.descriptions["r1.i"] == ""


def test_arrays_are_not_copied_and_read_only():
    t = np.linspace(0.0, 1.0, 5)
    values = np.arange(10.0).reshape(2, 5)
    res = SimResult(t, values, ["a.x", "a.y"], ["m", "m/s"])
    assert np.shares_memory(res.t, t)
    assert np.shares_memory(res["a.y"], values)
    with pytest.raises(ValueError, match="read-only"):
        res["a.x"][0] = 1.0
    assert values.flags.writeable  # the caller's array keeps its flags
    assert res.names is not res.names  # a copy each time: the log cannot be edited
    res.names.append("b")
    assert len(res.names) == 2


def test_empty_variable_set():
    res = SimResult([0.0, 1.0], np.empty((0, 2)), [], [])
    assert res.names == [] and len(res) == 2


@pytest.mark.parametrize(
    ("t", "values", "names", "units", "match"),
    [
        ([[0.0, 1.0]], [[1.0, 2.0]], ["a"], ["V"], "non-empty 1-D"),
        ([], np.empty((1, 0)), ["a"], ["V"], "non-empty 1-D"),
        ([0.0, 1.0], [[1.0, 2.0, 3.0]], ["a"], ["V"], r"shape \(n_vars, n_t\) = \(1, 2\)"),
        ([0.0, 1.0], [[1.0, 2.0]], ["a"], [], "1 names but 0 units"),
        ([0.0, np.nan], [[1.0, 2.0]], ["a"], ["V"], "1 non-finite"),
        ([0.0, 2.0, 1.0], [[1.0, 2.0, 3.0]], ["a"], ["V"], r"non-decreasing.*t\[1\] = 2.0"),
        ([0.0, 1.0], [[1.0, 2.0], [3.0, 4.0]], ["a", "a"], ["V", "V"], "repeated.*: a"),
    ],
)
def test_construction_errors(t, values, names, units, match):
    with pytest.raises(DataError, match=match):
        SimResult(t, values, names, units, model_name="m")


def test_description_of_unknown_variable_is_rejected():
    with pytest.raises(DataError, match="unknown variable.*: b"):
        SimResult([0.0], [[1.0]], ["a"], ["V"], descriptions={"b": "nope"})


def test_repr(res: SimResult):
    assert repr(res) == "<SimResult 'dc_motor': 7 variables, 102 time points, t = 0 .. 1 s>"


# -------------------------------------------------------------------------------- lookup
def test_lookup_returns_the_row(res: SimResult):
    w = res["motor.inertia.w"]
    assert w.shape == res.t.shape
    np.testing.assert_array_equal(w, res.values[0])
    assert res.final("motor.inertia.w") == pytest.approx(1.0 - np.exp(-10.0) + 0.25)
    assert isinstance(res.final("r1.i"), float)


def test_unknown_name_suggests_closest(res: SimResult):
    with pytest.raises(UnknownVariableError) as info:
        res["motor.inertia.ww"]
    err = info.value
    assert isinstance(err, KeyError) and isinstance(err, MechatronError)
    message = str(err)
    assert message.startswith("motor.inertia.ww: no such variable among the 7 variables")
    assert "'dc_motor'" in message
    assert "Closest: motor.inertia.w" in message
    assert err.path == "motor.inertia.ww"
    assert err.variables[0] == "motor.inertia.w"


def test_unknown_name_without_its_component_path_suggests_the_full_path(res: SimResult):
    with pytest.raises(KeyError, match=r"Closest: r1\.i\b"):
        res["i"]


def test_unknown_name_far_from_everything(res: SimResult):
    with pytest.raises(KeyError, match="No close match; SimResult.names lists them all"):
        res["zzzzzzzzzzzz"]


def test_component_name_is_explained(res: SimResult):
    with pytest.raises(KeyError, match=r"motor\.inertia: a component, not a variable; it has "
                                       r"2 logged variable\(s\).*select\('motor\.inertia'\)"):
        res["motor.inertia"]


def test_lookup_by_non_string_is_a_type_error(res: SimResult):
    with pytest.raises(TypeError, match="instance path"):
        res[0]


# ------------------------------------------------------------------------- interpolation
def test_at_matches_numpy_interp(res: SimResult):
    tq = np.linspace(0.0, 1.0, 57)
    expected = np.interp(tq, res.t, res["r1.p.v"])
    np.testing.assert_array_equal(res.at(tq, "r1.p.v"), expected)
    scalar = res.at(0.123, "r1.p.v")
    assert isinstance(scalar, float)
    assert scalar == np.interp(0.123, res.t, res["r1.p.v"])
    # At the event time the log holds the values before and after; `at` gives after.
    assert res.at(0.3, "motor.inertia.w") == res["motor.inertia.w"][31]


@pytest.mark.parametrize(("tq", "shown"), [(-0.1, "-0.1"), (1.5, "1.5"), ([0.5, 2.0], "2.0"),
                                          (np.nan, "nan")])
def test_at_does_not_extrapolate(res: SimResult, tq, shown):
    with pytest.raises(DataError, match=rf"r1\.i: cannot interpolate at t = {shown} s, "
                                        r"outside the logged range \[0, 1\] s"):
        res.at(tq, "r1.i")


# -------------------------------------------------------------------------------- select
def test_select_by_prefix_and_name(res: SimResult):
    sub = res.select("motor.inertia", "r1.i")
    assert sub.names == ["motor.inertia.w", "motor.inertia.phi", "r1.i"]
    assert sub.units == {"motor.inertia.w": "rad/s", "motor.inertia.phi": "rad", "r1.i": "A"}
    np.testing.assert_array_equal(sub["r1.i"], res["r1.i"])
    np.testing.assert_array_equal(sub.t, res.t)
    assert sub.model_name == "dc_motor"
    assert sub.stats == res.stats and sub.stats is not res.stats
    assert sub.descriptions["motor.inertia.w"] == "Angular velocity"


def test_select_keeps_argument_order_and_drops_repeats(res: SimResult):
    sub = res.select("r1", "r1.i", "motor.emf.tau", "r1.")
    assert sub.names == ["r1.p.v", "r1.n.v", "r1.i", "motor.emf.tau"]


def test_select_prefix_is_a_path_not_a_string_prefix(res: SimResult):
    # "motor.in" is not a component: no match on string prefix "motor.inertia".
    with pytest.raises(UnknownVariableError, match="motor.in: no such variable"):
        res.select("motor.in")


def test_select_needs_an_argument(res: SimResult):
    with pytest.raises(TypeError, match="at least one"):
        res.select()


# ------------------------------------------------------------------------------- exports
def test_to_pandas(res: SimResult):
    df = res.to_pandas()
    assert isinstance(df, pd.DataFrame)
    assert df.shape == (102, 7)
    assert df.index.name == "t"
    assert list(df.columns) == NAMES
    np.testing.assert_array_equal(df.index.to_numpy(), res.t)
    np.testing.assert_array_equal(df["r1.n.v"].to_numpy(), res["r1.n.v"])
    assert df.attrs["units"]["motor.emf.tau"] == "N*m"
    df.iloc[0, 0] = 99.0  # a copy: the log is untouched
    assert res["motor.inertia.w"][0] == 0.0


def test_csv_roundtrip_is_exact(res: SimResult, tmp_path):
    path = res.save(tmp_path / "run.csv")
    text = path.read_text().splitlines()
    assert text[0] == "t," + ",".join(NAMES)
    assert len(text) == 1 + len(res)
    back = SimResult.load(path)
    np.testing.assert_array_equal(back.t, res.t)
    np.testing.assert_array_equal(back.values, res.values)
    assert back.names == NAMES
    assert back.units == dict.fromkeys(NAMES, "")  # CSV stays plain: no units
    assert back.stats is None


def test_csv_roundtrip_of_special_values(tmp_path):
    values = [[np.inf, -np.inf, np.nan, -0.0, 5e-324, 1.7976931348623157e308]]
    res = SimResult(np.arange(6.0), values, ["a"], ["V"])
    back = SimResult.load(res.save(tmp_path / "special.csv"))
    np.testing.assert_array_equal(back["a"], res["a"])
    assert np.signbit(back["a"][3])


def test_parquet_roundtrip_is_exact_and_keeps_metadata(res: SimResult, tmp_path):
    back = SimResult.load(res.save(tmp_path / "run.parquet"))
    np.testing.assert_array_equal(back.t, res.t)
    np.testing.assert_array_equal(back.values, res.values)
    assert back.names == NAMES
    assert back.units == res.units
    assert back.model_name == "dc_motor"
    assert back.stats == res.stats
    assert back.descriptions == res.descriptions


def test_a_variable_named_t_survives_both_formats(tmp_path):
    res = SimResult([0.0, 1.0], [[3.0, 4.0]], ["t"], ["K"])
    for name in ("a.csv", "a.parquet"):
        back = SimResult.load(res.save(tmp_path / name))
        assert back.names == ["t"]
        np.testing.assert_array_equal(back["t"], [3.0, 4.0])


def test_parquet_suffix_is_case_insensitive(res: SimResult, tmp_path):
    back = SimResult.load(res.save(tmp_path / "RUN.PARQUET"))
    assert back.units == res.units


@pytest.mark.parametrize("name", ["run.txt", "run"])
def test_save_rejects_other_suffixes(res: SimResult, tmp_path, name):
    with pytest.raises(DataError, match=r"run.*allowed suffixes: \.csv, \.parquet") as info:
        res.save(tmp_path / name)
    assert info.value.path == str(tmp_path / name)
    assert not (tmp_path / name).exists()


def test_load_rejects_other_suffixes(tmp_path):
    with pytest.raises(DataError, match=r"cannot load a simlog from '\.json'; allowed"):
        SimResult.load(tmp_path / "run.json")


def test_load_csv_without_time_column(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("time,a\n0,1\n")
    with pytest.raises(DataError, match="first column must be 't'.*got 'time'"):
        SimResult.load(path)


def test_load_csv_with_text_in_the_data(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("t,a\n0,1\n1,oops\n")
    with pytest.raises(DataError, match="not a table of numbers"):
        SimResult.load(path)


def test_load_missing_file(tmp_path):
    for name in ("none.csv", "none.parquet"):
        with pytest.raises(FileNotFoundError):
            SimResult.load(tmp_path / name)


# ------------------------------------------------------------------------------- plotting
def test_plot_writes_png_and_groups_by_unit(res: SimResult, tmp_path):
    path = tmp_path / "plot.png"
    fig = res.plot("r1.p.v", "motor.inertia.w", "r1.n.v", path=path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert path.stat().st_size > 1000
    axes = fig.axes
    assert len(axes) == 2  # volts together, rad/s apart
    assert axes[0].get_ylabel() == "v [V]"          # the quantity the two share
    assert [line.get_label() for line in axes[0].get_lines()] == ["r1.p.v", "r1.n.v"]
    assert axes[1].get_ylabel() == "motor.inertia.w [rad/s]"
    assert axes[1].get_xlabel() == "t [s]"
    assert fig.get_suptitle() == "dc_motor"


def test_plot_component_prefix_and_dimensionless(res: SimResult):
    fig = res.plot("motor.inertia", "ctrl.e")
    assert [ax.get_ylabel() for ax in fig.axes] == [
        "motor.inertia.w [rad/s]", "motor.inertia.phi [rad]", "ctrl.e [1]"]


def test_some_plots_lack_quantity_names_and_units_result_plot(res: SimResult, tmp_path,
                                                              saved_figures):
    # several quantities in one unit: named after the unit's quantity
    from mechatron.results import axis_label
    res.plot("r1.p.v", "r1.n.v", "r1.i", "motor.inertia.w", "motor.inertia.phi",
             path=tmp_path / "a.png")
    assert saved_figures.problems() == []
    labels = [ax.get_ylabel() for ax in saved_figures[0].axes]
    assert "v [V]" in labels and "r1.i [A]" in labels
    assert axis_label("V", ["src.u", "r1.v"]) == "voltage [V]"
    assert axis_label("", ["a", "b"]) == "dimensionless [1]"


def test_plot_into_given_axes(res: SimResult):
    from matplotlib.figure import Figure

    fig = Figure()
    ax = fig.subplots()
    assert res.plot("r1.p.v", "r1.n.v", ax=ax) is fig
    assert len(ax.get_lines()) == 2
    with pytest.raises(DataError, match=r"2 unit group\(s\) \(\[V\], \[A\]\).*1 axes given"):
        res.plot("r1.p.v", "r1.i", ax=ax)


def test_plot_needs_a_name(res: SimResult):
    with pytest.raises(TypeError, match=r"at least one variable.*plot\('motor.inertia.w'\)"):
        res.plot()


def test_plot_unknown_name(res: SimResult):
    with pytest.raises(UnknownVariableError, match="Closest: r1.p.v"):
        res.plot("r1.p.vv")


# ---------------------------------------------------------------------------------- stats
def test_stats_as_dict(stats: SolverStats):
    d = stats.as_dict()
    assert d == {"solver": "RK4", "steps": 100, "rejected_steps": 3, "rhs_evals": 400,
                 "jac_evals": 7, "events": {"motor.stop": 2}, "wall_time": 0.0125,
                 "compile_time": 0.5, "solver_reason": "", "unconverged_steps": 0}
    d["events"]["motor.stop"] = 99
    assert stats.events == {"motor.stop": 2}
    assert SolverStats.from_dict(stats.as_dict()) == stats


def test_stats_read_by_name(stats: SolverStats):
    assert stats["solver"] == "RK4" and stats["steps"] == 100
    assert stats["unconverged_steps"] == 0
    with pytest.raises(KeyError):
        stats["bogus"]


def test_stats_defaults():
    s = SolverStats("BDF")
    assert (s.steps, s.rejected_steps, s.rhs_evals, s.jac_evals) == (0, 0, 0, 0)
    assert s.events == {} and s.events is not SolverStats("BDF").events
    assert s.compile_time is None


def test_stats_from_dict_rejects_unknown_keys():
    with pytest.raises(TypeError, match="bogus"):
        SolverStats.from_dict({"solver": "RK4", "bogus": 1})
