"""Tests of genthermal.mission and genthermal.conditions: Table 3.2, missions, scenario files."""

from __future__ import annotations

import copy

import numpy as np
import pandas as pd
import pytest

from genthermal.conditions import (
    LOAD_CONDITIONS,
    MIN_ACTION_DURATION_S,
    STARTUP_DURATION_S,
    find_condition,
)
from genthermal.errors import InputError
from genthermal.exciter import DEFAULT_POWER_FACTOR, exciter_current
from genthermal.mission import (
    INPUT_COLUMNS,
    SCENARIO_DIR,
    Action,
    Mission,
    available_scenarios,
    load_mission,
)

SHIPPED = ("step_rated", "thesis_fig_3_2", "thesis_fig_7_7", "varying_load")


def two_action_document():
    """Taxi (15 min) then cruise (30 min): a small valid scenario to break in tests."""
    return {
        "name": "two_actions",
        "actions": [
            {"condition": 3, "duration_min": 15},
            {"condition": "cruise", "duration_min": 30},
        ],
    }


def assert_input_error(document, field, value, *also_in_message):
    """from_dict(document) raises InputError naming ``field`` and ``value`` (and more text)."""
    with pytest.raises(InputError) as info:
        Mission.from_dict(document)
    message = str(info.value)
    assert info.value.field == field
    assert field in message
    assert repr(value) in message
    for text in also_in_message:
        assert text in message
    return info.value


# --- Table 3.2 ---------------------------------------------------------------------------------
def test_table_3_2_levels_names_and_provenance():
    expected = {
        1: ("loading_preparation", 40.0, 27.3),
        2: ("start_warm_up", 83.3, 66.7),
        3: ("taxi", 100.0, 83.3),
        4: ("take_off_climb", 83.3, 76.7),
        5: ("cruise", 83.3, 70.0),
        6: ("cruise_combat", 86.7, 73.3),
        7: ("landing", 100.0, 76.7),
    }
    assert len(LOAD_CONDITIONS) == 7
    for condition in LOAD_CONDITIONS:
        name, startup, continuous = expected[condition.number]
        assert (condition.name, condition.startup_percent, condition.continuous_percent) == (
            name, startup, continuous)
        assert condition.source == "thesis Table 3.2"
    assert STARTUP_DURATION_S == 300.0
    assert MIN_ACTION_DURATION_S == 900.0


def test_find_condition_by_number_and_forgiving_name():
    assert find_condition(6).name == "cruise_combat"
    assert find_condition("Take-off climb").number == 4
    assert find_condition(LOAD_CONDITIONS[0]) is LOAD_CONDITIONS[0]


# --- load over time ----------------------------------------------------------------------------
def test_startup_level_for_exactly_the_first_five_minutes_then_continuous():
    mission = Mission("cruise_only", [Action(5, 1800.0)])
    times = np.array([0.0, 299.999, 300.0, 1799.0, 1800.0])
    expected = np.array([83.3, 83.3, 70.0, 70.0, 70.0]) / 100 * 7.0
    np.testing.assert_allclose(mission.phase_current(times), expected)
    assert isinstance(mission.phase_current(10.0), float)


def test_phase_current_is_right_continuous_at_action_boundaries():
    mission = Mission.from_dict(two_action_document())
    assert mission.phase_current(899.0) == pytest.approx(0.833 * 7.0)  # taxi continuous
    assert mission.phase_current(900.0) == pytest.approx(0.833 * 7.0)  # cruise start-up
    assert mission.phase_current(1199.0) == pytest.approx(0.833 * 7.0)
    assert mission.phase_current(1200.0) == pytest.approx(0.700 * 7.0)  # cruise continuous
    assert mission.phase_current(0.0) == pytest.approx(1.000 * 7.0)  # taxi start-up


def test_phase_current_refuses_times_outside_the_mission():
    mission = Mission.from_dict(two_action_document())
    with pytest.raises(InputError, match="t_s"):
        mission.phase_current([0.0, mission.duration_s + 1.0])
    with pytest.raises(InputError, match="t_s"):
        mission.phase_current(-1.0)


def test_duration_and_action_boundaries():
    mission = load_mission("thesis_fig_7_7")
    assert mission.duration_s == 240 * 60.0
    np.testing.assert_allclose(mission.action_boundaries_s() / 60.0, [0, 15, 30, 45, 66, 120, 180, 220, 240])
    assert [action.condition.number for action in mission.actions] == [1, 2, 3, 4, 5, 6, 5, 7]


# --- model inputs ------------------------------------------------------------------------------
def test_to_inputs_shape_columns_and_dtype():
    mission = Mission.from_dict(two_action_document())  # 2700 s
    inputs = mission.to_inputs(10.0)
    assert isinstance(inputs, pd.DataFrame)
    assert tuple(inputs.columns) == INPUT_COLUMNS
    assert len(inputs) == 271  # 0, 10, ..., 2700 inclusive
    assert all(dtype == np.float64 for dtype in inputs.dtypes)
    assert inputs["time_s"].iloc[-1] == 2700.0
    assert (inputs["T_inlet"] == 20.0).all() and (inputs["T_ambient"] == 20.0).all()


def test_to_inputs_stops_before_the_end_when_dt_does_not_divide_the_duration():
    inputs = Mission.from_dict(two_action_document()).to_inputs(7.0)
    assert inputs["time_s"].iloc[-1] == 2695.0
    assert len(inputs) == 386


def test_to_inputs_uses_zero_order_hold_at_boundaries():
    inputs = Mission.from_dict(two_action_document()).to_inputs(60.0).set_index("time_s")
    assert inputs.loc[240.0, "I_u"] == pytest.approx(7.0)  # over [240, 300): taxi start-up
    assert inputs.loc[300.0, "I_u"] == pytest.approx(0.833 * 7.0)  # over [300, 360): continuous
    assert inputs.loc[840.0, "I_u"] == pytest.approx(0.833 * 7.0)
    assert inputs.loc[900.0, "I_u"] == pytest.approx(0.833 * 7.0)  # cruise start-up
    assert inputs.loc[1200.0, "I_u"] == pytest.approx(0.700 * 7.0)
    assert inputs.loc[2700.0, "I_u"] == pytest.approx(0.700 * 7.0)  # last level held at the end
    np.testing.assert_allclose(inputs["I_exc"], exciter_current(inputs["I_u"], DEFAULT_POWER_FACTOR))


def test_phase_share_makes_an_unbalanced_load():
    document = two_action_document()
    document["actions"][1]["phase_share"] = [1.2, 1.0, 0.8]
    mission = Mission.from_dict(document)
    inputs = mission.to_inputs(300.0).set_index("time_s")
    cruise_continuous = 0.7 * 7.0
    np.testing.assert_allclose(inputs.loc[1500.0, ["I_u", "I_v", "I_w"]],
                               [1.2 * cruise_continuous, cruise_continuous, 0.8 * cruise_continuous])
    assert inputs.loc[600.0, "I_u"] == inputs.loc[600.0, "I_w"]  # taxi stays balanced
    assert inputs.loc[1500.0, "I_exc"] == pytest.approx(exciter_current(cruise_continuous))
    assert mission.phase_current(1500.0) == pytest.approx(cruise_continuous)
    assert mission.phase_currents([1500.0]).shape == (1, 3)


def test_load_percent_action_for_step_tests():
    mission = load_mission("step_rated")
    assert mission.actions[0].condition is None
    np.testing.assert_allclose(mission.to_inputs(600.0)["I_v"], 7.0)
    overload = Mission("overload", [Action(None, 600.0, load_percent=120)])
    assert overload.phase_current(0.0) == pytest.approx(8.4)


# --- scenario files ----------------------------------------------------------------------------
@pytest.mark.parametrize("name", SHIPPED)
def test_each_shipped_scenario_loads(name):
    mission = load_mission(name)
    assert mission.name == name
    assert mission.description
    assert (mission.T_inlet_C, mission.T_ambient_C, mission.rated_current_A) == (20.0, 20.0, 7.0)
    assert load_mission(SCENARIO_DIR / f"{name}.yaml") == mission
    assert set(SHIPPED) <= set(available_scenarios())


def test_thesis_fig_3_2_sequence_and_assumed_durations():
    mission = load_mission("thesis_fig_3_2")
    assert [action.condition.number for action in mission.actions] == [1, 2, 3, 4, 5, 6, 5, 7]
    assert [action.duration_s / 60 for action in mission.actions] == [15, 15, 15, 15, 45, 30, 45, 15]
    assert "assumed" in mission.description


def test_varying_load_alternates_every_half_hour():
    mission = load_mission("varying_load")
    assert [action.load_percent for action in mission.actions] == [100.0, 27.3] * 4
    assert mission.duration_s == 4 * 3600.0


@pytest.mark.parametrize("name", SHIPPED)
def test_round_trip_to_dict_from_dict(name):
    mission = load_mission(name)
    assert Mission.from_dict(mission.to_dict()) == mission


def test_round_trip_keeps_phase_share_and_reserved_sections():
    document = two_action_document()
    document["actions"][0]["phase_share"] = [1.1, 1.0, 0.9]
    document["faults"] = [{"kind": "blockage", "at_min": 66}]
    document["generators"] = {"count": 2}
    document["extensions"] = {"my_tool": {"colour": "red"}}
    mission = Mission.from_dict(copy.deepcopy(document))
    assert mission.extras == {key: document[key] for key in ("faults", "generators", "extensions")}
    assert Mission.from_dict(mission.to_dict()) == mission


# --- bad input ---------------------------------------------------------------------------------
def test_unknown_condition_number_lists_valid_conditions():
    document = two_action_document()
    document["actions"][1]["condition"] = 9
    assert_input_error(document, "actions[1].condition", 9, "1 (loading_preparation)", "7 (landing)")


def test_unknown_condition_name_suggests_closest():
    document = two_action_document()
    document["actions"][0]["condition"] = "cruize"
    assert_input_error(document, "actions[0].condition", "cruize", "did you mean 'cruise'")


def test_duration_under_15_minutes():
    document = two_action_document()
    document["actions"][1]["duration_min"] = 10
    assert_input_error(document, "actions[1].duration_min", 10, "at least 15 min")


def test_non_numeric_duration():
    document = two_action_document()
    document["actions"][0]["duration_min"] = "30 min"
    assert_input_error(document, "actions[0].duration_min", "30 min", "number of minutes")


def test_negative_load_percent():
    document = {"name": "step", "actions": [{"load_percent": -5, "duration_min": 60}]}
    assert_input_error(document, "actions[0].load_percent", -5, "0..120")


def test_negative_rated_current():
    document = two_action_document()
    document["rated_current_A"] = -7
    assert_input_error(document, "rated_current_A", -7, "positive")


def test_negative_phase_share():
    document = two_action_document()
    document["actions"][0]["phase_share"] = [1.0, -0.5, 1.0]
    assert_input_error(document, "actions[0].phase_share[1]", -0.5, "positive")


def test_missing_required_name():
    document = two_action_document()
    del document["name"]
    assert_input_error(document, "name", None, "missing")


def test_missing_required_duration():
    document = two_action_document()
    del document["actions"][1]["duration_min"]
    assert_input_error(document, "actions[1].duration_min", None, "missing")


def test_misspelt_action_key_suggests_the_valid_one():
    document = two_action_document()
    document["actions"][0]["duraton_min"] = document["actions"][0].pop("duration_min")
    assert_input_error(document, "actions[0].duraton_min", 15, "did you mean 'duration_min'")


def test_misspelt_top_level_key_suggests_the_valid_one():
    document = two_action_document()
    document["T_inlet"] = 30
    assert_input_error(document, "T_inlet", 30, "did you mean 'T_inlet_C'")


def test_empty_actions():
    document = two_action_document()
    document["actions"] = []
    assert_input_error(document, "actions", [], "non-empty")


def test_extensions_must_be_a_mapping():
    document = two_action_document()
    document["extensions"] = "colour: red"
    assert_input_error(document, "extensions", "colour: red", "mapping")


def test_yaml_syntax_error_names_file_and_line(tmp_path):
    path = tmp_path / "broken.yaml"
    path.write_text("name: broken\nactions:\n  - {condition: 1, duration_min: 15\n  - {condition: 2}\n")
    with pytest.raises(InputError) as info:
        load_mission(path)
    assert info.value.field == str(path)
    assert str(path) in str(info.value)
    assert "line " in info.value.reason


def test_schema_error_in_a_file_names_the_file(tmp_path):
    path = tmp_path / "short.yaml"
    path.write_text("name: short\nactions:\n  - {condition: taxi, duration_min: 5}\n")
    with pytest.raises(InputError) as info:
        load_mission(str(path))
    assert info.value.field == "actions[0].duration_min"
    assert str(path) in str(info.value)


def test_missing_file_lists_available_scenarios(tmp_path):
    missing = tmp_path / "nowhere.yaml"
    with pytest.raises(InputError) as info:
        load_mission(missing)
    assert info.value.field == "scenario"
    assert repr(str(missing)) in str(info.value)
    assert "thesis_fig_7_7" in str(info.value)


def test_unknown_scenario_name_lists_available_ones():
    with pytest.raises(InputError) as info:
        load_mission("thesis_fig_7_8")
    message = str(info.value)
    assert info.value.field == "scenario"
    assert "'thesis_fig_7_8'" in message
    for name in SHIPPED:
        assert name in message
    assert "did you mean 'thesis_fig_7_7'" in message


@pytest.mark.parametrize("document", [None, [1, 2], "name: x"])
def test_non_mapping_document(document):
    with pytest.raises(InputError, match="mapping"):
        Mission.from_dict(document)


@pytest.mark.parametrize(
    "entry, field",
    [
        ("taxi", "actions[0]"),
        ({"duration_min": 15}, "actions[0].condition"),
        ({"condition": 1, "load_percent": 50, "duration_min": 15}, "actions[0].load_percent"),
        ({"condition": True, "duration_min": 15}, "actions[0].condition"),
        ({"condition": 1, "duration_min": 15, "phase_share": [1, 1]}, "actions[0].phase_share"),
    ],
)
def test_other_malformed_actions(entry, field):
    with pytest.raises(InputError) as info:
        Mission.from_dict({"name": "bad", "actions": [entry]})
    assert info.value.field == field


def test_direct_construction_is_checked_too():
    with pytest.raises(InputError, match="duration_s"):
        Action(3, 600.0)
    with pytest.raises(InputError, match="T_inlet_C"):
        Mission("hot", [Action(3, 900.0)], T_inlet_C=150.0)
    with pytest.raises(InputError, match="dt_s"):
        Mission("ok", [Action(3, 900.0)]).to_inputs(0.0)


@pytest.mark.parametrize("value", [0.0, 1.5, -0.8, "high", None])
def test_power_factor_outside_0_1_is_refused(value):
    document = two_action_document()
    document["power_factor"] = value
    assert_input_error(document, "power_factor", value)


def test_power_factor_sets_the_exciter_current_and_round_trips():
    document = two_action_document()
    document["power_factor"] = 1.0
    unity = Mission.from_dict(document)
    default = Mission.from_dict(two_action_document())
    assert default.power_factor == DEFAULT_POWER_FACTOR
    assert Mission.from_dict(unity.to_dict()).power_factor == 1.0
    # a lagging load needs more field current than a unity power-factor load at the same current
    assert np.all(default.to_inputs(300.0)["I_exc"] > unity.to_inputs(300.0)["I_exc"])
