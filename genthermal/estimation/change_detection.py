r"""Detect a change in what the model lacks from the filter's innovations, and open the
disturbance covariance so the filter learns it quickly (a fault, a blockage).

The disturbance states of :mod:`genthermal.estimation.ekf` drift as slow random walks: a
calibrated model is off by a few W that change little, and a slow walk learns them like an
online calibration instead of chasing sensor noise. A fault is a different thing: rare, sudden
and large. A random walk fast enough to follow it would chase noise the rest of the time, so the
filter is told about a change when its innovations show one (a jump detector in the spirit of
Willsky & Jones 1976, with a covariance reset instead of a state jump).

Test. With :math:`S_k = H P_k^- H^T + R` and its Cholesky factor :math:`S_k = L_k L_k^T`, the
whitened innovation :math:`\varepsilon_k = L_k^{-1}\nu_k` is :math:`N(0, I)` and white while the
filter's model holds. Over the last :math:`W` samples,

.. math::
    T_k = \frac{1}{W}\Big\lVert \sum_{i=k-W+1}^{k} \varepsilon_i \Big\rVert^2 \sim \chi^2_{n_y},

a persistent bias of the innovations (what a missed heat flow leaves) makes :math:`T_k` grow with
:math:`W`. When :math:`T_k` exceeds ``threshold`` the disturbance block of the filtered covariance
gets ``jump_covariance`` added (the size of change to expect) and the window starts again, so one
change opens the covariance once. Only past innovations are used: the rule is causal.
Samples with a missing sensor are left out of the window.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError


class InnovationChangeDetector:
    """Windowed test on the whitened innovations (module docstring).

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
        self.reset()

    def reset(self) -> None:
        """Forget the window (start of a record)."""
        self._window: list[np.ndarray] = []
        #: Samples (indices of :meth:`step` calls) at which the test fired.
        self.alarms: list[int] = []
        self._count = 0

    def step(self, innovation: np.ndarray, S: np.ndarray, P_filtered: np.ndarray) -> np.ndarray:
        """Add one sample's innovation (K, NaN = missing) with its covariance ``S`` (K²) and
        return the filtered covariance, opened by ``jump_covariance`` if the test fires."""
        index, self._count = self._count, self._count + 1
        if not np.all(np.isfinite(innovation)):
            return P_filtered
        self._window.append(np.linalg.solve(np.linalg.cholesky(S), innovation))
        if len(self._window) > self.window_samples:
            self._window.pop(0)
        if len(self._window) < self.window_samples:
            return P_filtered
        statistic = float(np.sum(np.sum(self._window, axis=0) ** 2)) / self.window_samples
        if statistic <= self.threshold:
            return P_filtered
        self.alarms.append(index)
        self._window.clear()
        return P_filtered + self.jump_covariance
