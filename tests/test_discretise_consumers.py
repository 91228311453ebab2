"""One owner of time stepping: every consumer steps the same mission to the same temperatures.

The mission (three load levels on the affine design model, inputs from the schedulers' load path)
is stepped by ``simulate``, calibration's parametric simulator, the Kalman filter and the EKF
(predict only), the generated C library, the schedulers' design generator and the MILP's
prediction matrices, at several step lengths (7 s does not divide the 900 s and 600 s segments).
All must agree with ``simulate`` to 1e-9 K: they share :mod:`genthermal.discretise`.
"""

import numpy as np
import pandas as pd
import pytest

from genthermal.codegen import model_library
from genthermal.diagnose.trajectory import ParametricSimulator
from genthermal.errors import CompilerNotFoundError
from genthermal.estimation.ekf import ExtendedKalmanFilter
from genthermal.estimation.kalman import KalmanFilter
from genthermal.schedule.planning.milp import _segment_maps
from genthermal.schedule.planning.plan import PlanningProblem, Segment
from genthermal.schedule.power_system import AffineGenerator
from genthermal.simulate import simulate

#: Agreement required between consumers, K.
TOLERANCE_K = 1e-9
#: (duration s, phase current A): above the design model's loss floor (1.6 A) throughout.
MISSION = ((900.0, 5.5), (600.0, 3.0), (1200.0, 6.5))
INLET_C, AMBIENT_C, START_C = 40.0, 30.0, 35.0
STEPS_S = (10.0, 60.0, 7.0)


@pytest.fixture(scope="module")
def generator(design_model):
    return AffineGenerator(design_model)


def _grid_inputs(generator, dt_s):
    """Inputs sampled every ``dt_s`` over the mission (the value at t_k is held over the step)."""
    ends = np.cumsum([duration for duration, _ in MISSION])
    time_s = np.arange(0.0, ends[-1], dt_s)
    current = np.array([current for _, current in MISSION])[np.searchsorted(ends, time_s, side="right")]
    U = generator.input(current, INLET_C, AMBIENT_C)
    frame = pd.DataFrame(U, columns=list(generator.model.input_names))
    frame.insert(0, "time_s", time_s)
    return frame, U.T


@pytest.fixture(scope="module", params=STEPS_S, ids=lambda dt: f"dt{dt:g}")
def mission(request, design_model, generator):
    """``(dt_s, inputs frame, U (n_inputs × N), simulate's states (n_states × N), outputs)``."""
    dt_s = request.param
    frame, U = _grid_inputs(generator, dt_s)
    reference = simulate(design_model, frame, x0=START_C)
    X = reference[[f"T_{name}" for name in design_model.state_names]].to_numpy().T
    Y = reference[list(design_model.output_names)].to_numpy().T
    return dt_s, frame, U, X, Y


def test_the_mission_has_a_step_that_does_not_divide_a_segment():
    assert any(duration % dt for duration, _ in MISSION for dt in STEPS_S)


def test_calibration_simulator_steps_like_simulate(design_model, mission):
    dt_s, _, U, _, Y = mission
    simulator = ParametricSimulator(design_model, dt_s, U, ["h_end_air"])
    outputs = simulator.outputs([design_model.parameters.value("h_end_air")], [0.0, START_C], simulator.indicator())
    assert np.max(np.abs(outputs - Y)) < TOLERANCE_K


def test_kalman_and_extended_kalman_predictions_step_like_simulate(design_model, mission):
    dt_s, _, U, X, _ = mission
    kalman = KalmanFilter(design_model, dt_s)
    ekf = ExtendedKalmanFilter(design_model, dt_s)
    x = np.full(design_model.n_states, START_C)
    z = np.concatenate([x, np.zeros(len(ekf.disturbance_names))])
    for k in range(U.shape[1] - 1):
        x, _ = kalman.predict(x, None, U[:, k])
        z, _ = ekf.predict(z, None, U[:, k])
        assert np.max(np.abs(x - X[:, k + 1])) < TOLERANCE_K
        assert np.max(np.abs(z[:design_model.n_states] - X[:, k + 1])) < TOLERANCE_K


def test_generated_c_steps_like_simulate(design_model, mission):
    dt_s, _, U, X, _ = mission
    try:
        library = model_library(design_model, dt_s, prefix="gtd")
    except CompilerNotFoundError as error:
        pytest.skip(f"no C compiler: {error}")
    states = library.simulate(np.full(design_model.n_states, START_C), U[:, :-1].T)
    assert np.max(np.abs(states.T - X[:, 1:])) < TOLERANCE_K


def test_scheduler_design_generator_steps_like_simulate(generator, mission):
    dt_s, _, U, X, Y = mission
    E, G = generator.step(dt_s)
    x = np.full(X.shape[0], START_C)
    for k in range(U.shape[1] - 1):
        assert np.max(np.abs(generator.outputs(x, U[:, k]) - Y[:, k])) < TOLERANCE_K
        x = E @ x + G @ generator.forcing(U[:, k])
        assert np.max(np.abs(x - X[:, k + 1])) < TOLERANCE_K


@pytest.mark.parametrize("check_s", STEPS_S)
def test_milp_prediction_matrices_step_like_simulate(design_model, generator, check_s):
    """The MILP's affine maps of each segment (windows of 300 s, checks every <= ``check_s``)
    against ``simulate`` on the same substeps, segment after segment."""
    segments = tuple(Segment(k, f"s{k}", duration, ((0.0, current),)) for k, (duration, current) in enumerate(MISSION))
    problem = PlanningProblem(segments, [generator], np.full((1, design_model.n_states), START_C),
                              np.array([INLET_C]), AMBIENT_C, 1.911, 7.0, limit_C=150.0, window_s=300.0)
    start = problem.x0[0]
    for k, segment in enumerate(segments):
        (P_y, phi_y, _), (P, phi, _) = _segment_maps(problem, 0, k, check_s)
        window_s = segment.windows(problem.window_s)[0][1]
        substep_s = window_s / max(int(np.ceil(window_s / check_s - 1e-9)), 1)
        n = int(round(segment.duration_s / substep_s))
        frame = pd.DataFrame(np.tile(problem.inputs(0, segment.levels[0][1]), (n + 1, 1)),
                             columns=list(design_model.input_names))
        frame.insert(0, "time_s", np.arange(n + 1) * substep_s)
        reference = simulate(design_model, frame, x0=start)
        expected_y = reference[list(design_model.output_names)].to_numpy()[1:].ravel()
        assert np.max(np.abs(P_y @ start + phi_y - expected_y)) < TOLERANCE_K
        end = reference[[f"T_{name}" for name in design_model.state_names]].to_numpy()[-1]
        assert np.max(np.abs(P @ start + phi - end)) < TOLERANCE_K
        start = end


def test_rest_of_whole_blocks_and_of_free_length_step_like_simulate(design_model, generator):
    """The MILP's rest (Φ^n from the step of n blocks) and the optimal scheduler's rest of free
    length (modal decay) against ``simulate``, at a low load above the design model's loss floor
    (where the planner's affine branch and the model are the same)."""
    block_s, n_blocks = 300.0, 4
    u_rest = generator.input(3.0, INLET_C, AMBIENT_C)
    steady = generator.steady_state(u_rest)
    hot = np.linspace(80.0, 120.0, design_model.n_states)
    frame = pd.DataFrame(np.tile(u_rest, (n_blocks + 1, 1)), columns=list(design_model.input_names))
    frame.insert(0, "time_s", np.arange(n_blocks + 1) * block_s)
    reference = simulate(design_model, frame, x0=hot)
    X = reference[[f"T_{name}" for name in design_model.state_names]].to_numpy()
    for n in range(n_blocks + 1):
        blocks = generator.step(n * block_s)[0] @ (hot - steady) + steady
        free = generator.decay.apply(hot - steady, n * block_s) + steady
        assert np.max(np.abs(blocks - X[n])) < TOLERANCE_K
        assert np.max(np.abs(free - X[n])) < TOLERANCE_K
