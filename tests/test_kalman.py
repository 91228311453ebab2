"""Kalman filter and n-step prediction (thesis 6.2-6.3) on synthetic data from a mismatched plant."""

import matplotlib.pyplot as plt
import numpy as np
import pytest

from genthermal.errors import CompilerNotFoundError, InputError
from genthermal.estimation.kalman import KalmanFilter, measurement_noise_covariance
from genthermal.estimation.prediction import improved_period, prediction_study
from genthermal.measurements import WINDING_SENSORS, dataframe_to_measurements
from genthermal.mission import load_mission
from genthermal.simulate import simulate
from genthermal.synth import synthesize

#: Plant ≠ design model: parameter factors of the brief (thesis 6.3 used the real rig).
MISMATCH = {"h_end_air": 0.85, "h_top_air": 1.1, "R0": 1.05, "P_iron": 1.2}
OUTPUTS = ["T_winding", "T_iron"]


@pytest.fixture(scope="module")
def plant(plant_model):
    values = {name: plant_model.parameters.value(name) * factor for name, factor in MISMATCH.items()}
    return plant_model.with_parameters(provenance="assumed", source="mismatched test plant", **values)


@pytest.fixture(scope="module")
def mission_inputs():
    return load_mission("thesis_fig_7_7").to_inputs(10.0)


@pytest.fixture(scope="module")
def truth(plant, mission_inputs):
    return simulate(plant, mission_inputs)


@pytest.fixture(scope="module")
def data(plant, mission_inputs):
    return dataframe_to_measurements(synthesize(plant, mission_inputs, seed=7), "synthetic thesis_fig_7_7")


@pytest.fixture(scope="module")
def kalman(design_model):
    return KalmanFilter(design_model, 10.0)


@pytest.fixture(scope="module")
def study(design_model, data, kalman):
    return prediction_study(design_model, data, kalman=kalman)


def test_filter_corrects_the_mismatch_to_within_1_K(study, truth, design_model):
    result = study.filter_result
    filtered_error = result.outputs - truth[OUTPUTS].to_numpy()
    assert np.max(np.abs(filtered_error)) <= 1.0  # thesis 6.3.1: no error greater than 1 °C
    assert max(study.filter_rmse.values()) < 0.2
    assert min(study.open_loop_rmse.values()) > 2.0  # the mismatch is real: the open loop is off
    # the unmeasured nodes (rotor, shaft, end windings, frame) are estimated too, after 10 min
    states = truth[[f"T_{name}" for name in design_model.state_names]].to_numpy()
    assert np.max(np.abs(result.states[60:] - states[60:])) < 1.5


def test_prediction_beats_open_loop_for_at_least_20_minutes(study):
    improved = study.to_json()["improved_minutes"]
    assert list(improved) == ["50", "75", "100", "125", "150", "175"]
    for start, per_sensor in improved.items():
        for sensor, minutes in per_sensor.items():
            assert minutes >= 20.0, (start, sensor, minutes)  # thesis 6.3.2
    # a prediction from the filtered state starts far closer to the measurement than the open loop
    k = study.start_indices[100.0]
    measured = study.filter_result.measured[k]
    assert np.all(np.abs(study.predictions[100.0][0] - measured) < 0.5)
    assert np.all(np.abs(study.open_loop[k] - measured) > 1.0)


def test_improved_period_definition():
    open_loop = np.full(100, -2.0)
    prediction = -2.0 * (1 - np.exp(-np.arange(100) / 20.0))
    samples, censored = improved_period(prediction, open_loop, window_samples=1, margin_K=0.25)
    assert not censored and samples == int(np.ceil(-20 * np.log(0.125)))  # 2 e^{-k/20} <= 0.25
    samples, censored = improved_period(prediction, open_loop, window_samples=1, margin_K=0.0)
    assert censored and samples == 99  # never reaches the open loop: a lower bound, flagged


def test_steady_state_gain_is_the_limit_of_the_time_varying_gain(kalman, data):
    steady = kalman.steady_state_gain()
    assert steady.shape == (8, 2)
    time_varying = kalman.run(data.frame, data.sensors)
    assert np.abs(time_varying.gains[-1] - steady).max() < 1e-4 * np.abs(steady).max()
    assert np.abs(time_varying.gains[10] - steady).max() > 0.1 * np.abs(steady).max()
    constant = kalman.run(data.frame, data.sensors, steady_state=True)
    assert np.allclose(constant.gains, steady)
    assert np.allclose(constant.outputs[-100:], time_varying.outputs[-100:], atol=1e-3)


@pytest.mark.parametrize("steady_state", [False, True])
def test_missing_measurements_are_skipped_and_counted(kalman, data, truth, steady_state):
    sensors = data.sensors.copy()
    sensors.loc[300:359, OUTPUTS] = np.nan  # ten minutes without any measurement
    sensors.loc[700:759, "T_iron"] = np.nan  # ten minutes without the iron sensor
    result = kalman.run(data.frame, sensors, steady_state=steady_state)
    assert result.samples_without_measurement == 60
    assert result.missing_counts == {"T_winding": 60, "T_iron": 120}
    assert np.array_equal(result.states[300:360], result.predicted_states[300:360])  # prediction only
    assert np.all(np.isnan(result.innovations[300:360]))
    assert np.all(result.gains[700:760, :, 1] == 0) and np.all(result.gains[700:760, :, 0] != 0)
    assert np.all(np.isfinite(result.states))
    assert np.max(np.abs(result.outputs - truth[OUTPUTS].to_numpy())) < 2.0


def test_estimated_measurement_noise_recovers_the_injected_variances(kalman, data):
    per_sensor = np.diag(measurement_noise_covariance(data.frame[[*WINDING_SENSORS, "T_iron"]]))
    assert per_sensor == pytest.approx([0.0082, 0.0082, 0.0082, 0.013], rel=0.2)
    # the filter's winding measurement is the mean of the three phase sensors
    R = kalman.estimate_measurement_noise(data.sensors)
    assert np.diag(R) == pytest.approx([0.0082 / 3, 0.013], rel=0.2)
    assert R[0, 1] == 0


def test_casadi_update_and_prediction_match_the_filter(kalman, data):
    x_pred = np.linspace(40, 75, 8)
    u = data.frame[list(kalman.model.input_names)].to_numpy()[500]
    y = np.array([71.0, 54.0])
    x_filtered, x_next = (np.asarray(v).ravel() for v in kalman.update_function()(x_pred, u, y))
    step = kalman.update(x_pred, None, y)
    assert np.allclose(x_filtered, step.x) and np.allclose(x_next, kalman.predict(step.x, None, u)[0])
    U = data.frame[list(kalman.model.input_names)].to_numpy()[500:530].T
    Y = np.asarray(kalman.predict_function(30)(x_filtered, U))
    x, expected = x_filtered, []
    for k in range(30):
        x, _ = kalman.predict(x, None, U[:, k])
        expected.append(kalman.C @ x + kalman.e)
    assert np.allclose(Y.T, expected)


def test_results_as_frames_json_and_figures(study, design_model):
    frame = study.filter_result.to_pandas()
    for name in ["time_s", *(f"T_{s}" for s in design_model.state_names), "T_winding", "T_iron",
                 "measured_T_winding", "innovation_T_iron"]:
        assert name in frame.columns
    report = study.to_json()
    assert set(report["filter_rmse"]) == set(report["open_loop_rmse"]) == set(OUTPUTS)
    for figure in (study.plot(), study.filter_result.plot()):
        assert len(figure.axes) >= 2
        plt.close(figure)


def test_bad_settings_are_refused(design_model, plant_model, data):
    with pytest.raises(InputError, match="affine"):
        KalmanFilter(plant_model)
    with pytest.raises(InputError, match="Q"):
        KalmanFilter(design_model, Q=np.ones(3))
    with pytest.raises(InputError, match="positive definite"):
        KalmanFilter(design_model, R=[0.0, 0.013])
    with pytest.raises(InputError, match="resample"):
        KalmanFilter(design_model, dt_s=5.0).run(data.frame, data.sensors)
    with pytest.raises(InputError, match="starts_min.*beyond the data"):
        prediction_study(design_model, data, starts_min=(50, 300))
    with pytest.raises(InputError, match="starts_min"):
        prediction_study(design_model, data, starts_min=(-5,))


def test_compiled_update_and_prediction_equal_python(design_model, kalman, data):
    from genthermal.codegen import model_library

    functions = {"kalman_update": kalman.update_function(), "predict_30": kalman.predict_function(30)}
    try:
        library = model_library(design_model, dt_s=10.0, prefix="gtl", extra_functions=functions)
    except CompilerNotFoundError as exc:
        pytest.skip(str(exc))
    x_pred, y = np.linspace(40, 75, 8), np.array([71.0, 54.0])
    inputs = data.frame[list(design_model.input_names)].to_numpy()
    x_filtered, x_next = library.call("kalman_update", x_pred, inputs[500], y)
    expected = functions["kalman_update"](x_pred, inputs[500], y)
    assert np.allclose(x_filtered, np.asarray(expected[0]).ravel(), rtol=0, atol=1e-10)
    assert np.allclose(x_next, np.asarray(expected[1]).ravel(), rtol=0, atol=1e-10)
    U = inputs[500:530].T
    assert np.allclose(library.call("predict_30", x_filtered, U), np.asarray(functions["predict_30"](x_filtered, U)),
                       rtol=0, atol=1e-10)
