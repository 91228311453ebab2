"""The manager's settings split into the settings of each role, with the scenario's say resolved once."""

import dataclasses

import pytest

from genthermal.errors import InputError
from genthermal.mission import load_mission
from genthermal.schedule.flight.manager_settings import DEFAULT_REST_BUDGET_FRACTION, ManagerSettings
from genthermal.schedule.flight.role_settings import PlannerSettings
from genthermal.schedule.power_system import MANAGER_KEYS, PowerSystem


@pytest.fixture(scope="module")
def thesis_system():
    """A chapter-7 scenario: it gives margin_K 0, filter kf and when_infeasible best_effort."""
    return PowerSystem.from_mission(load_mission("chapter7_inlet_3C"))


def test_each_role_gets_the_scenarios_say_and_its_own_settings(thesis_system):
    settings = ManagerSettings(cycle_s=600.0, seed=7, max_rest_s=1200.0)
    roles = settings.roles("heuristic", thesis_system.mission.duration_s, thesis_system.manager_say)
    assert thesis_system.manager_say == {"margin_K": 0.0, "filter": "kf", "when_infeasible": "best_effort"}
    assert roles.planner.margin_K == roles.monitor.margin_K == 0.0 != settings.margin_K
    assert roles.estimator.filter == "kf" and roles.planner.when_infeasible == "best_effort"
    assert (roles.loop.cycle_s, roles.loop.seed, roles.planner.max_rest_s) == (600.0, 7, 1200.0)
    assert roles.loop.rest_budget_s == pytest.approx(DEFAULT_REST_BUDGET_FRACTION * thesis_system.mission.duration_s)
    # the planner receives no loop, filter or monitor settings, the monitor no planner settings
    planner_fields = {f.name for f in dataclasses.fields(roles.planner)}
    assert not planner_fields & {"seed", "filter", "detection", "sensor_watch", "tell_fault", "cpu_limit_s"}
    assert not {f.name for f in dataclasses.fields(roles.monitor)} & {"optimal", "heuristic", "seed", "filter"}
    # the own shed plan needs the flown model: not with the thesis's linear filter
    assert not ManagerSettings().roles("optimal", 3600.0, {"filter": "kf"}).planner.own_shed
    assert ManagerSettings(planner_model="affine").roles("optimal", 3600.0, {}).planner.own_shed
    assert not ManagerSettings().roles("optimal", 3600.0, {}).planner.own_shed  # auto: plans on the flown model


def test_the_planner_settings_are_manager_settings_of_the_same_names():
    """One vocabulary: every planner setting is a key of the command line and of a scenario."""
    manager_fields = {f.name for f in dataclasses.fields(ManagerSettings)}
    assert {f.name for f in dataclasses.fields(PlannerSettings)} <= manager_fields
    assert set(MANAGER_KEYS) <= manager_fields


def test_an_unknown_scenario_key_is_named():
    with pytest.raises(InputError, match="generators.margin_C") as error:
        ManagerSettings().with_scenario({"margin_C": 2.0})
    assert "2.0" in str(error.value) and "margin_K" in str(error.value)  # the known keys are listed


def test_the_nonlinear_planner_refuses_a_scenarios_linear_filter():
    with pytest.raises(InputError, match="generators.filter"):
        ManagerSettings(planner_model="nonlinear").roles("optimal", 3600.0, {"filter": "kf"})
    with pytest.raises(InputError, match="planner_model"):  # the engineer plans on the design model only
        ManagerSettings(planner_model="nonlinear").roles("engineer", 3600.0, {})
