"""The parametric simulator's trajectory in chunks equals one ``mapaccum`` over every step."""

import casadi as ca
import numpy as np
import pytest

from genthermal.diagnose.trajectory import _chunked_outputs


def _toy_step() -> ca.Function:
    """``(x, v, c) -> (x_next, y)``: a decaying state driven by ``v``, outputs depending on ``c``."""
    x, v, c = ca.SX.sym("x", 2), ca.SX.sym("v", 1), ca.SX.sym("c", 3)
    x_next = ca.vertcat(c[0] * x[0] + v, c[1] * x[1] + x[0])
    return ca.Function("step", [x, v, c], [x_next, ca.vertcat(x[1] + c[2], x[0] * v)])


@pytest.mark.parametrize("n_samples", [1, 2, 3, 7, 16, 17, 100])
def test_chunked_outputs_equal_one_mapaccum_and_its_derivative(n_samples):
    step = _toy_step()
    x0, series, c = ca.MX.sym("x0", 2), ca.MX.sym("series", 1, n_samples), ca.MX.sym("c", 3)
    chunked, _ = _chunked_outputs(step, n_samples, x0, series, [c])
    _, plain = step.mapaccum("plain", n_samples, [0], [0])(x0, series, c)
    both = ca.Function("both", [x0, series, c], [chunked, plain, ca.jacobian(ca.vec(chunked), c),
                                                 ca.jacobian(ca.vec(plain), c)])
    rng = np.random.default_rng(n_samples)
    values = [np.array(v) for v in both([1.0, -2.0], rng.standard_normal((1, n_samples)), [0.9, 0.5, 3.0])]
    assert values[0].shape == (2, n_samples)
    np.testing.assert_array_equal(values[0], values[1])
    np.testing.assert_allclose(values[2], values[3], rtol=1e-12, atol=1e-12)
    assert np.count_nonzero(values[2]) >= n_samples  # every sample's outputs depend on c


def test_outputs_reuse_the_prefix_before_the_onset_and_equal_a_fresh_simulation():
    from genthermal.diagnose.trajectory import ParametricSimulator
    from genthermal.machines import build_model

    model = build_model()
    rated = np.asarray(model.input_vector(**model.spec.interface.rated_inputs), dtype=float).reshape(-1, 1)
    n_samples = 200
    inputs = rated * (1.0 + 0.2 * np.sin(np.arange(n_samples) / 15.0))  # a varying load, temperatures too
    nominal = model.parameters["k_l"].value
    simulator = ParametricSimulator(model, 10.0, inputs, ["k_l"], [{"k_l": nominal}, {"k_l": "k_l"}])
    for onset in (0, 13, 14, 150, 199):
        indicator = simulator.indicator([onset])
        assert simulator.theta_free_samples(indicator) == onset
        previous = None
        for k_l in (0.5 * nominal, 0.6 * nominal, 2.0 * nominal):
            outputs = simulator.outputs([k_l], [1.0, 20.0], indicator)
            fresh = np.asarray(simulator._trajectory([k_l], [1.0, 20.0], indicator, inputs))
            np.testing.assert_array_equal(outputs, fresh)
            if previous is not None:
                np.testing.assert_array_equal(outputs[:, :onset], previous[:, :onset])
                if onset < n_samples - 1:  # theta acts from the step after the onset on
                    assert np.max(np.abs(outputs[:, onset + 1:] - previous[:, onset + 1:])) > 1e-6
            previous = outputs
    assert sorted(simulator._suffixes) == [14, 140, 196]  # chunks of 14 samples: the prefixes were reused
