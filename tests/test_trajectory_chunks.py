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
    chunked = _chunked_outputs(step, n_samples, x0, series, [c])
    _, plain = step.mapaccum("plain", n_samples, [0], [0])(x0, series, c)
    both = ca.Function("both", [x0, series, c], [chunked, plain, ca.jacobian(ca.vec(chunked), c),
                                                 ca.jacobian(ca.vec(plain), c)])
    rng = np.random.default_rng(n_samples)
    values = [np.array(v) for v in both([1.0, -2.0], rng.standard_normal((1, n_samples)), [0.9, 0.5, 3.0])]
    assert values[0].shape == (2, n_samples)
    np.testing.assert_array_equal(values[0], values[1])
    np.testing.assert_allclose(values[2], values[3], rtol=1e-12, atol=1e-12)
    assert np.count_nonzero(values[2]) >= n_samples  # every sample's outputs depend on c
