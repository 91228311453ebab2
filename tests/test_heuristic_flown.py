"""The thesis heuristic on the flown (nonlinear) model: its least displacement, its rooms, its
agreement with the affine heuristic where the flown model is affine, and a closed-loop flight."""

import dataclasses

import numpy as np
import pytest

from genthermal.estimation.ekf import ExtendedKalmanFilter
from genthermal.mission import load_mission
from genthermal.schedule.flight.closed_loop import fly
from genthermal.schedule.planning.flown import FlownPlanning
from genthermal.schedule.planning.heuristic import heuristic_plan
from genthermal.schedule.planning.heuristic_flown import ROOT_TOLERANCE_A, ROOT_TOLERANCE_K, FlownSegmentResponse, _least_feasible
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.planning.plan import PlanningProblem, Segment, predict
from genthermal.schedule.power_system import AffineGenerator, PowerSystem
from genthermal.schedule.flight.replanning import flight_segments

BLOCKAGE = {"k_flow": 0.2, "n_flow": 0.0}
INLETS_C = np.array([51.0, 20.0])  # the faulty generator's inlet after the large blockage (thesis 7.3.3)
#: Two K-conditions with a 5-min start-up level each (thesis Table 3.2's shape).
SEGMENTS = (Segment(4, "5 cruise", 1800.0, ((0.0, 5.8), (300.0, 4.9))),
            Segment(5, "6 cruise_combat", 1800.0, ((0.0, 6.1), (300.0, 5.1))))


def _problem(generators, x0, limit_C, flown, rest_current_A=1.911, inlets_C=INLETS_C):
    return PlanningProblem(SEGMENTS, generators, np.asarray(x0), inlets_C, 20.0, rest_current_A, 10.5,
                           limit_C=limit_C, max_rest_s=3600.0, dt_s=10.0, window_s=300.0, flown=flown)


def _flown(filters, x0, P0):
    nd = len(filters[0].disturbance_names)
    return FlownPlanning(list(filters), [np.concatenate([x, np.zeros(nd)]) for x in x0], P0)


def test_least_feasible_finds_the_boundary_of_a_decreasing_function():
    calls = []

    def breach(d):
        calls.append(d)
        return 5.0 - d ** 2
    d = _least_feasible(breach, 0.0, 4.0)
    assert breach(d) <= 0.0
    assert breach(d) >= -ROOT_TOLERANCE_K or d - np.sqrt(5.0) <= ROOT_TOLERANCE_A
    assert len(calls) < 20


def test_agrees_with_the_affine_heuristic_when_the_flown_model_is_the_design_model(design_model):
    """The flown model is the design model itself and its filters have no uncertainty: the
    bracketed search on it must find the affine heuristic's rests and displacements (the rest
    current is 2.2 A: at 1.911 A the design model's loss floor is active in the end winding).
    Gen1 blocked with a 35 °C inlet, gen2 coming off 7.5 A: both need a 5-min rest before the
    first K-condition, and gen1 sheds load in the second."""
    faulty = design_model.with_effect("coolant_flow_reduction", **BLOCKAGE)
    generators = [AffineGenerator(faulty), AffineGenerator(design_model)]
    quiet = dict(node_heat_noise_W=0.0, disturbance_drift_W=0.0, load_scaled_drift_W=0.0, coolant_drift_W=0.0,
                 inlet_drift_K=0.0, initial_disturbance_W=0.0)
    filters = [ExtendedKalmanFilter(m, 10.0, **quiet) for m in (faulty, design_model)]
    inlets = np.array([35.0, 20.0])
    x0 = [g.steady_state(g.input(current, inlet, 20.0)) for g, current, inlet in zip(generators, (5.0, 7.5), inlets)]
    nz = len(filters[0].state_names)
    affine = heuristic_plan(_problem(generators, x0, 100.0, None, 2.2, inlets))
    flown = heuristic_plan(_problem(generators, x0, 100.0, _flown(filters, x0, np.zeros((2, nz, nz))), 2.2, inlets))
    assert affine.schedule.added_rest_s == 300.0 and affine.schedule.displaced_A[0, 1] > 0.5  # not trivial
    assert flown.feasible and affine.feasible
    np.testing.assert_array_equal(flown.schedule.rest_before_s, affine.schedule.rest_before_s)
    # the search stops within ROOT_TOLERANCE_K of the limit: a few hundredths of an ampere
    np.testing.assert_allclose(flown.schedule.displaced_A, affine.schedule.displaced_A, atol=0.02)


@pytest.fixture(scope="module")
def nonlinear_problem(plant_model, design_model):
    """Gen1 blocked and hot, gen2 healthy, planned on the nonlinear models with converged filters."""
    models = [plant_model.with_effect("coolant_flow_reduction", **BLOCKAGE), plant_model]
    filters = [ExtendedKalmanFilter(m, 10.0) for m in models]
    generators = [AffineGenerator(design_model.with_effect("coolant_flow_reduction", **BLOCKAGE)),
                  AffineGenerator(design_model)]
    x0 = [np.full(models[0].n_states, 100.0), np.full(models[1].n_states, 70.0)]
    return _problem(generators, x0, 110.0, _flown(filters, x0, [0.1 * f.P0 for f in filters]))


def test_least_displacement_is_the_least_that_keeps_the_limit(nonlinear_problem):
    problem = nonlinear_problem
    response = FlownSegmentResponse(problem, 0, 0, (problem.flown.z0[0], problem.flown.P0[0], 0), 0.0)
    assert response.peak(0.0) > problem.limit_C  # the faulty generator breaches undisplaced
    d = response.least_displacement(problem.limit_C)
    assert 0.0 < d < SEGMENTS[0].low_A
    assert response.peak(d) <= problem.limit_C
    assert response.peak(d) >= problem.limit_C - ROOT_TOLERANCE_K or \
        response.peak(d - 2 * ROOT_TOLERANCE_A) > problem.limit_C
    rested = FlownSegmentResponse(problem, 0, 0, (problem.flown.z0[0], problem.flown.P0[0], 0), 900.0)
    assert rested.least_displacement(problem.limit_C) < d  # a rested generator needs less displaced


def test_receiver_room_is_the_most_that_keeps_the_limit(nonlinear_problem):
    problem = nonlinear_problem
    response = FlownSegmentResponse(problem, 1, 1, (problem.flown.z0[1], problem.flown.P0[1], 0), 0.0)
    room = response.room(problem.limit_C)
    most = -problem.displacement_bounds(1)[0]
    assert 0.0 < room < most
    assert response.peak(-room) <= problem.limit_C
    assert response.peak(-room - 2 * ROOT_TOLERANCE_A) > problem.limit_C or \
        response.peak(-room) >= problem.limit_C - ROOT_TOLERANCE_K
    later = FlownSegmentResponse(problem, 1, 0, (problem.flown.z0[1], problem.flown.P0[1], 0), 0.0).later_room(
        problem.limit_C)
    assert 0.0 < later <= -problem.displacement_bounds(0)[0]


def test_plan_on_the_nonlinear_model_keeps_its_own_prediction_within_the_limit(nonlinear_problem):
    result = heuristic_plan(nonlinear_problem)
    assert result.feasible
    prediction = predict(nonlinear_problem, result.schedule)  # the filter's own step, with its back-off
    assert prediction.peak()[0] <= nonlinear_problem.limit_C + 0.05
    assert result.schedule.displaced_A[0].max() > 0.05  # the faulty generator is relieved
    assert result.schedule.displaced_A.shape == (2, len(SEGMENTS))  # one displacement per K-condition


def test_the_heuristic_plans_per_k_condition_on_the_nonlinear_model():
    system = PowerSystem.from_mission(load_mission("chapter7_blockage_large"))
    nonlinear = ManagerSettings(planner_model="nonlinear")
    assert len(flight_segments(system.mission, nonlinear, "heuristic")) == len(system.mission.actions)
    assert len(flight_segments(system.mission, nonlinear, "optimal")) > len(system.mission.actions)  # control intervals


def test_closed_loop_flight_on_a_plant_off_from_the_model_holds_thetamax(tmp_path):
    """One hour, gen1's coolant nearly blocked from 10 min, the plant 10 % short in end-winding
    cooling and 5 % high in resistance (the default mismatch), θmax 104 °C: the heuristic plans on
    the flown model from the command line and keeps both generators within θmax."""
    from flight_scenarios import fly_short_on_the_flown_model

    flight = fly_short_on_the_flown_model(tmp_path, "heuristic")
    assert flight["breach_s"] == 0.0 and max(flight["max_T_winding"].values()) <= 104.0
    assert flight["plans"] and all(plan["method"] == "heuristic" for plan in flight["plans"])


@pytest.mark.slow
def test_closed_loop_flight_on_the_nonlinear_model_holds_thetamax():
    """The thesis's large blockage with the heuristic predicting on the simulation model (thesis
    7.3.4: "a Kalman Filter containing the simulation model"), with the filter's back-off; the plant
    is the model here, as in the thesis's simulation (the test above flies one that differs)."""
    system = dataclasses.replace(PowerSystem.from_mission(load_mission("chapter7_blockage_large")), filter="ekf")
    result = fly(system, "heuristic", ManagerSettings(planner_model="nonlinear"))
    dt = np.diff(result.time_s)
    assert np.sum(dt[np.max(result.temperatures_C[:, 0, 1:], axis=0) > system.limit_C]) == 0.0
    moved = [np.max(result.nominal_A[(result.action_index == k) & ~result.resting]
                    - result.currents_A[0, (result.action_index == k) & ~result.resting], initial=0.0)
             for k in (5, 6, 7)]
    assert min(moved) > 0.05  # load displaced off gen1 in cruise/combat, the cruise after and landing
    assert all(plan["method"] == "heuristic" for plan in result.plans)


def test_schedulers_defined_on_the_design_model_refuse_the_flown_model():
    """The engineer's heuristic and the MILP plan on the design model: asked to plan on the flown
    one, the flight names the field and the value before flying."""
    from genthermal.errors import InputError

    from genthermal.schedule.flight.open_loop import plan_mission

    system = PowerSystem.from_mission(load_mission("chapter7_blockage_large"))
    for scheduler in ("engineer", "milp"):
        for run in (fly, plan_mission):  # closed and open loop
            with pytest.raises(InputError, match="planner_model.*nonlinear.*design model"):
                run(system, scheduler, ManagerSettings(planner_model="nonlinear"))
