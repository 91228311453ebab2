"""Power system, faults and schedule data: scenario schema, timelines, remaining plans."""

import numpy as np
import pytest

from genthermal.coolant import outlet_flow_fraction
from genthermal.errors import InputError
from genthermal.mission import Mission, load_mission
from genthermal.schedule.planning.plan import Schedule, build_timeline, mission_segments, remaining_after
from genthermal.schedule.power_system import PowerSystem

ACTIONS = [{"condition": "taxi", "duration_min": 15}, {"condition": "landing", "duration_min": 20}]


def system_from(**extras):
    return PowerSystem.from_mission(Mission.from_dict({"name": "t", "actions": ACTIONS, **extras}))


def test_outlet_diameter_maps_to_the_orifice_flow_fraction():
    system = system_from(faults=[{"generator": 1, "kind": "coolant_blockage", "onset_min": 6, "outlet_diameter_mm": 10}])
    assert system.faults[0].values == {"k_flow": pytest.approx(outlet_flow_fraction(10.0))}


def test_large_blockage_scenario_states_its_flow_and_exponent():
    system = PowerSystem.from_mission(load_mission("blockage_large"))
    (fault,) = system.faults
    assert system.generator_names == ("gen1", "gen2")
    assert fault.effect == "coolant_flow_reduction" and fault.values == {"k_flow": 0.2, "n_flow": 0.0}
    assert system.inlet_C(0, [0.0, 66 * 60.0]).tolist() == [20.0, 51.0]
    assert system.inlet_C(1, 66 * 60.0) == 20.0
    assert system.rest_current_A == pytest.approx(0.273 * 7.0)
    assert system.faults_known_at(66 * 60.0 - 1) == () and system.faults_known_at(66 * 60.0) == (0,)


@pytest.mark.parametrize("extras, field", [
    ({"faults": [{"generator": 1, "kind": "coolant_blockage", "onset_min": 66, "k_flow": 3}]}, "faults[0].k_flow"),
    ({"faults": [{"generator": 5, "kind": "inlet_rise", "onset_min": 1, "inlet_rise_C": 4}]}, "faults[0].generator"),
    ({"faults": [{"generator": 1, "kind": "meltdown"}]}, "faults[0].kind"),
    ({"faults": [{"generator": 1, "kind": "effect", "effect": "phase_short", "onset_min": 1}]}, "faults[0].effect"),
    ({"faults": [{"generator": 1, "kind": "inlet_rise", "onset_min": 1, "inlet_rise_C": 4, "k_flow": 0.2}]},
     "faults[0].k_flow"),
    ({"faults": [{"generator": 1, "kind": "coolant_blockage", "onset_min": 6, "k_flow": 0.2,
                  "outlet_diameter_mm": 10}]}, "faults[0].k_flow"),
    ({"faults": [{"generator": "gen1", "kind": "inlet_rise", "inlet_rise_C": 4}]}, "faults[0].onset_min"),
    ({"faults": {"generator": 1}}, "faults"),
    ({"generators": {"count": 1}}, "generators.count"),
    ({"generators": {"rest_percent": 150}}, "generators.rest_percent"),
    ({"generators": {"colour": "red"}}, "generators.colour"),
    ({"generators": {"plant_mismatch": {"h_end_air": -1}}}, "generators.plant_mismatch.h_end_air"),
    ({"generators": {"margin_K": -1}}, "generators.margin_K"),
    ({"generators": {"margin_K": "none"}}, "generators.margin_K"),
    ({"generators": {"filter": "ukf"}}, "generators.filter"),
])
def test_bad_fields_name_the_field(extras, field):
    with pytest.raises(InputError) as error:
        system_from(**extras)
    assert error.value.field == field


def test_a_scenario_margin_is_what_the_manager_plans_to_unless_the_option_overrides_it():
    """``generators.margin_K`` (the chapter-7 scenarios: 0, the thesis heuristic checks θmax itself)
    sets the planning limit; without it the manager's own margin applies; ``--margin`` overrides it."""
    import argparse

    from genthermal.commands.plan import add_schedule_arguments, settings_from_args
    from genthermal.schedule.flight.manager_settings import DEFAULT_MARGIN_K, ManagerSettings

    assert ManagerSettings().with_scenario(system_from(generators={"margin_K": 0}).manager_say).margin_K == 0.0
    assert ManagerSettings().with_scenario(system_from().manager_say).margin_K == DEFAULT_MARGIN_K
    parser = argparse.ArgumentParser()
    add_schedule_arguments(parser)
    system, settings = settings_from_args(parser.parse_args(["chapter7_inlet_3C", "--scheduler", "heuristic"]))
    assert settings.with_scenario(system.manager_say).margin_K == 0.0
    system, settings = settings_from_args(parser.parse_args(["chapter7_inlet_3C", "--scheduler", "heuristic",
                                                             "--margin", "1.5"]))
    assert settings.with_scenario(system.manager_say).margin_K == 1.5


def test_effect_fault_and_named_generators():
    system = system_from(generators={"names": ["left", "right"]},
                         faults=[{"generator": "right", "kind": "effect", "effect": "phase_short_circuit",
                                  "onset_min": 10, "values": {"R_short": 0.3}}])
    assert system.faults[0].generator == 1 and system.faults[0].values == {"R_short": 0.3}


def test_segments_timeline_and_what_remains():
    mission = Mission.from_dict({"name": "t", "actions": ACTIONS})
    segments = mission_segments(mission)
    assert segments[1].levels == ((0.0, 7.0), (300.0, pytest.approx(0.767 * 7.0)))
    schedule = Schedule(np.array([[0.0, 0.5], [0.0, -0.5]]), np.array([0.0, 125.0]))
    timeline = build_timeline(segments, schedule, 1.911, 10.0)
    assert timeline.n_steps == 90 + 13 + 120  # the 125 s rest rounds up to 130 s
    assert timeline.resting[90:103].all() and timeline.currents_A[0, 103] == pytest.approx(6.5)
    left, rest_of = remaining_after(segments, schedule, timeline, 95)
    assert len(left) == 1 and rest_of.rest_before_s[0] == pytest.approx(75.0)
    left, rest_of = remaining_after(segments, schedule, timeline, 103 + 10)
    assert left[0].duration_s == pytest.approx(1100.0) and left[0].levels[0] == (0.0, 7.0)
    assert left[0].levels[1][0] == pytest.approx(200.0) and rest_of.rest_before_s[0] == 0.0


def test_a_scenario_filter_is_the_one_flown_unless_the_option_overrides_it():
    """``generators.filter`` (the chapter-7 scenarios: ``kf``, the thesis manager's linear filter)
    is the filter a flight runs; without it the manager's own; ``fly --filter`` overrides it."""
    import argparse

    from genthermal.commands.fly import register
    from genthermal.commands.plan import settings_from_args
    from genthermal.schedule.flight.manager_settings import ManagerSettings

    assert ManagerSettings().with_scenario(system_from(generators={"filter": "kf"}).manager_say).filter == "kf"
    assert ManagerSettings().with_scenario(system_from().manager_say).filter == ManagerSettings().filter == "ekf"
    parser = argparse.ArgumentParser()
    register(parser.add_subparsers())
    system, settings = settings_from_args(parser.parse_args(["fly", "chapter7_inlet_3C", "--scheduler", "heuristic"]))
    assert settings.with_scenario(system.manager_say).filter == "kf" and not settings.tell_fault
    system, settings = settings_from_args(parser.parse_args(["fly", "chapter7_inlet_3C", "--scheduler", "heuristic",
                                                             "--filter", "ekf", "--tell-fault"]))
    assert settings.with_scenario(system.manager_say).filter == "ekf" and settings.tell_fault


def test_the_nonlinear_planner_refuses_a_scenario_that_flies_the_linear_filter():
    from genthermal.schedule.flight.closed_loop import fly
    from genthermal.schedule.flight.manager_settings import ManagerSettings

    system = PowerSystem.from_mission(load_mission("chapter7_inlet_3C"))
    with pytest.raises(InputError) as error:
        fly(system, "optimal", ManagerSettings(planner_model="nonlinear"))
    assert error.value.field == "generators.filter" and "--filter ekf" in str(error.value)
