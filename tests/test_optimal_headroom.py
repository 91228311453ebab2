"""The optimal scheduler's headroom tie-breaker (genthermal.schedule.headroom) on both planners."""

import numpy as np
import pytest

from genthermal.estimation.ekf import ExtendedKalmanFilter
from genthermal.schedule.flown import FlownPlanning
from genthermal.schedule.headroom import DEFAULT_HEADROOM_WEIGHT_S, MIN_SPAN_K, headroom_scale
from genthermal.schedule.heuristic import heuristic_plan
from genthermal.schedule.optimal import OptimalSettings, _Transcription
from genthermal.schedule.optimal_nlp import NonlinearSettings, flown_optimal_plan
from genthermal.schedule.plan import PlanningProblem, Segment, predict, split_segments
from genthermal.schedule.power_system import AffineGenerator

BLOCKAGE = {"k_flow": 0.2, "n_flow": 0.0}
INLETS_C = np.array([51.0, 20.0])  # the blocked generator's inlet after the large blockage (thesis 7.3.3)
#: The old tie-breaker: the least displacement, weight 1 s per A²·h, no headroom term.
LEAST_DISPLACEMENT = dict(headroom_weight_s=0.0, displacement_weight=1.0)


@pytest.fixture(scope="module")
def generators(design_model):
    """Design models of a blocked generator and a healthy one."""
    return [AffineGenerator(design_model.with_effect("coolant_flow_reduction", **BLOCKAGE)),
            AffineGenerator(design_model)]


def _problem(generators, currents_A, limit_C, flown=None, x0=None):
    """Two 15-min segments at ``currents_A`` from steady state at 4.5 A."""
    if x0 is None:
        x0 = np.array([g.steady_state(g.input(4.5, t, 20.0)) for g, t in zip(generators, INLETS_C)])
    segments = tuple(Segment(k, f"s{k}", 900.0, ((0.0, current),)) for k, current in enumerate(currents_A))
    return PlanningProblem(segments, generators, np.asarray(x0), INLETS_C, 20.0, 1.911, 7.0, limit_C=limit_C,
                           max_rest_s=900.0, flown=flown)


def _solve(problem, settings):
    """IPOPT's schedule of the affine transcription alone (no baseline candidates)."""
    transcription = _Transcription(problem, settings, minimax=False)
    schedule, success, status = transcription.solve(transcription.initial_guess(heuristic_plan(problem).schedule))
    assert success, status
    return schedule


def test_headroom_term_never_buys_rest(generators):
    """At 7 A nobody can take load, so only rest cools the blocked winding: the rest-only optimum
    (weight 0) and the default weight rest the same to within the weight; a weight far above
    any rest's worth does buy rest, so the bound is what keeps it out."""
    problem = _problem(generators, (7.0, 7.0), 130.0)
    rest_only = _solve(problem, OptimalSettings(headroom_weight_s=0.0))
    default = _solve(problem, OptimalSettings())
    assert rest_only.added_rest_s > 60.0  # the case needs rest
    assert default.added_rest_s <= rest_only.added_rest_s + DEFAULT_HEADROOM_WEIGHT_S + 1e-3
    bought = _solve(problem, OptimalSettings(headroom_weight_s=36000.0))
    assert bought.added_rest_s > rest_only.added_rest_s + 60.0


def test_headroom_term_keeps_the_blocked_winding_cool_where_rest_does_not_depend_on_it(generators):
    """No rest is needed within 115 °C: the least displacement holds the blocked winding at the
    limit, the headroom term moves load to the healthy generator, which has room."""
    problem = _problem(generators, (5.5, 6.0), 115.0)
    least = _solve(problem, OptimalSettings(**LEAST_DISPLACEMENT))
    headroom = _solve(problem, OptimalSettings())
    assert least.added_rest_s == 0.0 and headroom.added_rest_s == 0.0
    peaks_least = predict(problem, least).outputs.max(axis=(1, 2))
    peaks_headroom = predict(problem, headroom).outputs.max(axis=(1, 2))
    assert peaks_least[0] > 114.5  # at the limit
    assert peaks_headroom[0] < peaks_least[0] - 4.0
    assert peaks_headroom[1] < problem.limit_C and np.all(headroom.displaced_A[0] > least.displaced_A[0])


def test_the_flown_model_planner_keeps_the_blocked_winding_cool_too(generators, plant_model):
    """The same tie-breaker on the nonlinear planner (the same setting, the same default)."""
    models = [plant_model.with_effect("coolant_flow_reduction", **BLOCKAGE), plant_model]
    filters = [ExtendedKalmanFilter(m, 10.0) for m in models]
    x0 = [np.full(models[0].n_states, 85.0), np.full(models[1].n_states, 60.0)]
    nd = len(filters[0].disturbance_names)
    flown = FlownPlanning(filters, [np.concatenate([x, np.zeros(nd)]) for x in x0], [0.1 * f.P0 for f in filters])
    problem = _problem(generators, (4.9, 4.9), 110.0, flown, x0)
    problem.segments = split_segments(problem.segments, 300.0, 10.0)
    least = flown_optimal_plan(problem, NonlinearSettings(**LEAST_DISPLACEMENT), initial=None)
    headroom = flown_optimal_plan(problem, NonlinearSettings(), initial=None)
    assert least.method == headroom.method == "optimal"
    assert least.schedule.added_rest_s == 0.0 and headroom.schedule.added_rest_s == 0.0
    peak_least = predict(problem, least.schedule).outputs[0].max()
    peak_headroom = predict(problem, headroom.schedule).outputs[0].max()
    assert peak_headroom < peak_least - 2.0
    assert headroom.feasible


def test_headroom_scale_is_the_ambient_and_the_rise_the_limit_allows(generators):
    np.testing.assert_allclose(headroom_scale(_problem(generators, (5.0, 5.0), 110.0)), [20.0, 90.0])
    np.testing.assert_allclose(headroom_scale(_problem(generators, (5.0, 5.0), 15.0)), [20.0, MIN_SPAN_K])
