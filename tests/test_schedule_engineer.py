"""The engineer's heuristic (largest displacement as soon as a breach is predicted, fine rests)."""

import numpy as np
import pytest

from genthermal.schedule.planning.engineer import EngineerSettings, engineer_plan
from genthermal.schedule.planning.heuristic import heuristic_plan
from genthermal.schedule.planning.plan import PlanningProblem, Schedule, Segment, predict
from genthermal.schedule.power_system import AffineGenerator

HOT_INLET_C = 51.0


@pytest.fixture(scope="module")
def generators(design_model):
    return AffineGenerator(design_model.with_effect("coolant_flow_reduction", k_flow=0.2)), AffineGenerator(design_model)


def problem(generators, inlets, currents_A, limit_C, minutes, current_limit_A=7.0):
    x0 = np.array([g.steady_state(g.input(3.0, inlet, 20.0)) for g, inlet in zip(generators, inlets)])
    segments = tuple(Segment(k, f"test {k}", 60.0 * m, ((0.0, c),)) for k, (c, m) in enumerate(zip(currents_A, minutes)))
    return PlanningProblem(segments, list(generators), x0, np.array(inlets, dtype=float), 20.0,
                           rest_current_A=1.911, current_limit_A=current_limit_A, limit_C=limit_C)


def peak_of_nominal(p):
    return predict(p, Schedule.nominal(p.n_generators, len(p.segments))).outputs[0].max()


def test_sheds_from_the_first_segment_when_a_later_one_breaches(generators):
    faulty, healthy = generators
    base = problem([faulty, healthy], [HOT_INLET_C, 20.0], (3.0, 5.5), 200.0, (20, 20))
    limit = peak_of_nominal(base) - 3.0
    p = problem([faulty, healthy], [HOT_INLET_C, 20.0], (3.0, 5.5), limit, (20, 20))
    engineer, thesis = engineer_plan(p), heuristic_plan(p)
    assert engineer.feasible and engineer.peak_C <= limit + 1e-6
    d = engineer.schedule.displaced_A
    assert d[0, 0] > 0 and d[1, 0] == pytest.approx(-d[0, 0])  # the breach is in segment 2, shedding starts in 1
    assert thesis.schedule.displaced_A[0, 0] == 0.0
    assert engineer.schedule.displaced_Ah(p.segments) > thesis.schedule.displaced_Ah(p.segments)


def test_the_receiver_is_filled_to_its_limit_and_no_further(generators):
    faulty, healthy = generators
    p = problem([faulty, healthy], [HOT_INLET_C, 35.0], (4.9,), 200.0, (30,))
    limit = peak_of_nominal(p) - 3.0
    p = problem([faulty, healthy], [HOT_INLET_C, 35.0], (4.9,), limit, (30,))
    result = engineer_plan(p)
    d = result.schedule.displaced_A[:, 0]
    healthy_peak = predict(p, result.schedule).outputs[1].max()
    assert result.feasible and d[0] > 0
    assert healthy_peak == pytest.approx(limit, abs=1e-3) or -d[1] == pytest.approx(7.0 - 4.9)


def test_rest_on_a_fine_grid_just_long_enough(generators):
    faulty, _ = generators
    base = problem([faulty, faulty], [HOT_INLET_C, HOT_INLET_C], (4.9,), 200.0, (30,))
    limit = peak_of_nominal(base) - 3.0
    p = problem([faulty, faulty], [HOT_INLET_C, HOT_INLET_C], (4.9,), limit, (30,))
    result = engineer_plan(p, EngineerSettings(rest_step_s=10.0))
    rest = result.schedule.rest_before_s[0]
    assert result.feasible and rest > 0 and rest % 10.0 == 0.0
    assert predict(p, Schedule(np.zeros((2, 1)), np.array([rest - 10.0]))).outputs.max() > limit
    assert rest <= heuristic_plan(p).schedule.added_rest_s


def test_infeasible_is_reported_not_hidden(generators):
    faulty, _ = generators
    p = problem([faulty, faulty], [HOT_INLET_C, HOT_INLET_C], (4.9,), 60.0, (30,))
    p.max_rest_s = 600.0
    result = engineer_plan(p)
    assert not result.feasible and result.peak_C > 60.0 and "no rest up to 10 min" in result.warnings[0]
