"""The thesis heuristic (eqs. 7.1-7.5, Fig. 7.2) on small hand-made cases on the design model."""

import numpy as np
import pytest

from genthermal.schedule.planning.heuristic import heuristic_plan
from genthermal.schedule.planning.plan import PlanningProblem, Schedule, Segment, predict
from genthermal.schedule.power_system import AffineGenerator

HOT_INLET_C = 51.0


@pytest.fixture(scope="module")
def healthy(design_model):
    return AffineGenerator(design_model)


@pytest.fixture(scope="module")
def faulty(design_model):
    return AffineGenerator(design_model.with_effect("coolant_flow_reduction", k_flow=0.2, n_flow=0.0))


def problem(generators, inlets, current_A, limit_C, minutes=(30,), current_limit_A=7.0):
    """Constant-load segments from the steady state at 3 A; limit set by the caller."""
    x0 = np.array([g.steady_state(g.input(3.0, inlet, 20.0)) for g, inlet in zip(generators, inlets)])
    segments = tuple(Segment(k, f"test {k}", 60.0 * m, ((0.0, current_A),)) for k, m in enumerate(minutes))
    return PlanningProblem(segments, list(generators), x0, np.array(inlets, dtype=float), 20.0,
                           rest_current_A=1.911, current_limit_A=current_limit_A, limit_C=limit_C)


def nominal_peak(p):
    return predict(p, Schedule.nominal(p.n_generators, len(p.segments))).outputs[0].max()


def test_displacement_only_when_the_healthy_generator_has_room(faulty, healthy):
    base = problem([faulty, healthy], [HOT_INLET_C, 20.0], 4.9, limit_C=200.0)
    limit = nominal_peak(base) - 3.0
    p = problem([faulty, healthy], [HOT_INLET_C, 20.0], 4.9, limit_C=limit)
    result = heuristic_plan(p)
    d = result.schedule.displaced_A[:, 0]
    assert result.feasible and result.schedule.added_rest_s == 0.0
    assert d[0] > 0 and d[1] == pytest.approx(-d[0])
    # eq. 7.2: the least displacement, so the faulty generator just touches the limit
    assert result.peak_C == pytest.approx(limit, abs=1e-3)
    less = Schedule(np.array([[d[0] - 0.01], [-(d[0] - 0.01)]]), np.zeros(1))
    assert predict(p, less).outputs[0].max() > limit


def test_no_action_when_nothing_is_predicted_to_overheat(faulty, healthy):
    p = problem([faulty, healthy], [HOT_INLET_C, 20.0], 4.9, limit_C=200.0)
    result = heuristic_plan(p)
    assert result.feasible and not np.any(result.schedule.displaced_A) and result.schedule.added_rest_s == 0.0


def test_rest_when_no_generator_can_take_the_load(faulty):
    base = problem([faulty, faulty], [HOT_INLET_C, HOT_INLET_C], 4.9, limit_C=200.0)
    limit = nominal_peak(base) - 3.0
    p = problem([faulty, faulty], [HOT_INLET_C, HOT_INLET_C], 4.9, limit_C=limit)
    result = heuristic_plan(p)
    rest = result.schedule.rest_before_s[0]
    assert result.feasible and not np.any(result.schedule.displaced_A)
    assert rest > 0 and rest % 300.0 == 0.0  # extended in steps of 5 min ...
    shorter = Schedule(np.zeros((2, 1)), np.array([rest - 300.0]))
    assert predict(p, shorter).outputs.max() > limit  # ... until it is just long enough


def test_rest_then_more_displacement_when_the_current_limit_binds(faulty, healthy):
    # 6.5 A nominal: the healthy generator can take only 0.5 A before its 7 A limit
    base = problem([faulty, healthy], [HOT_INLET_C, 20.0], 6.5, limit_C=200.0, minutes=(15,))
    limit = nominal_peak(base) - 8.0
    p = problem([faulty, healthy], [HOT_INLET_C, 20.0], 6.5, limit_C=limit, minutes=(15,))
    result = heuristic_plan(p)
    rest, d = result.schedule.rest_before_s[0], result.schedule.displaced_A[:, 0]
    assert result.feasible and rest > 0 and 0 < d[0] <= 0.5 + 1e-9
    most = Schedule(np.array([[0.5], [-0.5]]), np.array([rest - 300.0]))
    assert predict(p, most).outputs[0].max() > limit  # the shorter rest fails even with all 0.5 A


def test_forward_sweep_handles_each_segment(faulty, healthy):
    base = problem([faulty, healthy], [HOT_INLET_C, 20.0], 4.9, limit_C=200.0, minutes=(20, 20))
    limit = nominal_peak(base) - 2.0
    p = problem([faulty, healthy], [HOT_INLET_C, 20.0], 4.9, limit_C=limit, minutes=(20, 20))
    result = heuristic_plan(p)
    assert result.feasible and result.peak_C <= limit + 1e-6
    assert result.schedule.displaced_A.shape == (2, 2)


@pytest.mark.parametrize("n_steps", [0, 1, 2, 5, 64, 361])
def test_affine_states_is_the_step_by_step_recurrence(n_steps):
    from genthermal.schedule.planning.plan import affine_states

    rng = np.random.default_rng(n_steps)
    E = 0.9 * np.eye(4) + 0.02 * rng.random((4, 4))  # stable, coupled, not symmetric
    forced, x0 = rng.normal(size=(n_steps, 4)), rng.normal(size=4) * 50.0
    expected, state = np.empty((n_steps, 4)), x0
    for i in range(n_steps):
        state = E @ state + forced[i]
        expected[i] = state
    np.testing.assert_allclose(affine_states(E, forced, x0), expected, rtol=1e-12, atol=1e-10)
