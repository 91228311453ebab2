"""The rest a re-plan may still add: the longest rest before one action and the flight's rest budget,
the rest under way counted once, and every scheduler planning within it."""

import dataclasses

import numpy as np
import pytest

from genthermal.mission import load_mission
from genthermal.schedule.planning.engineer import engineer_plan
from genthermal.schedule.planning.heuristic import heuristic_plan
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.planning.plan import PlanningProblem, mission_segments, rest_available_s
from genthermal.schedule.power_system import PowerSystem
from genthermal.schedule.flight.replanning import first_rest_max_s, planning_problem

from flight_scenarios import SHORT


@pytest.fixture(scope="module")
def system(tmp_path_factory):
    path = tmp_path_factory.mktemp("rest") / "short.yaml"
    path.write_text(SHORT)
    return PowerSystem.from_mission(load_mission(str(path)))


def _flight_problem(system, rest_budget_s, rest_taken_s, max_rest_s=3600.0):
    segments = mission_segments(system.mission)
    generators = [system.design_generator(g, ()) for g in range(system.n_generators)]
    x0 = np.full((system.n_generators, system.nominal_model.n_states), 40.0)
    return planning_problem(system.frame(), ManagerSettings(max_rest_s=max_rest_s), segments, x0, 0.0, generators,
                            rest_budget_s, rest_taken_s)


def test_the_rest_under_way_is_counted_once_against_the_budget(system):
    # 30 min rested before this action, 30 min of a 60-min budget left: 30 min more are allowed
    # (the budget left has the rest under way taken off already; it used to be taken off twice)
    problem = _flight_problem(system, rest_budget_s=1800.0, rest_taken_s=1800.0)
    assert first_rest_max_s(problem) == pytest.approx(1800.0)
    # the longest rest before one action binds: 50 min rested of at most 60, budget plenty
    problem = _flight_problem(system, rest_budget_s=3000.0, rest_taken_s=3000.0)
    assert first_rest_max_s(problem) == pytest.approx(600.0)
    # the budget binds, and the rests planned before a later segment count against it
    problem = _flight_problem(system, rest_budget_s=900.0, rest_taken_s=600.0)
    assert first_rest_max_s(problem) == pytest.approx(900.0)
    assert rest_available_s(problem, 1, earlier_rest_s=600.0) == pytest.approx(300.0)
    assert rest_available_s(problem, 2, earlier_rest_s=1200.0) == 0.0


@pytest.mark.parametrize("planner", [engineer_plan, heuristic_plan])
def test_schedulers_rest_before_the_first_segment_only_what_is_left_of_the_rest_under_way(system, planner):
    # gen1 hot with its coolant's inlet 31 K up, landing next: it needs rest before landing
    landing = mission_segments(system.mission)[-1:]
    generators = [system.design_generator(g, ()) for g in range(system.n_generators)]
    x0 = np.full((system.n_generators, system.nominal_model.n_states), 40.0)
    x0[0] = 110.0
    problem = PlanningProblem(landing, generators, x0, np.array([51.0, 20.0]), 20.0, system.rest_current_A,
                              system.current_limit_A, system.limit_C - 2.5, max_rest_s=1800.0, rise_backoff=0.3,
                              rest_budget_s=3600.0)
    fresh = planner(problem)
    assert fresh.schedule.rest_before_s[0] == pytest.approx(1800.0)  # the longest rest, and not enough
    for taken in (600.0, 1800.0):
        result = planner(dataclasses.replace(problem, rest_taken_s=taken))
        assert result.schedule.rest_before_s[0] == pytest.approx(1800.0 - taken)
        assert not result.feasible
