"""Model against measurement: metrics, where-it-fails splits, reports, model files."""

import json

import numpy as np
import pytest
import yaml

from genthermal.cli import main
from genthermal.diagnose.compare import compare, error_metrics, measured_series
from genthermal.diagnose.hidden import make_hidden_effect_case
from genthermal.diagnose.report import write_compare_report
from genthermal.errors import InputError
from genthermal.model_file import load_model, save_model


@pytest.fixture(scope="module")
def healthy(plant_model):
    return make_hidden_effect_case(None, mission="thesis_fig_7_7", dt_s=60.0, seed=2, plant=plant_model)


def test_error_metrics_by_hand():
    m = error_metrics([1.0, 2.0, 4.0], [1.0, 1.0, 1.0 + np.nan])
    assert m["n"] == 2 and m["rmse"] == pytest.approx(np.sqrt(0.5)) and m["bias"] == pytest.approx(0.5)
    assert m["max_abs"] == 1.0 and m["r2"] is None  # no spread in the measurement


def test_the_true_model_explains_its_data_to_noise_level(plant_model, healthy):
    comparison = compare(plant_model, healthy.data)
    metrics = comparison.metrics
    assert comparison.rmse() < 1.5 * healthy.noise_std * 1.5  # sensor noise + 1 % current noise
    for name in ("T_winding", "T_iron"):
        assert abs(metrics["overall"][name]["bias"]) < 0.05 and metrics["overall"][name]["r2"] > 0.999
        assert abs(metrics["trend_K_per_h"][name]) < 0.05
    assert metrics["initial_state"]["a"] == pytest.approx(0.0, abs=0.05)  # a cold start
    assert set(metrics["by_heating"]) <= {"heating", "cooling", "steady"}
    assert sum(v["T_iron"]["n"] for v in metrics["by_hour"].values()) == metrics["overall"]["T_iron"]["n"]


def test_a_wrong_model_shows_where_it_fails(plant_model, healthy, tmp_path):
    hotter = plant_model.with_parameters(provenance="assumed", R0=1.4)  # 17 % more copper loss
    comparison = compare(hotter, healthy.data)
    bands = comparison.metrics["by_load_band"]
    high = next(v for k, v in bands.items() if k.startswith("high"))
    assert comparison.metrics["overall"]["T_winding"]["bias"] > 1.0 and high["T_winding"]["bias"] > 1.0
    report = write_compare_report(comparison, tmp_path)
    assert "Where it fails" in report.read_text()
    for name in ("metrics.json", "model_vs_measurement.png", "residual_vs_time.png", "residual_vs_regressors.png"):
        assert (tmp_path / name).is_file()


def test_irregular_and_gappy_data_are_resampled(plant_model, healthy):
    frame = healthy.data.drop(index=[5, 6, 7]).reset_index(drop=True)
    frame.loc[20, "T_iron"] = np.nan
    series = measured_series(frame)
    assert series.dt_s == 60.0 and np.isnan(series.outputs).sum() >= 1
    assert compare(plant_model, frame).rmse() < 0.3


def test_model_file_round_trip(plant_model, tmp_path):
    model = plant_model.with_parameters(provenance="fitted", source="a test", h_end_air=17.5)
    model = model.with_effect("coolant_flow_reduction", k_flow=0.6)
    path = save_model(model, tmp_path / "model.yaml", {"coolant_flow_reduction": 3600.0})
    document = yaml.safe_load(path.read_text())
    assert list(document["parameters"]) == ["h_end_air"] and document["effects"][0]["onset_s"] == 3600.0
    loaded = load_model(path)
    assert loaded.parameters.value("h_end_air") == 17.5 and loaded.parameters["h_end_air"].provenance == "fitted"
    assert loaded.spec.effects == ("coolant_flow_reduction",) and loaded.parameters.value("k_flow") == 0.6
    assert load_model("genco_rf201a:linear").spec.variant == "linear"


@pytest.mark.parametrize("text, field", [
    ("machine: genco_rf201a\nparameters: {h_end_air: {value: abc}}", "parameters.h_end_air.value"),
    ("machine: genco_rf201a\nparameters: {h_nope: {value: 3}}", "parameters.h_nope"),
    ("machine: genco_rf201a\neffects: [{name: no_such_effect}]", "effects[0].name"),
    ("machine: genco_rf201a\neffects: [{name: coolant_flow_reduction, parameters: {k_flow: 9}}]", "effects[0]"),
    ("machine: genco_rf201a\nvariant: quadratic", "variant"),
    ("machine: genco_rf201a\nsize: 3", "size"),
    ("variant: linear", "machine"),
])
def test_bad_model_files_name_the_field(text, field, tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(InputError) as error:
        load_model(path)
    assert error.value.field.startswith(field)


def test_cli_compare_writes_report_and_json(healthy, tmp_path, capsys):
    healthy.data.to_csv(tmp_path / "data.csv", index=False)
    assert main(["compare", str(tmp_path / "data.csv"), "--report", str(tmp_path / "r"),
                 "--json", str(tmp_path / "m.json")]) == 0
    assert "T_winding: RMSE" in capsys.readouterr().out
    assert json.loads((tmp_path / "m.json").read_text())["overall"]["T_iron"]["n"] == len(healthy.data)
    assert (tmp_path / "r" / "report.md").is_file()
