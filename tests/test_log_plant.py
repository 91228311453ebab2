"""A recorded flight replayed as the plant (``fly --plant log.csv``): decisions scored, not applied,
and the bad logs: columns that are not the machine's sensors, a step that is not the flight's, a
NaN or an unreadable value mid-flight."""

import json

import numpy as np
import pandas as pd
import pytest

from genthermal.cli import main
from genthermal.errors import InputError
from genthermal.plants.log_plant import LogPlant
from genthermal.schedule.flight.closed_loop import fly
from genthermal.schedule.flight.manager_settings import ManagerSettings

from test_plants import HOT_MISSION, LumpedPlant, _system


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    """The hot mission flown unmanaged on the example numpy plant (330 s above θmax), as a log."""
    folder = tmp_path_factory.mktemp("log")
    system, mission = _system(folder, HOT_MISSION)
    flown = fly(system, "engineer", ManagerSettings(replan=False), LumpedPlant())
    log = folder / "unmanaged.csv"
    flown.to_pandas().to_csv(log, index=False)
    return system, mission, log, flown


def _edited(tmp_path, log, edit, name="edited.csv"):
    frame = pd.read_csv(log)
    frame = edit(frame)
    path = tmp_path / name
    frame.to_csv(path, index=False)
    return path


def test_a_replayed_log_is_flown_as_logged_and_the_decisions_are_scored(recorded):
    system, _, log, flown = recorded
    sensors = tuple(system.planning_model.output_names)
    result = fly(system, "engineer", ManagerSettings(), LogPlant(log, sensors))
    # the log does not change: the manager's rests are recorded, the logged temperatures and currents flown
    np.testing.assert_allclose(result.temperatures_C, flown.temperatures_C, atol=1e-9)
    np.testing.assert_allclose(result.currents_A, flown.currents_A, atol=1e-12)
    replay = result.summary()["replay"]
    assert replay["decisions_applied"] is False and replay["log_end_s"] == flown.time_s[-1]
    assert replay["commanded_rest_s"] > 0.0 and flown.resting.sum() == 0
    # the manager re-planned before the logged breach
    assert replay["log_first_breach_s"] is not None and replay["first_replan_s"] < replay["log_first_breach_s"]
    assert replay["lead_s"] == replay["log_first_breach_s"] - replay["first_replan_s"]
    assert result.summary()["breach_s"] == flown.summary()["breach_s"] == 330.0


@pytest.mark.parametrize("edit, column, words", [
    (lambda f: f.drop(columns=["gen2_T_iron"]), "gen2_T_iron", "missing"),
    (lambda f: f.assign(gen1_T_outlet=f["gen1_T_iron"]), "gen1_T_outlet", "extra"),
    (lambda f: f.rename(columns={"gen2_T_winding": "gen3_T_winding"}), "gen2_T_winding", "missing"),
])
def test_a_log_whose_columns_are_not_the_machines_sensors_names_the_column(recorded, tmp_path, capsys, edit,
                                                                           column, words):
    system, mission, log, _ = recorded
    path = _edited(tmp_path, log, edit)
    with pytest.raises(InputError, match=words) as error:
        fly(system, "engineer", ManagerSettings(), LogPlant(path, tuple(system.planning_model.output_names)))
    assert column in str(error.value)
    assert main(["fly", str(mission), "--scheduler", "engineer", "--plant", str(path)]) == 2
    assert column in capsys.readouterr().err


def test_a_log_at_another_step_or_without_time_is_refused(recorded, tmp_path):
    system, _, log, _ = recorded
    sensors = tuple(system.planning_model.output_names)
    coarse = _edited(tmp_path, log, lambda f: f.iloc[::2])
    with pytest.raises(InputError, match="step of 20 s"):
        fly(system, "engineer", ManagerSettings(), LogPlant(coarse, sensors))
    with pytest.raises(InputError, match="time_s"):
        LogPlant(_edited(tmp_path, log, lambda f: f.drop(columns=["time_s"]), "untimed.csv"), sensors)
    with pytest.raises(InputError, match="no such log"):
        LogPlant(tmp_path / "absent.csv", sensors)


@pytest.mark.parametrize("value, kind", [(np.nan, "not_finite"), ("broken", "raised")])
def test_a_log_that_fails_mid_flight_is_recorded_and_the_record_so_far_kept(recorded, tmp_path, value, kind):
    """A NaN (or an unreadable value) at 2000 s stops the flight in the cycle that reads it: the
    fault is in the JSON, the manager holds the minimum power mode, the record up to that cycle is
    written and is the log's."""
    system, mission, log, flown = recorded

    def spoil(frame):
        frame = frame.astype({"gen1_T_winding": object})
        frame.loc[frame["time_s"] == 2000.0, "gen1_T_winding"] = value
        return frame
    path = _edited(tmp_path, log, spoil)
    out, record = tmp_path / "flight.json", tmp_path / "record.csv"
    assert main(["fly", str(mission), "--scheduler", "engineer", "--plant", str(path), "--json", str(out),
                 "--record", str(record)]) == 3
    summary = json.loads(out.read_text())
    fault = summary["plant_fault"]
    assert fault["kind"] == kind and fault["held"] == "minimum power mode"
    assert 1700.0 <= fault["time_s"] < 2000.0  # the cycle that would read 2000 s
    kept = pd.read_csv(record)
    assert kept["time_s"].iloc[-1] == fault["time_s"]
    rows = flown.time_s <= fault["time_s"]
    np.testing.assert_allclose(kept["gen1_T_winding"], flown.temperatures_C[0, 0, rows], atol=1e-9)
    assert summary["replay"]["decisions_applied"] is False


def test_a_log_shorter_than_the_mission_ends_the_flight_at_its_last_row(recorded, tmp_path):
    system, _, log, _ = recorded
    short = _edited(tmp_path, log, lambda f: f[f["time_s"] <= 3000.0])
    result = fly(system, "engineer", ManagerSettings(), LogPlant(short, tuple(system.planning_model.output_names)))
    assert result.time_s[-1] == 3000.0 and result.plant_fault is None
