r"""Detect a change in what the model lacks from the filter's innovations, and open the disturbance covariance.

:class:`InnovationChangeDetector` tests an exponentially weighted mean of the innovations against
:math:`\chi^2_{n_y}` (a jump detector in the spirit of Willsky & Jones 1976); when it fires, the
filtered covariance of the disturbance states gets ``jump_covariance`` added, so the filter learns
a fault or a blockage quickly while its random walks stay slow. The rule is causal and carried by
the generated C update. Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError


def forgetting_factor(window_samples: int) -> float:
    """:math:`\\lambda = (W - 1)/(W + 1)` of a window of ``window_samples`` samples."""
    return (window_samples - 1.0) / (window_samples + 1.0)


def change_step(mean: np.ndarray, innovation: np.ndarray, S: np.ndarray, window_samples: int,
                threshold: float) -> tuple[np.ndarray, float, bool]:
    """One step of the test: ``(m_k, T_k, alarm)`` from ``m_{k-1}`` (K), the innovation (K, NaN =
    missing) and its covariance ``S`` (K²); after an alarm the returned mean is zero."""
    if not np.all(np.isfinite(innovation)):
        return mean, 0.0, False
    lam = forgetting_factor(window_samples)
    mean = lam * mean + (1.0 - lam) * innovation
    statistic = float((1.0 + lam) / (1.0 - lam) * mean @ np.linalg.solve(S, mean))
    if statistic > threshold:
        return np.zeros_like(mean), statistic, True
    return mean, statistic, False


class InnovationChangeDetector:
    """The test of the module docstring over one record, with its alarms.

    Parameters
    ----------
    window_samples : int
        :math:`W`, samples.
    threshold : float
        Alarm level of :math:`T_k` (a :math:`\\chi^2_{n_y}` quantile), dimensionless.
    jump_covariance : numpy.ndarray
        Added to the filtered covariance when the test fires (filter-state order; zero on the
        node temperatures), K² and W².
    """

    def __init__(self, window_samples: int, threshold: float, jump_covariance: np.ndarray):
        if not (isinstance(window_samples, (int, np.integer)) and window_samples >= 1):
            raise InputError("window_samples", window_samples, "must be a whole number of samples >= 1")
        if not (np.isfinite(threshold) and threshold > 0):
            raise InputError("threshold", threshold, "must be a positive chi-square value")
        self.window_samples = int(window_samples)
        self.threshold = float(threshold)
        self.jump_covariance = np.asarray(jump_covariance, dtype=float)
        self.mean: np.ndarray | None = None
        #: Samples (indices of :meth:`step` calls) at which the test fired.
        self.alarms: list[int] = []
        #: :math:`T_k` of every sample (0 where a sensor was missing).
        self.statistics: list[float] = []

    def step(self, innovation: np.ndarray, S: np.ndarray, P_filtered: np.ndarray) -> np.ndarray:
        """Add one sample's innovation (K, NaN = missing) with its covariance ``S`` (K²) and
        return the filtered covariance, opened by ``jump_covariance`` if the test fires."""
        if self.mean is None:
            self.mean = np.zeros(len(innovation))
        self.mean, statistic, alarm = change_step(self.mean, np.asarray(innovation, dtype=float), S,
                                                  self.window_samples, self.threshold)
        self.statistics.append(statistic)
        if not alarm:
            return P_filtered
        self.alarms.append(len(self.statistics) - 1)
        return P_filtered + self.jump_covariance
