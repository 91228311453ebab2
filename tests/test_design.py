"""The linear design model (thesis 5.2) and its agreement with the nonlinear simulation model."""

import numpy as np
import pandas as pd
import pytest

from genthermal.design import current_squared_fit, linear_design_model
from genthermal.errors import InputError
from genthermal.losses import fit_current_squared


def test_current_squared_fit_reproduces_thesis_eq_5_3():
    """Thesis eq. 5.3: I^2 ~ 7.3 I - 12 (R^2 0.9764), exact near 2.4 A and 4.9 A. A uniform
    least-squares fit gives slope a+b and intercept -(a^2+4ab+b^2)/6, so the thesis line is the
    fit over about [1.66, 5.64] A."""
    fit = fit_current_squared(1.66, 5.64)
    assert fit.slope == pytest.approx(7.3, abs=0.01)
    assert fit.intercept == pytest.approx(-12.0, abs=0.05)
    low, high = fit.exact_at
    assert low == pytest.approx(2.5, abs=0.15) and high == pytest.approx(4.8, abs=0.15)
    assert 0.97 < fit.r_squared < 0.99


def test_fit_rejects_bad_ranges():
    with pytest.raises(InputError, match="current_max"):
        fit_current_squared(5.0, 2.0)
    with pytest.raises(InputError, match="current_min"):
        fit_current_squared(-1.0, 2.0)


def test_design_model_is_affine_and_records_its_fit(plant_model, design_model):
    assert design_model.is_affine and not plant_model.is_affine
    assert design_model.spec.variant == "linear"
    fit = current_squared_fit(design_model)
    assert fit.current_range == pytest.approx((1.911, 7.0))
    assert design_model.parameters["I2_slope"].provenance == "fitted"
    assert design_model.parameters["theta_ref"].provenance == "assumed"
    # same network, only the copper sources differ
    assert design_model.network.links == plant_model.network.links
    assert design_model.network.air_streams == plant_model.network.air_streams


def test_linear_and_nonlinear_agree_at_the_linearisation_point(plant_model):
    """Where I^2 = aI + b exactly and the winding sits at theta_ref, both models have the same
    steady state (up to the spread of the three winding divisions around theta_ref)."""
    fit = fit_current_squared(1.911, 7.0)
    current = fit.exact_at[1]
    u = plant_model.input_vector(current, current, current, 1.0, 20.0, 20.0)
    x_nonlinear = plant_model.steady_state(u)
    winding = x_nonlinear[plant_model.state_names.index("stator_winding")]
    design = linear_design_model(plant_model, (1.911, 7.0), theta_ref_C=winding)
    x_linear = design.steady_state(u)
    assert np.max(np.abs(x_linear - x_nonlinear)) < 0.05
    # nearby transients stay close, and the mismatch grows in proportion to the distance from
    # the point (the line's slope differs from dI^2/dI = 2I): one hour after a current step
    mismatch = {}
    for delta in (0.05, 0.2):
        v = u.copy()
        v[:3] += delta
        U = np.tile(v[:, None], (1, 360))
        X_lin = np.asarray(design.discretise(10.0).simulator(360)(x_nonlinear, U))
        X_non = np.asarray(plant_model.discretise(10.0).simulator(360)(x_nonlinear, U))
        mismatch[delta] = np.max(np.abs(X_lin - X_non))
    assert mismatch[0.05] < 0.35
    assert 3.0 < mismatch[0.2] / mismatch[0.05] < 5.0


def test_linear_model_error_grows_away_from_the_fit(plant_model, design_model):
    """Thesis 5.2.3: the line is worst far from where it crosses I^2. Below the fit range the
    thesis's line even gives a negative copper loss; the design model floors it at 0 W, so at no load
    both models have no copper loss and agree, and the worst error is at the top of the range."""
    fit = current_squared_fit(design_model)
    assert fit.intercept < 0  # the line itself is negative at no load, as in the thesis
    errors = {}
    for current in (0.0, 2.5, 3.5, 7.0):
        u = plant_model.input_vector(current, current, current, 1.0, 20.0, 20.0)
        errors[current] = abs(design_model.outputs(design_model.steady_state(u), u)[0]
                              - plant_model.outputs(plant_model.steady_state(u), u)[0])
    assert errors[0.0] < 1e-6
    assert errors[7.0] > errors[3.5] > errors[2.5] and errors[7.0] > 5.0


def test_copper_loss_is_never_negative_and_zero_load_stays_at_ambient(plant_model, design_model):
    """24 h at zero load from ambient: the design model never falls below ambient and ends where the
    nonlinear model does, heated by the iron loss only (before the floor its winding ended 20 K below). Simulation, the Kalman filter's
    prediction and the exact step agree; over the fit range the step is the thesis's affine one."""
    from genthermal.estimation.kalman import KalmanFilter
    from genthermal.simulate import simulate

    ambient = 20.0
    zero = design_model.input_vector(0.0, 0.0, 0.0, 0.0, ambient, ambient)
    for current in np.linspace(0.0, 7.0, 15):  # every source's power >= 0 at any load
        u = design_model.input_vector(current, current, current, 1.0, ambient, ambient)
        assert float(design_model.functions["heat"](np.full(design_model.n_states, ambient), u,
                                                    design_model.p0)) >= 0.0
    discrete = design_model.discretise(60.0)
    X = np.asarray(discrete.simulator(1440)(np.full(design_model.n_states, ambient), np.tile(zero[:, None], 1440)))
    # only the iron loss heats it: the end state is the nonlinear model's no-load steady state
    assert X.min() >= ambient - 1e-9 and X[:, -1] == pytest.approx(plant_model.steady_state(zero), abs=0.01)
    filter_ = KalmanFilter(design_model, dt_s=60.0)
    x = np.full(design_model.n_states, ambient)
    for _ in range(1440):
        x, _ = filter_.predict(x, None, zero)
    assert x.min() >= ambient - 1e-9
    time_s = np.arange(0.0, 86400.0 + 1.0, 600.0)
    frame = simulate(design_model, pd.DataFrame({"time_s": time_s, **{n: np.full(time_s.size, v) for n, v in
                                                                       zip(design_model.input_names, zero)}}))
    assert frame["T_winding"].min() >= ambient - 1e-9
    # in the fit range the exact step and the affine matrices are the same model
    u = design_model.input_vector(4.0, 3.0, 5.0, 1.0, 30.0, 25.0)
    x = np.linspace(40.0, 90.0, design_model.n_states)
    assert np.asarray(discrete.step(x, u)).ravel() == pytest.approx(discrete.A @ x + discrete.B @ u + discrete.c,
                                                                    abs=1e-9)
