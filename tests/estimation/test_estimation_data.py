"""Measured data: loading from CSV, Parquet and pandas; every bad-data error names the
file, the column and the row."""

import numpy as np
import pandas as pd
import pytest

import mechatron as mt
from mechatron.errors import DataError
from mechatron.estimation import EstimationProblem, Experiment, load_experiment


def frame(n=50, dt=1e-3):
    t = np.arange(n) * dt
    return pd.DataFrame({"t": t, "V": np.full(n, 2.0), "i [mA]": 1e3 * (1 - np.exp(-t / 0.01))})


def test_csv_parquet_and_pandas_load_the_same_data(tmp_path):
    df = frame()
    df.to_csv(tmp_path / "run.csv", index=False)
    df.to_parquet(tmp_path / "run.parquet", index=False)
    a = load_experiment(tmp_path / "run.csv", inputs=["V"], outputs=["i"])
    b = load_experiment(tmp_path / "run.parquet", inputs=["V"], outputs=["i"])
    c = Experiment.from_frame(df, inputs=["V"], outputs=["i"])
    for e in (a, b, c):
        np.testing.assert_array_equal(e.t, df["t"].to_numpy())
        np.testing.assert_array_equal(e.outputs["i"], df["i [mA]"].to_numpy())
        assert e.units["i"] == "mA"            # from the "name [unit]" header


def test_save_and_reload_round_trip(tmp_path):
    e = Experiment.from_frame(frame(), inputs=["V"], outputs=["i"], units={"V": "V"})
    path = e.save(tmp_path / "again.csv")
    back = load_experiment(path, inputs=["V"], outputs=["i"])
    np.testing.assert_allclose(back.outputs["i"], e.outputs["i"], rtol=1e-9)
    assert back.units == {"V": "V", "i": "mA"}


def test_nan_names_file_column_and_row(tmp_path):
    df = frame()
    df.loc[7, "V"] = np.nan
    df.to_csv(tmp_path / "bad.csv", index=False)
    with pytest.raises(DataError, match=r"bad\.csv: column 'V', row 9: value is nan"):
        load_experiment(tmp_path / "bad.csv", inputs=["V"], outputs=["i"])


def test_time_not_increasing_names_the_row(tmp_path):
    df = frame()
    df.loc[20, "t"] = df.loc[19, "t"]
    df.to_csv(tmp_path / "dup.csv", index=False)
    with pytest.raises(DataError, match=r"dup\.csv: column 't', row 22: time .* does not "
                                        r"increase"):
        load_experiment(tmp_path / "dup.csv", inputs=["V"], outputs=["i"])


def test_missing_column_lists_the_columns(tmp_path):
    frame().to_csv(tmp_path / "run.csv", index=False)
    with pytest.raises(DataError, match=r"run\.csv: no column 'w' \(for 'w'\); columns: "
                                        r"t, V, i \[mA\]"):
        load_experiment(tmp_path / "run.csv", inputs=["V"], outputs=["w"])


def test_text_in_a_numeric_column(tmp_path):
    (tmp_path / "txt.csv").write_text("t,V\n0,1\n0.1,oops\n")
    with pytest.raises(DataError, match=r"txt\.csv: column 'V', row 3: 'oops' is not a "
                                        "number"):
        load_experiment(tmp_path / "txt.csv", inputs=["V"])


def rc_model():
    return mt.models.get("dc_motor").build("ode")


def test_unit_mismatch_with_the_model_names_the_column(tmp_path):
    df = frame()
    df = df.rename(columns={"i [mA]": "i [rad/s]"})
    df.to_csv(tmp_path / "units.csv", index=False)
    e = load_experiment(tmp_path / "units.csv", inputs=["V"], outputs=["i"])
    with pytest.raises(DataError, match=r"units\.csv: column 'i': unit 'rad/s' does not "
                                        r"match the model's 'A'"):
        EstimationProblem(rc_model(), [e], ["R"], inputs={"V": "V"}, outputs={"i": "i"})


def test_milliamperes_are_converted_to_the_models_amperes(tmp_path):
    e = Experiment.from_frame(frame(), inputs=["V"], outputs=["i"])
    prob = EstimationProblem(rc_model(), [e], ["R"], inputs={"V": "V"}, outputs={"i": "i"},
                             jit=False)
    np.testing.assert_allclose(prob.bound[0]["Ym"][0], e.outputs["i"] / 1000)


def test_a_sample_rate_the_model_cannot_follow(tmp_path):
    t = np.arange(20) * 0.05                      # 20 Hz for a 50 us electrical mode
    df = pd.DataFrame({"t": t, "V": 1.0, "i": 0.0})
    df.to_csv(tmp_path / "slow.csv", index=False)
    e = load_experiment(tmp_path / "slow.csv", inputs=["V"], outputs=["i"])
    with pytest.raises(DataError, match=r"slow\.csv: column 't': sample interval 0\.05 s .* "
                                        r"cannot follow this sample rate"):
        EstimationProblem(rc_model(), [e], ["R"], inputs={"V": "V"}, outputs={"i": "i"},
                          step_ratio=1.0)


def test_several_problems_are_reported_at_once():
    with pytest.raises(DataError) as info:
        Experiment("x", t=[0, 1, 1], inputs={"V": [1, np.nan, 1]}, outputs={"i": [0, 0]})
    assert len(info.value.problems) == 3
