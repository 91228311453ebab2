"""The manager's price decides between resting and shedding: a shed plan rests first only where the
load that rest keeps served is worth more than its minutes, and when only the margin is lost the
cheaper of the lowest-peak schedule and the margin-keeping shed plan is flown."""

import dataclasses

import numpy as np
import pytest

from genthermal.mission import load_mission
from genthermal.schedule.flight import replanning
from genthermal.schedule.planning import registry
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.planning.plan import PlanningProblem, PlanResult, Schedule, mission_segments
from genthermal.schedule.power_system import PowerSystem
from genthermal.schedule.planning.price import (SHED_PRICE_MIN_PER_AH, cost_min, not_served_Ah, not_served_per_segment_Ah,
                                      schedule_cost_min)
from genthermal.schedule.planning.shed import priced_shed_plan, shed_rest_candidates_s, shed_switching_off

from flight_scenarios import SHORT


@pytest.fixture(scope="module")
def system(tmp_path_factory):
    path = tmp_path_factory.mktemp("price") / "short.yaml"
    path.write_text(SHORT)
    return PowerSystem.from_mission(load_mission(str(path)))


def _hot_landing(system, rest_budget_s=3600.0):
    """gen1 hot (110 °C) with its coolant's inlet 31 K up, landing next: it must shed or rest."""
    landing = mission_segments(system.mission)[-1:]
    generators = [system.design_generator(g, ()) for g in range(system.n_generators)]
    x0 = np.full((system.n_generators, system.nominal_model.n_states), 40.0)
    x0[0] = 110.0
    return PlanningProblem(landing, generators, x0, np.array([51.0, 20.0]), 20.0, system.rest_current_A,
                           system.current_limit_A, system.limit_C - 2.5, max_rest_s=3600.0, rise_backoff=0.3,
                           rest_budget_s=rest_budget_s)


def test_not_served_counts_shed_load_and_switched_off_generators(system):
    segments = mission_segments(system.mission)
    n = len(segments)
    assert not_served_Ah(segments, Schedule.nominal(2, n)) == 0.0
    moved = np.zeros((2, n))
    moved[0], moved[1] = 1.0, -1.0  # displaced, all served
    assert not_served_Ah(segments, Schedule(moved, np.zeros(n))) == 0.0
    shed = np.zeros((2, n))
    shed[0, 1] = 2.0  # 2 A of gen1 go to nobody for the 30-min combat cruise
    assert not_served_Ah(segments, Schedule(shed, np.zeros(n))) == pytest.approx(1.0)
    # gen1 off: its whole nominal charge is not served but what gen2 takes (1 A throughout)
    taken = np.zeros((2, n))
    taken[1] = -1.0
    nominal_Ah = sum(d * c for s in segments for d, c in s.pieces) / 3600.0
    off = Schedule(taken, np.zeros(n), np.array([True, False]))
    assert not_served_Ah(segments, off) == pytest.approx(nominal_Ah - sum(s.duration_s for s in segments) / 3600.0)
    rest = Schedule(shed, np.array([600.0, 0.0, 0.0]))
    assert schedule_cost_min(segments, rest) == pytest.approx(10.0 + SHED_PRICE_MIN_PER_AH * 1.0)
    with pytest.raises(ValueError, match="not_served"):
        cost_min(0.0, -1.0)


def test_rest_candidates_double_up_to_what_is_available():
    np.testing.assert_allclose(shed_rest_candidates_s(2000.0, 300.0), [0, 300, 600, 1200, 2000])
    np.testing.assert_allclose(shed_rest_candidates_s(0.0, 300.0), [0])
    with pytest.raises(ValueError, match="step_s"):
        shed_rest_candidates_s(600.0, 0.0)


def test_the_shed_plan_rests_first_only_when_the_load_it_saves_is_worth_its_minutes(system):
    problem = _hot_landing(system)
    flat = shed_switching_off(problem, [False, False], system.limit_C, 2.5)
    assert not_served_Ah(problem.segments, flat.schedule) > 0.01  # with no rest, gen1 sheds in landing
    priced = priced_shed_plan(problem, [False, False], system.limit_C, 2.5)
    costs = {(k, rest): cost for k, rest, cost in priced.details["priced_rests"]}
    assert set(costs) == {(0, rest) for rest in shed_rest_candidates_s(3600.0, problem.window_s)}
    for (k, rest), cost in costs.items():  # every candidate priced as the plan it is
        plan = shed_switching_off(problem, [False, False], system.limit_C, 2.5, rest_s=rest, rest_segment=k)
        assert cost == pytest.approx(schedule_cost_min(problem.segments, plan.schedule))
    assert priced.details["cost_min"] == pytest.approx(min(costs.values()), abs=10.0 / 60.0)
    # at 1000 min per A·h the rest that cools gen1 before landing is worth its minutes
    assert priced.schedule.added_rest_s > 0
    assert priced.details["cost_min"] < costs[(0, 0.0)]
    # no budget left: no rest
    spent = priced_shed_plan(_hot_landing(system, rest_budget_s=0.0), [False, False], system.limit_C, 2.5)
    assert spent.schedule.added_rest_s == 0.0 and spent.details["priced_rests"] == [(0, 0.0, spent.details["cost_min"])]


def _margin_lost(system):
    segments = mission_segments(system.mission)
    generators = [system.design_generator(g, ()) for g in range(system.n_generators)]
    x0 = np.full((system.n_generators, system.nominal_model.n_states), 40.0)
    return PlanningProblem(segments, generators, x0, np.array([51.0, 20.0]), 20.0, system.rest_current_A,
                           system.current_limit_A, system.limit_C - 2.5, rise_backoff=0.3)


@pytest.mark.parametrize("shed_cost_min, flown", [(5.0, "shed"), (45.0, "engineer")])
def test_margin_lost_flies_the_cheaper_of_resting_and_shedding(system, monkeypatch, shed_cost_min, flown):
    problem = _margin_lost(system)
    n = len(problem.segments)
    lowest_peak_C = problem.limit_C + 0.4  # θmax can be kept, the margin cannot

    def plan(rest_s, peak_C, feasible, method, shed_A=0.0):
        displaced = np.zeros((2, n))
        displaced[0, -1] = shed_A
        return PlanResult(Schedule(displaced, np.array([0.0] * (n - 1) + [rest_s])), feasible, peak_C, 0, n - 1,
                          0.0, method)

    def engineer(p, settings):  # 30 min of rest within the lowest peak, infeasible within the margin
        if p.limit_C == problem.limit_C:
            return plan(0.0, lowest_peak_C + 1.0, False, "engineer")
        return plan(1800.0, p.limit_C - 0.05, True, "engineer")

    def shed(p, off, limit_C, receiver_margin_K):  # keeps the margin, at the given price
        result = plan(0.0, p.limit_C, False, "shed", shed_A=0.1)
        result.details.update(shedding=[0], cost_min=shed_cost_min)
        return result
    monkeypatch.setattr(replanning, "lowest_reachable_peak", lambda p, s: plan(3600.0, lowest_peak_C, False, "min-max"))
    monkeypatch.setitem(registry._PLANNERS, "engineer", dataclasses.replace(
        registry.planner("engineer"), plan=lambda p, settings, previous: engineer(p, settings)))
    monkeypatch.setattr(replanning, "priced_shed_plan", shed)
    result = replanning.plan_with("engineer", problem, ManagerSettings(), system.generator_names, system.limit_C)
    assert result.method == flown and not result.feasible
    if flown == "shed":
        assert result.details["lowest_peak_schedule_cost_min"] == pytest.approx(30.0)
        assert "cheaper at the manager's price" in result.warnings[-1]
    else:
        assert result.details["cost_min"] == pytest.approx(30.0)
        assert result.details["shed_alternative_cost_min"] == pytest.approx(45.0)
        assert result.schedule.added_rest_s == 1800.0
    # the manager that flies best effort never sheds: the lowest-peak schedule
    best_effort = replanning.plan_with("engineer", problem, ManagerSettings(), system.generator_names, system.limit_C,
                                       when_infeasible="best_effort")
    assert best_effort.method == "engineer" and best_effort.schedule.added_rest_s == 1800.0


def test_the_priced_rest_comes_right_before_the_shedding_when_that_is_cheaper(system):
    # gen1 at 95 °C in the combat cruise, its inlet 31 K up: without rest it sheds only in landing
    segments = mission_segments(system.mission)[1:]
    generators = [system.design_generator(g, ()) for g in range(system.n_generators)]
    x0 = np.full((system.n_generators, system.nominal_model.n_states), 40.0)
    x0[0] = 95.0
    problem = PlanningProblem(segments, generators, x0, np.array([51.0, 20.0]), 20.0, system.rest_current_A,
                              system.current_limit_A, system.limit_C - 2.5, max_rest_s=3600.0, rise_backoff=0.3,
                              rest_budget_s=3600.0)
    unrested = shed_switching_off(problem, [False, False], system.limit_C, 2.5)
    short = not_served_per_segment_Ah(segments, unrested.schedule)
    assert short[0] == 0.0 and short[1] > 0.1
    priced = priced_shed_plan(problem, [False, False], system.limit_C, 2.5)
    assert priced.schedule.rest_before_s[0] == 0.0 and priced.schedule.rest_before_s[1] > 0.0
    now = min(cost for k, rest, cost in priced.details["priced_rests"] if k == 0)
    assert priced.details["cost_min"] < now < schedule_cost_min(segments, unrested.schedule) + 1e-9
