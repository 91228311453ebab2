"""Extended Kalman filter with disturbance heat flows, against plants that are not its model."""

import dataclasses

import numpy as np
import pytest

from genthermal.errors import InputError
from genthermal.machines import Sensor
from genthermal.estimation.ekf import ExtendedKalmanFilter
from genthermal.estimation.prediction import prediction_study
from genthermal.measurements import dataframe_to_measurements
from genthermal.mission import load_mission
from genthermal.model import ThermalModel
from genthermal.synth import synthesize

DT_S = 10.0


@pytest.fixture(scope="module")
def ekf(plant_model):
    return ExtendedKalmanFilter(plant_model, DT_S)


def test_transition_is_the_simulation_step_and_its_jacobian_is_exact(ekf, plant_model):
    rng = np.random.default_rng(0)
    step = plant_model.discretise(DT_S).step
    u = plant_model.input_vector(6.5, 6.5, 6.5, 0.97, 25.0, 22.0)
    nx, nd = plant_model.n_states, len(ekf.disturbance_names)
    z = np.concatenate([40 + 50 * rng.random(nx), np.zeros(nd)])
    z_next, F = (np.asarray(v) for v in ekf.transition(z, u))
    # no disturbance: exactly the step simulate() takes
    assert np.max(np.abs(z_next.ravel()[:nx] - np.asarray(step(z[:nx], u)).ravel())) < 1e-12
    z[nx:] = 30.0 * rng.standard_normal(nd)
    z_next, F = (np.asarray(v) for v in ekf.transition(z, u))
    for j in range(len(z)):  # central differences of the same step
        dz = np.zeros(len(z))
        dz[j] = 1e-3
        column = (np.asarray(ekf.transition(z + dz, u)[0]) - np.asarray(ekf.transition(z - dz, u)[0])).ravel() / 2e-3
        assert np.allclose(F[:, j], column, rtol=1e-6, atol=1e-9)
    assert np.all(np.any(np.abs(F[:nx, nx:]) > 0, axis=0))  # every disturbance heats its node


def test_predictions_are_offset_free_under_an_effect_the_model_lacks(plant_model, ekf):
    """At constant load a missing effect is a constant model error: the disturbances absorb it,
    so the 60-min prediction lands on the plant, while the open loop stays off."""
    plant = plant_model.with_effect("coolant_flow_reduction", k_flow=0.7)
    data = dataframe_to_measurements(synthesize(plant, load_mission("step_rated").to_inputs(DT_S), seed=3), "step")
    study = prediction_study(plant_model, data, starts_min=(60,), kalman=ekf, every_min=30)
    late = study.horizon_start_indices >= 6 * 120  # two hours in: the disturbance has settled
    errors = study.horizon_errors["prediction"]["60"][late]
    open_loop = study.horizon_errors["open_loop"]["60"][late]
    assert np.max(np.abs(errors)) < 0.1 * np.min(np.abs(open_loop)) and np.min(np.abs(open_loop)) > 4.0
    assert study.filter_result.disturbances[-1, 0] > 5.0  # heat the model does not remove from the winding


def test_linear_design_model_and_missing_samples(design_model):
    ekf = ExtendedKalmanFilter(design_model, DT_S)
    data = dataframe_to_measurements(synthesize(design_model, load_mission("step_rated").to_inputs(DT_S), seed=2), "s")
    sensors = data.sensors.copy()
    sensors.iloc[50:80] = np.nan
    result = ekf.run(data.frame[["time_s", *design_model.input_names]], sensors)
    assert np.array_equal(result.states[51:80], result.predicted_states[51:80])  # prediction only
    assert np.all(result.gains[50:80] == 0) and np.all(np.isfinite(result.states))
    assert set(result.to_pandas().columns) >= {"q_stator_winding_W", "q_stator_iron_W"}


def test_bad_inputs_name_the_field(plant_model, ekf):
    with pytest.raises(InputError, match="dt_s"):
        ExtendedKalmanFilter(plant_model, 900.0)  # cannot be discretised accurately
    with pytest.raises(InputError, match="dt_s"):
        ExtendedKalmanFilter(plant_model, -1.0)
    with pytest.raises(InputError, match="disturbance_nodes"):
        ExtendedKalmanFilter(plant_model, DT_S, disturbance_nodes=["no_such_node"])
    with pytest.raises(InputError, match="disturbance_drift_W"):
        ExtendedKalmanFilter(plant_model, DT_S, disturbance_drift_W=-1.0)
    with pytest.raises(InputError, match="inlet_drift_K"):
        ExtendedKalmanFilter(plant_model, DT_S, inlet_drift_K=float("nan"))
    with pytest.raises(InputError, match="change_threshold"):
        ExtendedKalmanFilter(plant_model, DT_S, change_threshold=0.0)
    with pytest.raises(InputError, match="change_window_min"):
        ExtendedKalmanFilter(plant_model, DT_S, change_window_min=0.05)  # shorter than one 10-s step
    with pytest.raises(InputError, match="jump_std"):
        ExtendedKalmanFilter(plant_model, DT_S, jump_std={"blockage": 5.0})
    with pytest.raises(InputError, match="P"):
        ekf.update(np.zeros(10), None, [20.0, 20.0])
    # a model of another machine: its sensors are not in the data
    other = ThermalModel(plant_model.network, plant_model.parameters,
                         dataclasses.replace(plant_model.spec, interface=dataclasses.replace(
                               plant_model.spec.interface, sensors=(plant_model.spec.interface.sensors[0],
                                                                    Sensor("T_rotor", "rotor", ("T_rotor",), 0.01)))))
    data = dataframe_to_measurements(synthesize(plant_model, load_mission("step_rated").to_inputs(DT_S)), "s")
    with pytest.raises(InputError, match="T_rotor"):
        prediction_study(other, data, starts_min=(60,))
    with pytest.raises(InputError, match="longest horizon"):
        prediction_study(plant_model, data.frame.iloc[:300], starts_min=(20,))


@pytest.mark.slow
def test_compiled_ekf_update_and_prediction_equal_python(plant_model, ekf):
    from genthermal.codegen import model_library
    from genthermal.errors import CompilerNotFoundError
    from genthermal.estimation.change_detection import change_step
    from genthermal.estimation.ekf import embedded_functions

    functions = embedded_functions(plant_model, DT_S, predict_steps=30)
    try:
        library = model_library(plant_model, dt_s=DT_S, prefix="gte", extra_functions=functions)
    except CompilerNotFoundError as exc:
        pytest.skip(str(exc))
    disturbances = np.resize([12.0, -4.0, 6.0, 3.0, 9.0, -2.0, 1.5], len(ekf.disturbance_names))
    z = np.concatenate([np.linspace(40.0, 90.0, plant_model.n_states), disturbances])
    P = ekf.P0 * 0.3 + 0.01
    u = plant_model.input_vector(6.0, 6.0, 6.0, 0.93, 22.0, 21.0)
    S = ekf.H @ P @ ekf.H.T + ekf.R
    close = ekf.H @ z + ekf.e + np.array([0.05, -0.03])  # a reading the filter expects
    far, biased = np.array([85.0, 60.0]), np.array([3.0, -2.0])  # a biased one after a biased history
    cases = (([1.0, 1.0], close, np.zeros(2), False), ([1.0, 0.0], far, np.zeros(2), False),
             ([1.0, 1.0], far, biased, True), ([0.0, 1.0], far, biased, False))  # a missing sensor: no test
    for measured, y, mean, fires in cases:
        compiled = library.call("ekf_update", z, P, u, y, np.array(measured), mean)
        step = ekf.update(z, P, np.where(np.array(measured) == 1, y, np.nan))
        mean_next, statistic, alarm = change_step(mean, step.innovation, S, ekf.change_window_samples,
                                                  ekf.change_threshold)
        P_filtered = step.P + ekf.jump_covariance if alarm else step.P
        z_next, P_next = ekf.predict(step.x, P_filtered, u)
        assert alarm == fires
        for c_value, python in zip(compiled, (step.x, P_filtered, z_next, P_next, mean_next, np.array(statistic))):
            assert np.max(np.abs(np.asarray(c_value).reshape(python.shape) - python)) < 1e-9
    U = np.tile(u[:, None], (1, 30))
    expected = ekf.forecast(z_next, np.hstack([U, U[:, :1]]))[1:].T  # outputs after each step
    assert np.max(np.abs(library.call("ekf_predict", z_next, U) - expected)) < 1e-9


def test_load_scaled_losses_act_with_the_load_squared_and_not_at_rest(plant_model, ekf):
    nx = plant_model.n_states
    z = np.concatenate([np.full(nx, 60.0), np.zeros(len(ekf.disturbance_names))])
    load = ekf.state_names.index("q_load_" + plant_model.spec.sensors["T_winding"])
    constant = ekf.state_names.index("q_" + plant_model.spec.sensors["T_winding"])
    rises = {}
    for current in (0.0, 3.5, 7.0):
        u = plant_model.input_vector(current, current, current, 0.8, 25.0, 22.0)
        base = np.asarray(ekf.transition(z, u)[0]).ravel()[:nx]
        with_load, with_constant = z.copy(), z.copy()
        with_load[load], with_constant[constant] = 40.0, 40.0
        rises[current] = [np.max(np.asarray(ekf.transition(state, u)[0]).ravel()[:nx] - base)
                          for state in (with_load, with_constant)]
    assert rises[0.0][0] == 0.0 and rises[7.0][0] > 0  # no load, no loss
    np.testing.assert_allclose(rises[3.5][0] / rises[7.0][0], (3.5 / 7.0) ** 2, rtol=1e-2)  # not 0.5: squared
    np.testing.assert_allclose(rises[7.0][0], rises[7.0][1], rtol=1e-2)  # at rated current: W for W


def test_coolant_scaled_heat_flow_grows_with_the_rise_above_the_inlet_and_the_inlet_offset_heats(plant_model, ekf):
    """q_coolant_<node> is W at COOLANT_REFERENCE_RISE_K above the inlet: it acts in proportion
    to the node's rise; dT_inlet acts as that much hotter coolant."""
    from genthermal.estimation.ekf import COOLANT_REFERENCE_RISE_K

    nx = plant_model.n_states
    coolant = ekf.state_names.index("q_coolant_" + plant_model.spec.sensors["T_winding"])
    winding = plant_model.state_names.index(plant_model.spec.sensors["T_winding"])
    u = plant_model.input_vector(5.0, 5.0, 5.0, 0.9, 20.0, 20.0)
    steps = {}
    for rise in (COOLANT_REFERENCE_RISE_K / 2, COOLANT_REFERENCE_RISE_K):
        z = np.concatenate([np.full(nx, 20.0 + rise), np.zeros(len(ekf.disturbance_names))])
        base = np.asarray(ekf.transition(z, u)[0]).ravel()[winding]
        z[coolant] = 40.0
        steps[rise] = np.asarray(ekf.transition(z, u)[0]).ravel()[winding] - base
    np.testing.assert_allclose(steps[COOLANT_REFERENCE_RISE_K / 2] / steps[COOLANT_REFERENCE_RISE_K], 0.5, rtol=1e-6)
    z = np.concatenate([np.full(nx, 60.0), np.zeros(len(ekf.disturbance_names))])
    hotter = z.copy()
    hotter[ekf.state_names.index("dT_inlet")] = 10.0
    u_hot = u.copy()
    u_hot[plant_model.input_names.index(plant_model.spec.interface.coolant_input)] += 10.0
    np.testing.assert_allclose(np.asarray(ekf.transition(hotter, u)[0]).ravel()[:nx],
                               np.asarray(ekf.transition(z, u_hot)[0]).ravel()[:nx], atol=1e-12)


def _constant_winding_heat(plant_model, watts: float):
    """The model with a constant heat flow into the stator winding that the model does not have."""
    from genthermal.effects import Effect, EffectParameter, apply_effect
    from genthermal.network import HeatSource

    effect = Effect("test_constant_winding_heat", "constant unmodelled heat into the winding", r"q_w \mathrel{+}= q",
                    (EffectParameter("q", 0.0, "W", 0.0, 100.0, 20.0),),
                    lambda network, roles, q: network.with_heat_sources([HeatSource("stator_winding", q, "test")]))
    return apply_effect(plant_model, effect, q=watts)


def _horizon_rms(study, which: str, first_start_min: float = 0.0) -> dict:
    keep = study.horizon_start_indices >= first_start_min * 60.0 / DT_S
    return {h: float(np.sqrt(np.nanmean(errors[keep, 0] ** 2))) for h, errors in study.horizon_errors[which].items()}


def test_disturbance_states_make_prediction_offset_free_under_a_constant_unmodelled_heat_flow(plant_model, ekf):
    """25 W into the winding that the model lacks (the open loop runs several K cold): once the
    disturbance has been learnt, the predictions at every horizon are at most a third of the open
    loop's error, across the load steps of the varying-load mission."""
    plant = _constant_winding_heat(plant_model, 25.0)
    data = dataframe_to_measurements(synthesize(plant, load_mission("varying_load").to_inputs(DT_S), seed=5), "q")
    study = prediction_study(plant_model, data, starts_min=(60,), kalman=ekf)
    prediction, open_loop = _horizon_rms(study, "prediction", 60.0), _horizon_rms(study, "open_loop", 60.0)
    for horizon in ("15", "30", "60"):
        assert open_loop[horizon] > 2.0
        assert prediction[horizon] < open_loop[horizon] / 3.0, (horizon, prediction, open_loop)


def test_disturbance_states_cost_little_on_a_matched_plant(plant_model, ekf):
    """Plant = model: the open loop is off only by the current noise, and the prediction from the
    filtered state, with disturbances learnt from noise, may add at most 0.1 K RMS at any horizon
    (twice the 0.05 K noise of the averaged winding reading, thesis eq. 6.10: 0.0082 K² per PT100,
    three averaged). With the flight filter's fast random walks (8 and 15 W per hour) it is worse."""
    data = dataframe_to_measurements(synthesize(plant_model, load_mission("varying_load").to_inputs(DT_S), seed=6), "m")
    study = prediction_study(plant_model, data, starts_min=(60,), kalman=ekf)
    prediction, open_loop = _horizon_rms(study, "prediction"), _horizon_rms(study, "open_loop")
    for horizon in ("15", "30", "60"):
        assert prediction[horizon] <= open_loop[horizon] + 0.1, (horizon, prediction, open_loop)
    from genthermal.schedule.state_estimator import FLIGHT_EKF_SETTINGS

    fast = prediction_study(plant_model, data, starts_min=(60,),
                            kalman=ExtendedKalmanFilter(plant_model, DT_S, **FLIGHT_EKF_SETTINGS))
    assert _horizon_rms(fast, "prediction")["60"] > prediction["60"]


def test_change_test_opens_the_disturbance_covariance_on_a_blockage_only(plant_model, ekf):
    """The innovation change test fires within half an hour of a coolant blockage (on this plant,
    the model itself, the blockage's open-loop error grows more slowly than on the rig plants of
    bench_prediction, where it fires after 9 min) and never on the healthy record of the mission."""
    from genthermal.commands.synth import apply_scenario_faults

    inputs, switches, _ = apply_scenario_faults(plant_model, load_mission("blockage_large"), DT_S, 1)
    frame = synthesize(plant_model, inputs, seed=7, switches=switches)
    healthy = synthesize(plant_model, load_mission("blockage_large").to_inputs(DT_S), seed=7)
    alarms = {}
    for name, record in (("blockage", frame), ("healthy", healthy)):
        data = dataframe_to_measurements(record, name)
        result = ekf.run(data.frame[["time_s", *plant_model.input_names]], data.sensors)
        alarms[name] = [t / 60.0 for t in result.change_alarm_times_s]
    assert alarms["healthy"] == []
    assert alarms["blockage"] and 66.0 <= alarms["blockage"][0] <= 96.0, alarms
