"""The disturbance prior a calibration leaves: learnt on one record, carried by the model file,
where an extended Kalman filter on the model starts."""

import numpy as np
import pytest

from genthermal.errors import InputError
from genthermal.estimation.disturbance_prior import DisturbancePrior, learn_disturbance_prior
from genthermal.estimation.ekf import ExtendedKalmanFilter
from genthermal.estimation.prediction import prediction_study
from genthermal.measurements import dataframe_to_measurements
from genthermal.mission import load_mission
from genthermal.model_file import load_model, save_model
from genthermal.synth import synthesize

DT_S = 10.0


@pytest.fixture(scope="module")
def lacking_plant(plant_model):
    """A plant with an iron loss that grows with the excitation current, which the model lacks."""
    return plant_model.with_effect("excitation_iron_loss", k_exc=20.0)


@pytest.fixture(scope="module")
def prior(plant_model, lacking_plant):
    """Learnt on a record that has seen both loads (the varying-load test)."""
    record = dataframe_to_measurements(synthesize(lacking_plant, load_mission("varying_load").to_inputs(DT_S),
                                                  seed=11), "varying load")
    return learn_disturbance_prior(plant_model, record, DT_S)


def test_the_prior_is_the_filters_posterior_and_narrower_than_the_default(plant_model, prior):
    ekf = ExtendedKalmanFilter(plant_model, DT_S)
    assert prior.names == ekf.disturbance_names
    iron_load = prior.names.index("q_load_stator_iron")
    assert prior.mean[iron_load] > 5.0  # the missing iron loss grows with the load
    nx = plant_model.n_states
    assert np.all(np.diag(prior.covariance) < np.diag(ekf.P0)[nx:])
    assert "varying load" in prior.source


def test_filter_starts_from_the_prior_and_the_open_loop_does_not(plant_model, lacking_plant, prior):
    model = plant_model.with_disturbance_prior(prior)
    ekf = ExtendedKalmanFilter(model, DT_S)
    bare = ExtendedKalmanFilter(model, DT_S, disturbance_prior=None)
    nx = plant_model.n_states
    assert ekf.prior_used and not bare.prior_used
    assert np.allclose(ekf.P0[nx:, nx:], prior.covariance) and np.allclose(ekf.P0[:nx, :nx], bare.P0[:nx, :nx])
    flight = dataframe_to_measurements(synthesize(lacking_plant, load_mission("thesis_fig_3_2").to_inputs(DT_S),
                                                  seed=12), "fig 3.2")
    with_prior = prediction_study(model, flight, starts_min=(20,), kalman=ekf)
    without = prediction_study(model, flight, starts_min=(20,), kalman=bare)
    assert np.allclose(with_prior.open_loop, without.open_loop)  # the reference is the bare model
    assert np.allclose(with_prior.filter_result.disturbances[0], prior.mean, atol=5.0)
    # the first hour's starts: the prior knows how the error scales with load before the flight does
    early = with_prior.horizon_start_indices < 6 * 60
    rms = {name: float(np.sqrt(np.mean(study.horizon_errors["prediction"]["60"][early, 0] ** 2)))
           for name, study in (("prior", with_prior), ("none", without))}
    assert rms["prior"] < 0.8 * rms["none"]


def test_a_prior_for_other_disturbance_states_is_not_used(plant_model, prior):
    model = plant_model.with_disturbance_prior(prior)
    flight_filter = ExtendedKalmanFilter(model, DT_S, coolant_drift_W=0.0, inlet_drift_K=0.0)
    assert not flight_filter.prior_used
    assert np.all(flight_filter.initial_state([40.0, 35.0], model.input_vector())[model.n_states:] == 0.0)


def test_model_file_round_trip_keeps_the_prior_and_a_new_fit_drops_it(plant_model, prior, tmp_path):
    model = plant_model.with_parameters(R0=1.3).with_disturbance_prior(prior)
    loaded = load_model(save_model(model, tmp_path / "calibrated.yaml"))
    assert loaded.disturbance_prior.names == prior.names
    assert np.allclose(loaded.disturbance_prior.mean, prior.mean, atol=1e-6)
    assert np.allclose(loaded.disturbance_prior.covariance, prior.covariance, atol=1e-5)
    assert loaded.parameters.value("R0") == pytest.approx(1.3)
    assert loaded.with_parameters(R0=1.2).disturbance_prior is None  # learnt with other values


def test_bad_priors_name_the_field(tmp_path):
    with pytest.raises(InputError, match="disturbance_prior.covariance"):
        DisturbancePrior(("q_a", "q_b"), [0.0, 1.0], [[1.0, 0.5], [0.0, 1.0]])
    with pytest.raises(InputError, match="disturbance_prior.mean"):
        DisturbancePrior(("q_a", "q_b"), [0.0], np.eye(2))
    with pytest.raises(InputError, match="disturbance_prior.covariance"):
        DisturbancePrior(("q_a",), [0.0], [[-1.0]])
    path = tmp_path / "bad.yaml"
    path.write_text("machine: genco_rf201a\ndisturbance_prior: {states: [q_a], mean: [1.0]}\n")
    with pytest.raises(InputError, match="disturbance_prior.covariance"):
        load_model(path)
    with pytest.raises(InputError, match="disturbance_prior"):
        ExtendedKalmanFilter(load_model("genco_rf201a"), DT_S, disturbance_prior="calibration")
