"""Optimal (IPOPT) and MILP (HiGHS) schedules on the design model, and infeasible cases."""

import itertools

import numpy as np
import pytest

from genthermal.mission import load_mission
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.flight.open_loop import plan_mission
from genthermal.schedule.flight.replanning import plan_with
from genthermal.schedule.planning.optimal import lowest_reachable_peak
from genthermal.schedule.planning.milp import MilpSettings, milp_objective, milp_plan
from genthermal.schedule.planning.plan import PlanningProblem, Schedule, Segment, predict
from genthermal.schedule.power_system import AffineGenerator, PowerSystem


@pytest.fixture(scope="module")
def blockage():
    return PowerSystem.from_mission(load_mission("blockage_large"))


@pytest.fixture(scope="module")
def open_loop_plans(blockage):
    # on the design model, every one (the optimal scheduler's default plans on the flown model)
    return {s: plan_mission(blockage, s, ManagerSettings(planner_model="affine")) for s in ("heuristic", "optimal", "milp")}


def test_optimal_rests_no_more_than_the_heuristic_and_keeps_the_limit(blockage, open_loop_plans):
    heuristic, optimal = open_loop_plans["heuristic"], open_loop_plans["optimal"]
    planning_limit = blockage.limit_C - ManagerSettings().margin_K
    for flown in (heuristic, optimal):
        assert flown.plans and all(plan["feasible"] for plan in flown.plans)
        assert flown.temperatures_C.max() <= planning_limit + 0.05  # design model, every 10 s
    rest = {name: flown.time_s[-1] - blockage.mission.duration_s for name, flown in open_loop_plans.items()}
    assert rest["heuristic"] > 0
    assert rest["optimal"] <= 0.75 * rest["heuristic"]
    assert open_loop_plans["optimal"].plans[0]["method"] == "optimal"


def test_milp_plan_is_certified_and_feasible(open_loop_plans):
    plan = open_loop_plans["milp"].plans[0]
    assert plan["certified"] and plan["feasible"]
    assert plan["status"].startswith("HiGHS")


@pytest.fixture(scope="module")
def tiny(design_model):
    faulty = AffineGenerator(design_model.with_effect("coolant_flow_reduction", k_flow=0.2, n_flow=0.0))
    healthy = AffineGenerator(design_model)
    inlets = np.array([51.0, 20.0])
    x0 = np.array([g.steady_state(g.input(4.5, t, 20.0)) for g, t in zip((faulty, healthy), inlets)])
    segments = (Segment(0, "a", 900.0, ((0.0, 5.5),)), Segment(1, "b", 900.0, ((0.0, 6.0),)))
    return PlanningProblem(segments, [faulty, healthy], x0, inlets, 20.0, 1.911, 7.0, limit_C=108.0,
                           max_rest_s=900.0)


def test_milp_optimum_is_no_worse_than_any_enumerated_discrete_schedule(tiny):
    settings = MilpSettings(chunk_A=0.5, max_rest_s=900.0, relative_gap=1e-9)
    result = milp_plan(tiny, settings)
    assert result.method == "milp" and result.details["certified"]
    assert result.feasible and predict(tiny, result.schedule).peak()[0] <= tiny.limit_C + 0.05
    best = np.inf
    # gen1 sheds m chunks, gen2 takes them: both currents within [0, 7 A]
    chunks = [range(max(int(np.ceil(lo / 0.5 - 1e-9)), -int(np.floor(hi / 0.5 + 1e-9))),
                    min(int(np.floor(hi / 0.5 + 1e-9)), -int(np.ceil(lo / 0.5 - 1e-9))) + 1)
              for lo, hi in (tiny.displacement_bounds(0), tiny.displacement_bounds(1))]
    for r0, r1, m0, m1 in itertools.product(range(4), range(4), *chunks):
        schedule = Schedule(np.array([[0.5 * m0, 0.5 * m1], [-0.5 * m0, -0.5 * m1]]), 300.0 * np.array([r0, r1]))
        if predict(tiny, schedule).peak()[0] <= tiny.limit_C:
            best = min(best, milp_objective(tiny, schedule, settings))
    assert np.isfinite(best)
    assert result.details["objective_min"] <= best + 1e-6
    assert milp_objective(tiny, result.schedule, settings) == pytest.approx(result.details["objective_min"], abs=1e-6)


def test_infeasible_case_names_the_lowest_peak_and_the_action(tiny):
    hopeless = PlanningProblem(tiny.segments, tiny.generators, tiny.x0, tiny.inlet_C, 20.0, 1.911, 7.0,
                               limit_C=60.0, max_rest_s=900.0)
    result = plan_with("heuristic", hopeless, ManagerSettings(), ("gen1", "gen2"), limit_C=60.0)
    assert not result.feasible
    message = result.warnings[-1]
    assert message.startswith("infeasible: no schedule keeps θ ≤ 60 °C")
    assert "lowest reachable peak is" in message and "during action" in message
    assert result.details["lowest_peak_C"] > 60.0


@pytest.mark.parametrize("scheduler", ["engineer", "optimal"])
def test_a_plan_that_keeps_thetamax_but_not_its_back_off_is_not_feasible(tiny, scheduler):
    lowest = lowest_reachable_peak(tiny).peak_C
    squeezed = PlanningProblem(tiny.segments, tiny.generators, tiny.x0, tiny.inlet_C, 20.0, 1.911, 7.0,
                               limit_C=lowest - 1.0, max_rest_s=900.0)
    result = plan_with(scheduler, squeezed, ManagerSettings(), ("gen1", "gen2"), limit_C=lowest + 1.0)
    assert not result.feasible
    assert result.warnings[-1].startswith("margin not kept") and "rest" in result.details["response"]
    assert result.details["planned_peak_C"] <= lowest + 1.0


def test_while_shedding_the_manager_keeps_shedding_rather_than_use_up_the_margin(tiny):
    """Hysteresis: a manager that sheds goes back to plans without shedding only once one keeps the
    planning limit; a lowest-peak schedule within θmax but into the margin is not flown then."""
    lowest = lowest_reachable_peak(tiny).peak_C
    squeezed = PlanningProblem(tiny.segments, tiny.generators, tiny.x0, tiny.inlet_C, 20.0, 1.911, 7.0,
                               limit_C=lowest - 1.0, max_rest_s=900.0)
    names = ("gen1", "gen2")
    relaxed = plan_with("optimal", squeezed, ManagerSettings(), names, limit_C=lowest + 1.0)
    assert relaxed.method != "shed" and relaxed.peak_C > squeezed.limit_C  # not shedding: into the margin
    kept = plan_with("optimal", squeezed, ManagerSettings(), names, limit_C=lowest + 1.0, shedding=True)
    assert kept.method == "shed" and not kept.feasible
    assert kept.peak_C < relaxed.peak_C and kept.peak_C <= lowest + 1.0  # load not served instead of margin
    assert kept.warnings[-1].startswith("margin not kept") and "keeps shedding" in kept.warnings[-1]
    assert "within the planning limit" in kept.details["response"]


def test_the_optimal_scheduler_keeps_the_plan_with_the_least_rest_of_its_candidates(tiny, monkeypatch):
    """IPOPT's local optimum is one candidate among the heuristic's, the engineer's and the previous
    plan, all judged on the same problem: a baseline's plan that rests less is flown, and says so."""
    import genthermal.schedule.planning.optimal as optimal
    from genthermal.schedule.planning.plan import evaluate

    honest = optimal.optimal_plan(tiny)
    assert honest.feasible and honest.method == "optimal"
    resting = Schedule(honest.schedule.displaced_A, honest.schedule.rest_before_s + [600.0, 0.0])  # 10 min more

    def worse_optimum(transcription, guess):
        return resting, True, "Solve_Succeeded"
    monkeypatch.setattr(optimal._Transcription, "solve", worse_optimum)
    safeguarded = optimal.optimal_plan(tiny)
    assert evaluate(tiny, resting, "x", 0.0).feasible
    assert safeguarded.feasible and safeguarded.method == "optimal"
    assert safeguarded.schedule.added_rest_s < 600.0 - optimal.MIN_REST_S
    assert safeguarded.details["chosen_from"] in ("heuristic", "engineer")


def test_a_previous_plan_that_sheds_load_is_no_candidate(tiny):
    from genthermal.schedule.planning.optimal import least_cost, optimal_plan, serves_all_load
    from genthermal.schedule.planning.plan import evaluate

    shedding = Schedule(np.array([[2.0, 2.0], [0.0, 0.0]]), np.zeros(2))  # gen1's 2 A go to nobody
    assert not serves_all_load(tiny, shedding) and not serves_all_load(tiny, None)
    assert not serves_all_load(tiny, Schedule.nominal(2, 2, switched_off=[True, False]))
    assert serves_all_load(tiny, Schedule(np.array([[1.0, 0.5], [-1.0, -0.5]]), np.zeros(2)))
    plan = optimal_plan(tiny).schedule
    cool = evaluate(tiny, Schedule(plan.displaced_A, plan.rest_before_s + 60.0), "a minute more", 0.0)
    quick = evaluate(tiny, Schedule(plan.displaced_A, plan.rest_before_s + [60.0, 59.5]), "half a second less", 0.0)
    quicker = evaluate(tiny, Schedule(plan.displaced_A, plan.rest_before_s + [60.0, 0.0]), "a minute less", 0.0)
    assert cool.feasible and quick.feasible and quicker.feasible
    segments = tiny.segments
    assert least_cost([cool, quick], segments) is cool  # less than MIN_REST_S less is no saving
    assert least_cost([cool, None, quicker], segments) is quicker
    # two minutes less rest bought with 0.1 A of gen1's load not served costs more at the manager's price
    sheds = evaluate(tiny, Schedule(plan.displaced_A + np.array([[0.1, 0.1], [0.0, 0.0]]), plan.rest_before_s),
                     "sheds 0.1 A", 0.0)
    assert sheds.feasible and sheds.schedule.added_rest_s < cool.schedule.added_rest_s - 100.0
    assert least_cost([cool, sheds], segments) is cool
    with pytest.raises(ValueError, match="feasible"):
        least_cost([None], segments)
