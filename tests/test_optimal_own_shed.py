"""The optimal scheduler's own shed plan on the flown model, against the shared shed plan the baselines fly."""

import dataclasses

import numpy as np
import pytest

from genthermal.errors import InputError
from genthermal.estimation.ekf import ExtendedKalmanFilter
from genthermal.schedule.planning.flown import FlownPlanning
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.planning.optimal_shed import chosen_shed_plan, on_flown_model, shed_guess
from genthermal.schedule.planning.plan import PlanningProblem, PlanResult, Schedule, Segment, predict
from genthermal.schedule.power_system import AffineGenerator
from genthermal.schedule.planning.price import PRICE_TOLERANCE_MIN, schedule_cost_min
from genthermal.schedule.flight.replanning import plan_with

BLOCKAGE = {"k_flow": 0.2, "n_flow": 0.0}
NAMES = ("gen1", "gen2")
THETA_MAX_C = 110.0
#: A filter that has converged: a tenth of the initial covariance (as tests/test_schedule_optimal_nlp.py).
CONVERGED = 0.1


@pytest.fixture(scope="module")
def forced_to_shed(plant_model, design_model):
    """Two generators at 100 °C, gen1 with a k_flow 0.2 blockage and a 51 °C inlet, 20 min at the
    7-A limit and a 10-min landing at 5 A, no rest left: no schedule serving all load keeps θmax
    (the lowest reachable peak is 144 °C), so every scheduler must shed. Returns the design-model
    problem as the affine planner poses it and the filters' FlownPlanning."""
    models = [plant_model.with_effect("coolant_flow_reduction", **BLOCKAGE), plant_model]
    filters = [ExtendedKalmanFilter(m, 10.0) for m in models]
    generators = [AffineGenerator(design_model.with_effect("coolant_flow_reduction", **BLOCKAGE)),
                  AffineGenerator(design_model)]
    x0 = np.array([np.full(models[0].n_states, 100.0), np.full(models[1].n_states, 100.0)])
    segments = (Segment(5, "6 cruise_combat", 1200.0, ((0.0, 7.0),)), Segment(7, "7 landing", 600.0, ((0.0, 5.0),)))
    settings = ManagerSettings()
    problem = PlanningProblem(segments, generators, x0, np.array([51.0, 20.0]), 20.0, 1.911, 7.0,
                              limit_C=THETA_MAX_C - settings.margin_K, max_rest_s=0.0, dt_s=10.0,
                              rise_backoff=settings.rise_backoff, window_s=300.0, rest_budget_s=0.0)
    nd = len(filters[0].disturbance_names)
    flown = FlownPlanning(filters, [np.concatenate([x, np.zeros(nd)]) for x in x0],
                          [CONVERGED * f.P0 for f in filters])
    return problem, flown


def test_optimal_flies_its_own_shed_plan_on_the_flown_model(forced_to_shed):
    """The shared shed plan (the baselines') costs 1162 min at the manager's price on this problem;
    the optimal scheduler's own plan on the flown model keeps both generators within θmax with its
    back-off and costs 1069 min, so it is flown, reported infeasible (it sheds) with both costs."""
    problem, flown = forced_to_shed
    settings = ManagerSettings()
    shared = plan_with("engineer", problem, settings, NAMES, THETA_MAX_C, flown_shed=flown)
    optimal = plan_with("optimal", problem, settings, NAMES, THETA_MAX_C, flown_shed=flown)
    assert shared.method == optimal.method == "shed" and not shared.feasible and not optimal.feasible
    assert "shed_plan_flown" not in shared.details  # the baselines keep the shared plan
    assert optimal.details["shed_plan_flown"] == "own"
    shared_cost = schedule_cost_min(problem.segments, shared.schedule)
    own_cost = schedule_cost_min(problem.segments, optimal.schedule)
    assert optimal.details["shared_shed_cost_min"] == pytest.approx(shared_cost)
    assert optimal.details["own_shed_cost_min"] == pytest.approx(own_cost)
    assert own_cost < shared_cost - PRICE_TOLERANCE_MIN
    # its own forecast: every generator within θmax with the filters' back-off
    assert predict(on_flown_model(problem, flown, THETA_MAX_C), optimal.schedule).peak()[0] <= THETA_MAX_C + 0.05
    assert optimal.schedule.added_rest_s == 0.0 and not optimal.schedule.switched_off.any()
    assert "own plan on the flown model" in optimal.warnings[-1]


def test_without_own_shedding_the_optimal_scheduler_flies_the_shared_plan(forced_to_shed):
    """``own_shed=False`` (or no filters to plan on) gives the shared plan, the baselines' behaviour."""
    problem, flown = forced_to_shed
    shared = plan_with("engineer", problem, ManagerSettings(), NAMES, THETA_MAX_C)
    for settings, flown_shed in ((ManagerSettings(own_shed=False), None), (ManagerSettings(), None)):
        optimal = plan_with("optimal", problem, settings, NAMES, THETA_MAX_C, flown_shed=flown_shed)
        np.testing.assert_allclose(optimal.schedule.displaced_A, shared.schedule.displaced_A)
    assert not ManagerSettings(own_shed=False).sheds_on_flown_model("optimal", "ekf")
    assert ManagerSettings().sheds_on_flown_model("optimal", "ekf")
    assert not ManagerSettings().sheds_on_flown_model("engineer", "ekf")
    assert not ManagerSettings(planner_model="nonlinear").sheds_on_flown_model("optimal", "ekf")  # plans there already
    # no flown model to plan on with the linear filter, the settings' or a scenario's (generators.filter: kf)
    assert not ManagerSettings(filter="kf").sheds_on_flown_model("optimal", "kf")
    assert not ManagerSettings().sheds_on_flown_model("optimal", "kf")


def test_own_plan_is_flown_when_it_keeps_thetamax_whatever_the_shared_plans_forecast_costs(forced_to_shed):
    """A shared plan whose design-model forecast costs nothing (all load served, no rest) does not
    displace an own plan that keeps θmax on the flown model: the two costs are forecasts on
    different models (optimal_shed). Where the own plan cannot keep θmax on its forecast (a limit
    below today's temperatures), the shared plan is returned as it is, with the comparison."""
    problem, flown = forced_to_shed
    nominal = Schedule.nominal(problem.n_generators, len(problem.segments))
    shared = PlanResult(nominal, False, 120.0, 0, 0, 0.0, "shed")
    chosen, comparison = chosen_shed_plan(problem, shared, flown, THETA_MAX_C)
    assert chosen is not shared and comparison["shed_plan_flown"] == "own"
    assert comparison["shared_shed_cost_min"] == 0.0 < comparison["own_shed_cost_min"]
    chosen, comparison = chosen_shed_plan(dataclasses.replace(problem, limit_C=40.0), shared, flown, 40.0)
    assert chosen is shared and comparison["shed_plan_flown"] == "shared" and comparison["own_shed_cost_min"] is None


def test_own_shed_plan_starts_from_a_switched_off_generator_shedding_its_load(forced_to_shed):
    """The transcription cannot switch a generator off: the shared plan's switched-off generator
    becomes one that sheds its whole (lowest) load in each segment, within the displacement bounds."""
    problem, _ = forced_to_shed
    off = Schedule(np.zeros((2, 2)), np.array([30.0, 0.0]), np.array([True, False]))
    guess = shed_guess(problem, off)
    np.testing.assert_allclose(guess.displaced_A[0], [7.0, 5.0])
    np.testing.assert_allclose(guess.displaced_A[1], [0.0, 0.0])
    np.testing.assert_allclose(guess.rest_before_s, [30.0, 0.0])
    assert not guess.switched_off.any()
    assert shed_guess(problem, Schedule.nominal(2, 3)) is None and shed_guess(problem, None) is None


def test_bad_inputs_name_field_and_value(forced_to_shed):
    problem, flown = forced_to_shed
    with pytest.raises(InputError, match="flown"):
        on_flown_model(problem, "filters", THETA_MAX_C)
    with pytest.raises(InputError, match="limit_C = nan"):
        on_flown_model(problem, flown, float("nan"))
    with pytest.raises(InputError, match="shared"):
        chosen_shed_plan(problem, PlanResult(Schedule.nominal(2, 3), False, 0.0, 0, 0, 0.0, "shed"), flown,
                          THETA_MAX_C)
    with pytest.raises(InputError, match="problem.flown"):
        chosen_shed_plan(dataclasses.replace(problem, flown=flown),
                          PlanResult(Schedule.nominal(2, 2), False, 0.0, 0, 0, 0.0, "shed"), flown, THETA_MAX_C)
    with pytest.raises(InputError, match="own_shed = 'yes'"):
        ManagerSettings(own_shed="yes")


@pytest.mark.slow
def test_closed_loop_on_a_plant_hot_at_rest_sheds_less_with_the_own_plan(tmp_path):
    """The plant of tests/test_closed_loop_shed.py whose gen1 is above θmax (85 °C) even at rest:
    with the shared shed plan the optimal flight rests 15 min and leaves 1.10 A·h unserved (1116 min
    at the manager's price, as the baselines); with its own plan on the flown model 15 min and
    0.36 A·h (370 min), and neither generator goes above θmax."""
    from test_closed_loop_shed import HOT_AT_REST, _system

    from genthermal.schedule.flight.closed_loop import fly
    from genthermal.schedule.report import flight_summary

    def cost(summary):
        return summary["rested_s"] / 60.0 + 1000.0 * sum(summary["shed"]["not_served_Ah"].values())
    design = ManagerSettings(planner_model="affine")  # the own shed plan is the design-model planner's
    shared = flight_summary(fly(_system(tmp_path, HOT_AT_REST), "optimal", dataclasses.replace(design, own_shed=False)))
    result = fly(_system(tmp_path, HOT_AT_REST), "optimal", design)
    own = flight_summary(result)
    assert any(plan.get("shed_plan_flown") == "own" for plan in result.plans)
    assert cost(own) < 0.5 * cost(shared)
    assert own["breach_s"] == 0.0 and own["rested_s"] <= shared["rested_s"]
    limit = result.system.limit_C
    assert max(own["max_T_winding"].values()) <= limit and max(own["max_T_iron"].values()) <= limit
