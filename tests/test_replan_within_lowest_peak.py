"""When no schedule keeps the margin, the re-plan within the lowest reachable peak flies the
scheduler's plan whenever it keeps that limit by the tolerance every plan is judged with."""

import dataclasses

import numpy as np
import pytest

from genthermal.mission import load_mission
from genthermal.schedule.flight import replanning
from genthermal.schedule.planning import registry
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.planning.plan import FEASIBLE_TOLERANCE_K, PlanningProblem, PlanResult, Schedule, mission_segments
from genthermal.schedule.power_system import PowerSystem

from flight_scenarios import SHORT

MIN_MAX_REST_S = 600.0
SCHEDULER_REST_S = 10.0


@pytest.fixture(scope="module")
def problem_and_system(tmp_path_factory):
    path = tmp_path_factory.mktemp("lowest") / "short.yaml"
    path.write_text(SHORT)
    system = PowerSystem.from_mission(load_mission(str(path)))
    segments = mission_segments(system.mission)
    generators = [system.design_generator(g, ()) for g in range(system.n_generators)]
    x0 = np.full((system.n_generators, system.nominal_model.n_states), 40.0)
    problem = PlanningProblem(segments, generators, x0, np.array([51.0, 20.0]), 20.0, system.rest_current_A,
                              system.current_limit_A, system.limit_C - 2.5, rise_backoff=0.3)
    return problem, system


def _plan(n_segments: int, rest_s: float, peak_C: float, feasible: bool, method: str) -> PlanResult:
    rests = np.zeros(n_segments)
    rests[-1] = rest_s
    return PlanResult(Schedule(np.zeros((2, n_segments)), rests), feasible, peak_C, 0, n_segments - 1, 0.0, method)


@pytest.mark.parametrize("over_K, flown_rest_s", [(0.01, SCHEDULER_REST_S),
                                                  (FEASIBLE_TOLERANCE_K - 1e-3, SCHEDULER_REST_S),
                                                  (FEASIBLE_TOLERANCE_K + 0.02, MIN_MAX_REST_S)])
def test_scheduler_plan_within_the_tolerance_of_the_relaxed_limit_is_flown(problem_and_system, monkeypatch,
                                                                           over_K, flown_rest_s):
    problem, system = problem_and_system
    n = len(problem.segments)
    lowest_peak_C = problem.limit_C + 0.4  # the margin cannot be kept, θmax can

    def min_max(p, settings):
        return _plan(n, MIN_MAX_REST_S, lowest_peak_C, False, "lowest peak")

    def engineer(p, settings):
        if p.limit_C == problem.limit_C:  # the margin: infeasible
            return _plan(n, 0.0, lowest_peak_C + 1.0, False, "engineer")
        # within the lowest reachable peak (+ 0.1 K): a short rest, over_K above that limit
        return _plan(n, SCHEDULER_REST_S, p.limit_C + over_K, over_K <= FEASIBLE_TOLERANCE_K, "engineer")
    def costly_shed(p, off, limit_C, receiver_margin_K):  # keeping the margin by shedding costs more than resting
        shed = _plan(n, 0.0, p.limit_C, False, "shed")
        shed.details.update(shedding=[0], cost_min=1000.0)
        return shed
    monkeypatch.setattr(replanning, "lowest_reachable_peak", min_max)
    monkeypatch.setattr(replanning, "priced_shed_plan", costly_shed)
    monkeypatch.setitem(registry._PLANNERS, "engineer", dataclasses.replace(
        registry.planner("engineer"), plan=lambda p, settings, previous: engineer(p, settings)))
    result = replanning.plan_with("engineer", problem, ManagerSettings(), system.generator_names, system.limit_C)
    assert result.schedule.added_rest_s == flown_rest_s
    assert not result.feasible and "margin not kept" in result.warnings[-1]
    assert result.method == ("engineer" if flown_rest_s == SCHEDULER_REST_S else "engineer (lowest peak)")
