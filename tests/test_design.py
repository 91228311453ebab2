"""The linear design model (thesis 5.2) and its agreement with the nonlinear simulation model."""

import numpy as np
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
    """Thesis 5.2.3: the linear model is worst at no load (it even predicts negative copper loss)."""
    errors = []
    for current in (0.0, 3.5, 7.0):
        u = plant_model.input_vector(current, current, current, 1.0, 20.0, 20.0)
        errors.append(abs(design_model.outputs(design_model.steady_state(u), u)[0]
                          - plant_model.outputs(plant_model.steady_state(u), u)[0]))
    assert errors[0] > errors[1] and errors[0] > 5.0
