"""``genthermal estimate`` and ``genthermal compare-models`` end to end on synthetic rig data."""

import json

import numpy as np
import pandas as pd
import pytest

from genthermal.cli import main
from genthermal.estimation.comparison import MODEL_LABELS, compare_design_models
from genthermal.measurements import load_measurements

PLANT = ["--param", "h_end_air=13.175", "--param", "h_top_air=17.05", "--param", "R0=1.26", "--param", "P_iron=48"]


@pytest.fixture(scope="module")
def records(tmp_path_factory):
    """Validation record (thesis Fig. 7.7 mission) and training record (Fig. 3.2) of a mismatched plant."""
    folder = tmp_path_factory.mktemp("rig")
    validation, train = folder / "val.csv", folder / "train.csv"
    assert main(["synth", "thesis_fig_7_7", "--out", str(validation), "--seed", "5", *PLANT]) == 0
    assert main(["synth", "thesis_fig_3_2", "--out", str(train), "--seed", "6", *PLANT]) == 0
    return train, validation


def test_estimate_writes_the_study(records, tmp_path, capsys):
    _, validation = records
    out, plot = tmp_path / "est.json", tmp_path / "est.png"
    assert main(["estimate", str(validation), "--json", str(out), "--plot", str(plot)]) == 0
    report = json.loads(out.read_text())
    assert report["filter"] == "ekf" and list(report["improved_minutes"]) == ["50", "75", "100", "125", "150", "175"]
    for key in ("filter_rmse", "one_step_rmse", "open_loop_rmse", *(report["improved_minutes"].values())):
        section = report[key] if isinstance(key, str) else key
        assert set(section) == {"T_winding", "T_iron"}
    assert max(report["filter_rmse"].values()) < 1.0 < min(report["open_loop_rmse"].values())
    assert min(v for start in report["improved_minutes"].values() for v in start.values()) >= 20.0
    # error by horizon: a start every 10 min while 60 min fit in the 4 h record
    assert report["horizon_starts"] == 18 and "filter_rmse" in report["definition"]
    for key in ("prediction_rmse_by_horizon", "prediction_max_by_horizon", "open_loop_rmse_by_horizon"):
        assert list(report[key]) == ["15", "30", "60"]
        assert all(set(row) == {"T_winding", "T_iron"} for row in report[key].values())
    rmse, peak = report["prediction_rmse_by_horizon"], report["prediction_max_by_horizon"]
    open_loop = report["open_loop_rmse_by_horizon"]
    for horizon in rmse:
        for sensor in rmse[horizon]:
            assert rmse[horizon][sensor] <= peak[horizon][sensor]
            # the plant is not the model: predictions from the filtered state beat the open loop
            assert rmse[horizon][sensor] < 0.5 * open_loop[horizon][sensor]
    for picture in (plot, tmp_path / "est_filter.png", tmp_path / "est_horizons.png"):
        assert picture.stat().st_size > 10_000
    text = capsys.readouterr().out
    assert "period of increased accuracy" in text and "rotor" in text


def test_estimate_counts_missing_samples(records, tmp_path, capsys):
    _, validation = records
    frame = pd.read_csv(validation)
    frame.loc[100:130, ["T_winding_u", "T_winding_v", "T_winding_w", "T_iron"]] = np.nan
    gappy, out = tmp_path / "gappy.csv", tmp_path / "gappy.json"
    frame.to_csv(gappy, index=False)
    assert main(["estimate", str(gappy), "--json", str(out), "--predict-from", "60,90", "--steady-state",
                 "--filter", "kf"]) == 0
    report = json.loads(out.read_text())
    assert report["samples_without_measurement"] == 31  # data already on the grid: not resampled
    assert list(report["improved_minutes"]) == ["60", "90"] and report["steady_state_gain"] is True
    assert report["filter"] == "kf"


def test_linear_filter_is_the_weaker_baseline(records, tmp_path):
    _, validation = records
    reports = {}
    for kind in ("ekf", "kf"):
        assert main(["estimate", str(validation), "--json", str(tmp_path / f"{kind}.json"), "--filter", kind]) == 0
        reports[kind] = json.loads((tmp_path / f"{kind}.json").read_text())["prediction_rmse_by_horizon"]
    for horizon in ("15", "30", "60"):
        assert reports["ekf"][horizon]["T_winding"] < reports["kf"][horizon]["T_winding"]


BAD = [
    (["--predict-from", "-5"], "--predict-from"),
    (["--predict-from", "50,abc"], "--predict-from"),
    (["--predict-from", "500"], "--predict-from"),
    (["--dt", "0"], "--dt"),
    (["--min-improvement", "-1"], "--min-improvement"),
    (["--dt", "600"], "--dt"),  # the nonlinear model cannot be discretised accurately at 10 min
    (["--every", "0"], "--every"),
    (["--filter", "ukf"], "--filter"),
    (["--steady-state"], "--steady-state"),
    (["--model", "no_such_machine"], "--model"),
]


@pytest.mark.parametrize("extra, named", BAD, ids=[" ".join(e) for e, _ in BAD])
def test_bad_estimate_arguments_exit_2_naming_the_option(records, extra, named, tmp_path, capsys):
    _, validation = records
    assert main(["estimate", str(validation), "--json", str(tmp_path / "x.json"), *extra]) == 2
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err
    assert not (tmp_path / "x.json").exists()


def test_estimate_refuses_a_record_shorter_than_the_longest_horizon(records, tmp_path, capsys):
    _, validation = records
    short = tmp_path / "short.csv"
    pd.read_csv(validation).iloc[:360].to_csv(short, index=False)  # 60 min: no start leaves room for 60 min
    assert main(["estimate", str(short), "--json", str(tmp_path / "x.json"), "--predict-from", "20"]) == 2
    err = capsys.readouterr().err
    assert "data" in err and "longest horizon" in err


def test_compare_models_table(records, tmp_path, capsys):
    train, validation = records
    out = tmp_path / "compare.json"
    assert main(["compare-models", str(train), str(validation), "--json", str(out)]) == 0
    rows = json.loads(out.read_text())["models"]
    assert [(r["model"], r["sensor"]) for r in rows] == [(m, s) for m in MODEL_LABELS for s in ("T_winding", "T_iron")]
    for row in rows:
        assert row["R2"] > 0.5 and 0 < row["rmse_K"] <= row["max_abs_error_K"] < 15
    assert "linear physics" in capsys.readouterr().out


def test_compare_with_the_true_plant_and_a_fixed_arx_structure(records, plant_model):
    train, validation = records
    values = dict(h_end_air=13.175, h_top_air=17.05, R0=1.26, P_iron=48.0)
    plant = plant_model.with_parameters(provenance="assumed", source="the synthetic plant", **values)
    table = compare_design_models(load_measurements(train), load_measurements(validation), plant=plant,
                                  inputs=("I_sq",), na_range=(1,), nb_range=(2,), nk_range=(0,))
    nonlinear = table[table["model"] == "nonlinear physics"].set_index("sensor")
    assert (nonlinear["rmse_K"] < 0.2).all()  # the plant itself: only sensor and current noise remain
    arx = table[table["model"] == "ARX"]
    assert list(arx["detail"]) == ["input I_sq, na=1 nb=2 nk=0"] * 2 and list(arx["order"]) == [1, 1]
