"""Fault detection on the extended Kalman filter's disturbance heat flows, between generators: a
CUSUM on each generator's extra heat flow against the others'. Main objects:
:class:`DisturbanceDetector`, :class:`DetectorSettings`, :func:`extra_heat_flow`. Method:
docs/guide/flight-methods.md.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ...errors import InputError
from ...estimation.ekf import ExtendedKalmanFilter


@dataclasses.dataclass(frozen=True)
class DetectorSettings:
    """Drifts and thresholds of the disturbance CUSUMs (module docstring for their provenance).

    Attributes
    ----------
    winding_drift, winding_threshold : float
        :math:`\\nu, h` on the winding node's statistic (dimensionless, in standard deviations).
    iron_drift, iron_threshold : float
        :math:`\\nu, h` on the iron node's statistic.
    settle_s : float
        No test before this time from the mission start, s (the filters start from a covariance
        that says nothing about the disturbances).
    load_tolerance : float
        A generator whose load factor exceeds its references' median by more than this fraction
        is not tested (module docstring).
    """

    winding_drift: float = 0.8
    winding_threshold: float = 1.5
    iron_drift: float = 2.0
    iron_threshold: float = 3.0
    settle_s: float = 600.0
    load_tolerance: float = 0.05

    def __post_init__(self):
        for name in ("winding_drift", "winding_threshold", "iron_drift", "iron_threshold", "settle_s",
                     "load_tolerance"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise InputError(f"detection.{name}", value, "must be a finite number >= 0")


def extra_heat_flow(filter_, z, P, load_factor: float):
    """Estimated extra heat flow into each disturbance node at ``load_factor`` and its variance.

    Parameters
    ----------
    filter_ : ExtendedKalmanFilter
    z, P : numpy.ndarray
        The filter's state (nodes °C, then disturbances W) and covariance.
    load_factor : float
        :math:`\\ell = \\overline{I^2}/I_{rated}^2`.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray)
        :math:`q_j(\\ell)` (W) and :math:`\\sigma^2_j(\\ell)` (W²), one per node of
        ``filter_.disturbance_nodes``.
    """
    if not isinstance(filter_, ExtendedKalmanFilter):
        raise InputError("filter", type(filter_).__name__, "fault detection needs the extended Kalman filter's "
                         "disturbance states")
    if set(filter_.bases) - {"constant", "load"} or filter_.inlet_offset:
        raise InputError("filter", filter_.disturbance_names, "fault detection works on constant and load-scaled "
                         "heat flows only (schedule.state_estimator.FLIGHT_EKF_SETTINGS); this filter has state-dependent "
                         "ones")
    nx, n_nodes = filter_.model.n_states, len(filter_.disturbance_nodes)
    q, variance = np.empty(n_nodes), np.empty(n_nodes)
    for j in range(n_nodes):
        index = [nx + j, nx + n_nodes + j] if filter_.load_scaled else [nx + j]
        a = np.array([1.0, load_factor][:len(index)])
        q[j] = a @ z[index]
        variance[j] = a @ P[np.ix_(index, index)] @ a
    return q, variance


class DisturbanceDetector:
    """The CUSUMs of the module docstring for every generator and disturbance node.

    Parameters
    ----------
    n_generators : int
    settings : DetectorSettings
    node_roles : sequence of str
        Per disturbance node, ``"winding"`` or ``"iron"`` (selects its drift and threshold).
    """

    def __init__(self, n_generators: int, settings: DetectorSettings, node_roles):
        self.settings = settings
        self.drift = np.array([getattr(settings, f"{role}_drift") for role in node_roles])
        self.threshold = np.array([getattr(settings, f"{role}_threshold") for role in node_roles])
        self.sums = np.zeros((n_generators, len(node_roles)))
        self.last_statistic = np.full((n_generators, len(node_roles)), np.nan)
        #: Highest statistic and highest sum per node seen in the flight (tested cycles only):
        #: the margin of a healthy flight to its thresholds.
        self.peak_statistic = np.full(len(node_roles), -np.inf)
        self.peak_sum = np.zeros(len(node_roles))

    def statistics(self, extra, load_factors, believed_healthy, masked=frozenset()) -> np.ndarray:
        """:math:`r_{gj}` (n_generators, n_nodes); NaN where g is not tested (no healthy generator to
        compare with, or more load than its references, or its sensor of node j masked).

        Parameters
        ----------
        extra : callable
            ``extra(g, load_factor)`` → :func:`extra_heat_flow` of generator g at that load.
        load_factors : array_like
            :math:`\\ell_g` of the cycle flown.
        believed_healthy : sequence of bool
            Per generator, True when no fault has been identified on it.
        masked : collection of (int, int)
            ``(generator, node index)`` whose sensor is masked (a claimed sensor fault): the
            filter no longer observes that node's heat flow, so it is neither tested nor a
            reference.
        """
        n = len(load_factors)
        r = np.full(self.sums.shape, np.nan)
        for g in range(n):
            references = [h for h in range(n) if h != g and believed_healthy[h]]
            if not references or load_factors[g] > (1.0 + self.settings.load_tolerance) * \
                    np.median([load_factors[h] for h in references]):
                continue
            q, variance = extra(g, load_factors[g])
            others = {h: extra(h, load_factors[g]) for h in references}
            for j in range(r.shape[1]):
                observed = [others[h] for h in references if (h, j) not in masked]
                if (g, j) in masked or not observed:
                    continue
                q_ref = np.median([o[0][j] for o in observed])
                variance_ref = np.median([o[1][j] for o in observed])
                r[g, j] = (q[j] - q_ref) / np.sqrt(variance[j] + variance_ref)
        return r

    def update(self, t_s: float, r) -> list:
        """Add one cycle of statistics; the ``(generator, node index)`` pairs that alarm (their
        sums restart)."""
        self.last_statistic = np.asarray(r, dtype=float)
        if t_s < self.settings.settle_s:
            return []
        finite = np.isfinite(self.last_statistic)
        step = np.where(finite, self.last_statistic - self.drift, 0.0)
        self.sums = np.where(finite, np.maximum(0.0, self.sums + step), 0.0)
        if finite.any():
            self.peak_statistic = np.fmax(self.peak_statistic,
                                          np.max(np.where(finite, self.last_statistic, -np.inf), axis=0))
        self.peak_sum = np.maximum(self.peak_sum, self.sums.max(axis=0))
        alarms = [tuple(int(i) for i in pair) for pair in np.argwhere(self.sums > self.threshold)]
        for g, _ in alarms:
            self.sums[g] = 0.0
        return alarms

    def restart(self, generator: int) -> None:
        """Clear generator ``generator``'s sums (after its model changed)."""
        self.sums[generator] = 0.0
