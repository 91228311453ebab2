"""Diagnosis and CalibrationResult as tables (``to_pandas``) and figures (``plot``), matching ``to_dict``."""

import math

import numpy as np
import pandas as pd
import pytest

from genthermal.diagnose import calibrate, diagnose
from genthermal.diagnose.hidden import Injection, make_hidden_effect_case
from genthermal.diagnose.result_views import CLAIM_COLUMNS, PARAMETER_COLUMNS
from genthermal.errors import InputError
from genthermal.sensor_faults import SENSOR_FAULT_BOUNDS, STUCK_RANGE_C, SensorFault, fault_bounds


def is_png(path) -> bool:
    return path.is_file() and path.stat().st_size > 1000 and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def blocked_case():
    """A coolant blockage from 1.5 h on the thesis Fig. 7.7 mission, read through the rig's sensors."""
    return make_hidden_effect_case([Injection("coolant_flow_reduction", {"k_flow": 0.6}, 1.5 * 3600.0)],
                                   mission="thesis_fig_7_7", dt_s=60.0, seed=3)


@pytest.fixture(scope="module")
def diagnosis(plant_model, blocked_case):
    return diagnose(plant_model, blocked_case.data, effects=["coolant_flow_reduction", "end_winding_stray_loss"],
                    pairs=False, design_experiment=False, sensor_faults=False)


@pytest.fixture(scope="module")
def calibration(plant_model):
    machine = plant_model.with_parameters(provenance="assumed", R0=1.1, h_end_air=18.0)
    case = make_hidden_effect_case(None, mission="varying_load", dt_s=60.0, seed=4, plant=machine)
    return calibrate(plant_model, case.data, ["R0", "h_end_air"])


def test_the_diagnosis_table_holds_every_claim_with_its_size_and_bound(diagnosis):
    document = diagnosis.to_dict()
    frame = diagnosis.to_pandas()
    assert diagnosis.verdict == "coolant_flow_reduction"
    assert list(frame.columns) == list(CLAIM_COLUMNS)
    machine = [c for c in document["claims"] if c["kind"] == "machine_effect"]
    rows = frame[frame["kind"] == "machine_effect"]
    assert len(rows) == sum(len(c["params"]) for c in machine) >= 1
    for _, row in rows.iterrows():
        claim = document["claims"][row["claim"]]
        assert row["subject"] == claim["effect"]
        assert row["size"] == pytest.approx(claim["params"][row["quantity"]])
        assert row["onset_s"] == pytest.approx(claim["onset_s"])
        assert (row["evidence"], row["confidence"]) == (claim["evidence"], claim["confidence"])
        assert row["delta_ic"] == pytest.approx(claim["delta_ic"])
        assert row["bound_low"] <= row["size"] <= row["bound_high"]  # a claimed effect is plausible
    flow = rows[rows["quantity"] == "k_flow"].iloc[0]
    assert flow["size"] == pytest.approx(0.6, abs=0.1) and abs(flow["onset_s"] - 1.5 * 3600.0) < 600.0
    assert set(frame["claim"]) == set(range(len(document["claims"])))


def test_the_diagnosis_figure_is_a_png_with_one_panel_per_sensor(diagnosis, tmp_path):
    figure = diagnosis.plot(tmp_path / "figures" / "residual.png")
    assert is_png(tmp_path / "figures" / "residual.png")
    assert len(figure.axes) == len(diagnosis.output_names)
    # the residual after the found effect is smaller than before on every sensor, as drawn
    for axes in figure.axes:
        before, after = (np.sqrt(np.nanmean(line.get_ydata() ** 2)) for line in axes.lines[:2])
        assert after < before


def test_the_diagnosis_draws_into_the_users_axes(diagnosis):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    assert diagnosis.plot(ax=ax) is fig
    assert len(ax.lines) == 3 * len(diagnosis.output_names)  # before, after and zero per sensor
    with pytest.raises(InputError, match="ax"):
        diagnosis.plot(ax=[ax])


def test_the_calibration_table_matches_its_json(calibration):
    document = calibration.to_dict()
    frame = calibration.to_pandas()
    assert list(frame.columns) == list(PARAMETER_COLUMNS)
    assert list(frame["name"]) == [p["name"] for p in document["parameters"]]
    for (_, row), parameter in zip(frame.iterrows(), document["parameters"]):
        assert row["value"] == pytest.approx(parameter["value"]) and row["start"] == pytest.approx(parameter["start"])
        assert [row["ci95_low"], row["ci95_high"]] == pytest.approx(parameter["ci95"])
        assert row["std"] == pytest.approx(parameter["std"]) and row["unit"] == parameter["unit"]
        assert row["ci95_low"] < row["value"] < row["ci95_high"]
        assert row["provenance"] == "fitted" and row["source"].startswith("least squares on")
    assert set(frame["start_provenance"]) <= {"thesis", "literature", "assumed", "fitted"}
    assert frame.set_index("name")["value"].to_dict() == pytest.approx({"R0": 1.1, "h_end_air": 18.0}, rel=0.03)


def test_the_calibration_figure_shows_the_fit_against_the_measurement(calibration, tmp_path):
    figure = calibration.plot(tmp_path / "fit.png")
    assert is_png(tmp_path / "fit.png")
    trajectories = calibration.trajectories
    assert len(figure.axes) == len(calibration.model.output_names)
    for k, name in enumerate(calibration.model.output_names):
        measured = trajectories[f"{name}_measured"]
        before = np.sqrt(np.nanmean((trajectories[f"{name}_before"] - measured) ** 2))
        after = np.sqrt(np.nanmean((trajectories[f"{name}_after"] - measured) ** 2))
        assert after < before
        # the figure draws those very series
        assert np.allclose(figure.axes[k].lines[2].get_ydata(), trajectories[f"{name}_after"], equal_nan=True)
    rmse_after = np.sqrt(np.nanmean(np.concatenate(
        [(trajectories[f"{n}_after"] - trajectories[f"{n}_measured"]) ** 2 for n in calibration.model.output_names])))
    assert rmse_after == pytest.approx(calibration.after["rmse_all_sensors"], rel=0.05)


def test_a_calibration_without_trajectories_refuses_to_plot(calibration):
    import dataclasses

    with pytest.raises(InputError, match="trajectories"):
        dataclasses.replace(calibration, trajectories=None).plot()


@pytest.mark.parametrize("fault, expected", [
    (SensorFault("T_iron", "bias", 2.0), (-SENSOR_FAULT_BOUNDS["iron"]["bias"], SENSOR_FAULT_BOUNDS["iron"]["bias"])),
    (SensorFault("T_inlet", "drift", 1.0), (-SENSOR_FAULT_BOUNDS["air"]["drift"], SENSOR_FAULT_BOUNDS["air"]["drift"])),
    (SensorFault("T_winding_u", "stuck", 80.0), STUCK_RANGE_C),
])
def test_fault_bounds_are_the_plausibility_bounds(fault, expected):
    assert fault_bounds(fault) == pytest.approx(expected)


def test_a_noise_fault_has_no_bound():
    assert all(math.isnan(b) for b in fault_bounds(SensorFault("T_iron", "noise", 3.0)))


def test_an_empty_diagnosis_is_an_empty_table_with_the_columns(plant_model):
    case = make_hidden_effect_case(None, mission="thesis_fig_7_7", dt_s=60.0, seed=5)
    result = diagnose(plant_model, case.data, effects=["coolant_flow_reduction"], pairs=False,
                      design_experiment=False, sensor_faults=False)
    frame = result.to_pandas()
    assert result.verdict == "none"
    assert list(frame.columns) == list(CLAIM_COLUMNS)
    assert set(frame["kind"]) <= {"unexplained"}
    assert isinstance(frame, pd.DataFrame)


def test_a_sensor_fault_claim_is_a_row_with_the_faults_value_and_bounds(plant_model):
    from genthermal.sensor_faults import inject_sensor_faults

    case = make_hidden_effect_case(None, mission="thesis_fig_7_7", dt_s=60.0, seed=5)
    data = inject_sensor_faults(case.data, [SensorFault("T_winding_u", "bias", 2.0, 5400.0)], noise_std_K=0.09)
    result = diagnose(plant_model, data, effects=["coolant_flow_reduction"], pairs=False, design_experiment=False)
    document, frame = result.to_dict(), result.to_pandas()
    claim, fault = document["claims"][0], document["sensor_faults"][0]
    row = frame.iloc[0]
    assert (row["kind"], row["subject"], row["quantity"]) == ("sensor_fault", claim["sensor"], fault["kind"])
    assert row["size"] == pytest.approx(fault["value"]) == pytest.approx(2.0, abs=0.2)
    assert row["onset_s"] == pytest.approx(fault["onset_s"])
    assert (row["bound_low"], row["bound_high"]) == (-SENSOR_FAULT_BOUNDS["winding"]["bias"],
                                                     SENSOR_FAULT_BOUNDS["winding"]["bias"])
    assert (row["evidence"], row["confidence"]) == (claim["evidence"], claim["confidence"])
