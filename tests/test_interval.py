"""Intervals of identified parameters (genthermal/diagnose/interval.py): the effective sample size
of serially correlated residuals."""

import numpy as np
import pytest

from genthermal.diagnose.interval import effective_samples


def test_white_residuals_count_fully_and_correlated_ones_count_less():
    rng = np.random.default_rng(0)
    white = rng.standard_normal((2, 5000))
    assert effective_samples(white) == pytest.approx(10000, rel=0.05)
    rho = 0.9
    correlated = np.zeros((1, 5000))
    for k in range(1, 5000):
        correlated[0, k] = rho * correlated[0, k - 1] + rng.standard_normal()
    assert effective_samples(correlated) == pytest.approx(5000 * (1 - rho) / (1 + rho), rel=0.2)


def test_missing_samples_are_left_out():
    residuals = np.array([[0.1, -0.2, np.nan, 0.3, -0.1, 0.2], [np.nan] * 6])
    assert 0 < effective_samples(residuals) <= 5
