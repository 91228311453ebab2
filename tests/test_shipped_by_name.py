"""Every shipped stand-in plant, record and mission is selectable by name, from any folder."""

import pytest

from genthermal import InputError, load_measurements, load_mission, load_model
from genthermal.mission import available_scenarios
from genthermal.resources import DEMO_DATA_DIR, shipped_data_missions, shipped_data_names


@pytest.fixture
def empty_folder(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_every_shipped_data_file_is_named_once():
    plants, records, missions = shipped_data_names(".yaml"), shipped_data_names(".csv"), shipped_data_missions()
    assert {"rig_plant", "rig_plant_b"} <= set(plants) and "hidden_effect_demo" in records
    assert "low_load_calibration" in missions and not set(plants) & set(missions)
    shipped = {path.name for path in DEMO_DATA_DIR.iterdir() if path.suffix in (".yaml", ".csv")}
    assert shipped == {f"{name}.yaml" for name in plants + missions} | {f"{name}.csv" for name in records}


@pytest.mark.parametrize("name", shipped_data_names(".yaml"))
def test_a_stand_in_plant_loads_by_name_and_by_file_name(name, empty_folder):
    by_name, by_file_name = load_model(name), load_model(f"{name}.yaml")
    assert by_name.spec.effects and by_name.spec.effects == by_file_name.spec.effects
    assert list(by_name.p0) == list(by_file_name.p0)


def test_a_shipped_record_and_mission_load_by_name(empty_folder):
    assert len(load_measurements("hidden_effect_demo").time_s) == 1441
    assert load_mission("low_load_calibration").duration_s == 3 * 3600.0
    assert "low_load_calibration" in available_scenarios()


def test_a_local_file_of_the_same_name_wins(empty_folder):
    (empty_folder / "rig_plant.yaml").write_text("machine: genco_rf201a\nvariant: linear\n")
    assert load_model("rig_plant.yaml").spec.variant == "linear"
    assert load_model("rig_plant").spec.variant == "nonlinear"  # the bare name is the shipped plant


def test_an_unknown_name_lists_the_stand_in_plants_not_the_missions(empty_folder):
    with pytest.raises(InputError, match="rig_plant, rig_plant_b") as error:
        load_model("rig_plnat")
    assert "low_load_calibration" not in str(error.value)


def test_the_cli_synthesises_on_a_stand_in_plant_by_name(empty_folder, capsys):
    from genthermal.cli import main

    assert main(["synth", "step_rated", "--model", "rig_plant", "--out", "rig.csv"]) == 0
    assert (empty_folder / "rig.csv").stat().st_size > 1000
