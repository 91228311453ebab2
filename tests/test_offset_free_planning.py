"""Offset-free planning: the planner's design model carries the extended Kalman filter's
disturbance heat flows (constant and load-scaled) into its predictions."""

import numpy as np
import pytest

from genthermal.errors import InputError
from genthermal.estimation.ekf import node_heat_capacities
from genthermal.schedule.planning.linearise import planning_design_model
from genthermal.schedule.state_estimator import StateEstimator, planning_generator
from genthermal.schedule.power_system import AffineGenerator


@pytest.fixture(scope="module")
def generator(plant_model):
    return AffineGenerator(planning_design_model(plant_model))


def _winding(model):
    return model.state_names.index(model.spec.sensors["T_winding"])


def test_constant_heat_flow_warms_the_steady_state_by_what_the_network_says(generator):
    model = generator.model
    heat = np.zeros(model.n_states)
    heat[_winding(model)] = 20.0
    disturbed = generator.with_disturbances(heat, np.zeros(model.n_states), 7.0)
    u = generator.input(5.0, 20.0, 20.0)
    expected = -np.linalg.solve(generator.L, heat / node_heat_capacities(model))
    np.testing.assert_allclose(disturbed.steady_state(u) - generator.steady_state(u), expected, rtol=1e-9)
    assert expected[_winding(model)] > 1.0  # 20 W into the winding is felt
    np.testing.assert_array_equal(disturbed.L, generator.L)  # dynamics and steps are shared
    assert disturbed.step(10.0)[0] is generator.step(10.0)[0]
    untouched = generator.with_disturbances(np.zeros(model.n_states), np.zeros(model.n_states), 7.0)
    np.testing.assert_allclose(untouched.forcing(u), generator.forcing(u), rtol=0, atol=1e-15)


def test_load_scaled_heat_follows_the_design_loss_line_and_is_exact_where_the_line_is(generator):
    """m (W at rated current) enters as m (aI + b)/I_rated²: exactly m I²/I_rated² at the two
    currents where the loss line crosses I², affine in I in between (the planners need that)."""
    model = generator.model
    load_heat = np.zeros(model.n_states)
    load_heat[_winding(model)] = 30.0
    disturbed = generator.with_disturbances(np.zeros(model.n_states), load_heat, 7.0)
    slope, intercept = model.parameters.value("I2_slope"), model.parameters.value("I2_intercept")
    exact = np.roots([1.0, -slope, -intercept]).real
    capacity = node_heat_capacities(model)[_winding(model)]
    for current in exact:
        u = generator.input(current, 20.0, 20.0)
        extra = (disturbed.forcing(u) - generator.forcing(u))[_winding(model)]
        assert extra * capacity == pytest.approx(30.0 * current**2 / 49.0, rel=1e-9)
    u = generator.input(np.array([3.0, 4.0, 5.0]), 20.0, 20.0)
    extra = (disturbed.forcing(u) - generator.forcing(u))[:, _winding(model)]
    assert extra[1] - extra[0] == pytest.approx(extra[2] - extra[1], rel=1e-9)  # affine in the current
    assert np.all(extra > 0)


def test_bad_disturbances_name_the_field(generator):
    n = generator.model.n_states
    with pytest.raises(InputError, match="heat_W"):
        generator.with_disturbances(np.zeros(n - 1), np.zeros(n), 7.0)
    with pytest.raises(InputError, match="load_heat_W"):
        generator.with_disturbances(np.zeros(n), np.full(n, np.nan), 7.0)
    with pytest.raises(InputError, match="rated_current_A"):
        generator.with_disturbances(np.zeros(n), np.zeros(n), 0.0)


def _fly_mismatched(plant_model, generator, filter_name, hours=1.5, dt=10.0, seed=0):
    """One generator of a plant with R0 × 1.2 and h_end_air × 0.8 flown at 90 % load with noisy
    measurements; returns the plant, its true state and the estimator at the end."""
    plant = plant_model.with_parameters("assumed", "test mismatch", R0=1.2 * plant_model.parameters.value("R0"),
                                        h_end_air=0.8 * plant_model.parameters.value("h_end_air"))
    step = plant.discretise(dt).step
    current = 0.9 * plant_model.spec.rated_current_A
    u = generator.input(current, 20.0, 20.0)
    x_true = np.full(plant.n_states, 20.0)
    estimator = StateEstimator(generator, lambda: plant_model, x_true, dt, {}, filter_name)
    rng = np.random.default_rng(seed)
    for _ in range(int(hours * 3600 / dt)):
        x_true = np.asarray(step(x_true, u)).ravel()
        estimator.predict([current], [20.0], 20.0)
        estimator.update(plant.outputs(x_true, u) + rng.normal(0.0, 0.3, 2))
    return plant, x_true, estimator


def _hour_ahead_winding_errors(plant_model, generator, fraction, dt=10.0, n=360):
    """After :func:`_fly_mismatched`, the planner's winding prediction one hour ahead at
    ``fraction`` of rated current minus the plant's, K, with the design model alone and with the
    filter's disturbance heat flows."""
    plant, x_true, estimator = _fly_mismatched(plant_model, generator, "ekf")
    u = generator.input(fraction * plant_model.spec.rated_current_A, 20.0, 20.0)
    step = plant.discretise(dt).step
    truth = x_true
    for _ in range(n):
        truth = np.asarray(step(truth, u)).ravel()
    errors = {}
    for name, model in (("alone", generator), ("offset_free", estimator.planning_generator)):
        E, G = model.step(dt)
        x = estimator.x
        for _ in range(n):
            x = E @ x + G @ model.forcing(u)
        errors[name] = float(model.outputs(x, u)[0] - plant.outputs(truth, u)[0])
    return errors


@pytest.mark.parametrize("fraction", [0.9, 0.273])
def test_plan_prediction_with_the_filter_disturbances_is_closer_to_a_mismatched_plant(plant_model, generator,
                                                                                      fraction):
    """One hour ahead at the load flown (90 %) and in the rest mode: with the EKF's heat flows the
    winding error is a fraction of the design model's alone (measured -27.1 -> -6.8 K and
    -8.3 -> +0.9 K)."""
    errors = _hour_ahead_winding_errors(plant_model, generator, fraction)
    assert abs(errors["offset_free"]) < 0.5 * abs(errors["alone"]), errors
    assert errors["alone"] < -2.0  # the mismatch matters: the design model alone is degrees too cool


def test_after_one_load_the_split_of_the_heat_flows_errs_warm_at_a_lower_load(plant_model, generator):
    """After 1.5 h at one load the filter cannot tell a constant heat flow from a load-scaled one:
    at 60 % the plan is too warm (measured +10.5 K, against -4.5 K for the design model alone),
    on the safe side. Load changes in flight separate the two."""
    errors = _hour_ahead_winding_errors(plant_model, generator, 0.6)
    assert errors["offset_free"] > 0.0 > errors["alone"], errors


def test_planning_generator_of_a_filter_without_disturbances_is_the_design_model(plant_model, generator):
    _, _, estimator = _fly_mismatched(plant_model, generator, "kf", hours=0.1)
    assert planning_generator(generator, estimator.filter, estimator.z) is generator
    _, _, ekf = _fly_mismatched(plant_model, generator, "ekf", hours=0.1)
    disturbed = ekf.planning_generator
    nx = plant_model.n_states
    nodes = ekf.filter.disturbance_nodes
    for j, node in enumerate(nodes):
        i = generator.model.state_names.index(node)
        assert disturbed.disturbance_heat_W[i] == ekf.z[nx + j]
        assert disturbed.disturbance_load_heat_W[i] == ekf.z[nx + len(nodes) + j]
