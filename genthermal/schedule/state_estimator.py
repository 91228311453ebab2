"""The filter of each generator in flight, on the model the manager believes in (the extended
Kalman filter with disturbance heat flows, or the thesis linear filter). Main objects:
:class:`StateEstimator`, :func:`believed_model`, :func:`planning_generator`.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..estimation.ekf import ExtendedKalmanFilter
from ..estimation.kalman import KalmanFilter

#: Noise settings of the flight EKF: constant and load-scaled heat flows only, as random walks
#: of 8 and 15 W per hour, no coolant-scaled states, no change detection. The fault detector's
#: drifts and thresholds (:class:`~genthermal.schedule.monitoring.detector.DetectorSettings`) were measured
#: on this filter (``benchmarks/bench_detection.py``), and its CUSUM is itself the flight's change
#: detection, so the flight keeps it; ``genthermal estimate`` uses the slower defaults of
#: :mod:`genthermal.estimation.ekf` with its own change test.
FLIGHT_EKF_SETTINGS = {"disturbance_drift_W": 8.0, "load_scaled_drift_W": 15.0, "coolant_drift_W": 0.0,
                       "inlet_drift_K": 0.0, "change_threshold": None}
#: Filters the closed loop can use: name → how to build one from ``(design generator, flown
#: model, step s)``: ``ekf`` on the flown nonlinear model, ``kf`` on the design model.
FLIGHT_FILTERS = {"ekf": lambda generator, flown_model, dt_s: ExtendedKalmanFilter(flown_model, dt_s,
                                                                                   **FLIGHT_EKF_SETTINGS),
                  "kf": lambda generator, flown_model, dt_s: KalmanFilter(generator.model, dt_s)}


def planner_state(filter_state, filter_state_names, design_model) -> np.ndarray:
    """The state the planner needs from a filter's state: the design model's node temperatures.

    The extended Kalman filter's state is the flown model's nodes (°C) followed by its disturbance
    heat flows (W); the planner's design model has the same nodes. Each design-model node takes the
    filter's estimate of the node of the same name; the disturbances are handed over separately,
    as forcing of the design model (:func:`planning_generator`).

    Parameters
    ----------
    filter_state : array_like
        The filter's state, in ``filter_state_names`` order.
    filter_state_names : sequence of str
    design_model : ThermalModel
        The model the planner predicts with.

    Returns
    -------
    numpy.ndarray
        Node temperatures, °C, in ``design_model.state_names`` order.
    """
    index = {name: i for i, name in enumerate(filter_state_names)}
    missing = [name for name in design_model.state_names if name not in index]
    if missing:
        raise InputError("design_model", design_model.name,
                         f"has nodes the filter does not estimate: {', '.join(missing)}")
    state = np.asarray(filter_state, dtype=float)
    return np.array([state[index[name]] for name in design_model.state_names])


def planning_generator(generator, filter_, filter_state):
    """The design generator the planner predicts with: ``generator`` with the filter's estimated
    disturbance heat flows (:meth:`AffineGenerator.with_disturbances
    <genthermal.schedule.power_system.AffineGenerator.with_disturbances>`).

    Each disturbance node's constant heat flow :math:`d_j` (W) and load-scaled loss :math:`m_j`
    (W at rated current) of the extended Kalman filter (:mod:`genthermal.estimation.ekf`) go to
    the design-model node of the same name, so the plan carries the model error the filter has
    learnt into the future (held constant, as :meth:`ExtendedKalmanFilter.forecast` does). A
    filter without disturbance states (the linear ``kf``) gives ``generator`` unchanged.

    Parameters
    ----------
    generator : AffineGenerator
        Design model of the generator as the manager believes it.
    filter_ : RecursiveFilter
        The generator's filter.
    filter_state : array_like
        The filter's state (nodes °C, then disturbances W).

    Returns
    -------
    AffineGenerator
    """
    if not isinstance(filter_, ExtendedKalmanFilter):
        return generator
    model = generator.model
    state = np.asarray(filter_state, dtype=float)
    nx, n_nodes = filter_.model.n_states, len(filter_.disturbance_nodes)
    heat, load_heat = np.zeros(model.n_states), np.zeros(model.n_states)
    for j, node in enumerate(filter_.disturbance_nodes):
        if node not in model.state_names:
            raise InputError("design_model", model.name, f"has no node {node}, where the filter estimates a "
                             "disturbance heat flow")
        i = model.state_names.index(node)
        heat[i] = state[nx + j]
        if filter_.load_scaled:
            load_heat[i] = state[nx + n_nodes + j]
    return generator.with_disturbances(heat, load_heat, filter_.rated_current_A)


class StateEstimator:
    """The filter of one generator on the model the manager believes in.

    Parameters
    ----------
    generator : AffineGenerator
        Design model to start with (what the planner predicts with).
    flown_model : callable
        ``flown_model()`` returns the nonlinear model that ``generator`` was linearised from (called
        only when a filter for ``generator`` is first built).
    x0 : array_like
        Initial node temperatures, °C (disturbances start at zero).
    dt_s : float
        Filter step, s.
    filters : dict
        Filters by design generator, shared between the generators of one flight.
    filter_name : str
        Key of :data:`FLIGHT_FILTERS`.
    """

    def __init__(self, generator, flown_model, x0, dt_s: float, filters: dict, filter_name: str = "ekf"):
        if filter_name not in FLIGHT_FILTERS:
            raise InputError("filter", filter_name, f"must be one of {', '.join(FLIGHT_FILTERS)}")
        self.dt_s, self._filters, self._make = dt_s, filters, FLIGHT_FILTERS[filter_name]
        self.filter, self.z, self.P = None, np.array(x0, dtype=float), None
        self._names = None
        self.innovation, self.innovation_std = np.full(2, np.nan), np.full(2, np.nan)
        self.use(generator, flown_model)

    @property
    def x(self) -> np.ndarray:
        """Node temperatures of the current design model, °C (:func:`planner_state`)."""
        return planner_state(self.z, self.filter.state_names, self.generator.model)

    @property
    def planning_generator(self):
        """The design model with the filter's disturbance heat flows (:func:`planning_generator`)."""
        return planning_generator(self.generator, self.filter, self.z)

    def use(self, generator, flown_model) -> None:
        """Continue on ``generator``'s model (``flown_model()`` builds the nonlinear one if needed).

        Node temperatures carry over by name. While the filter's state is the same, the nodes'
        covariance carries over too; otherwise the covariance restarts from the new filter's ``P0``.
        The disturbance states (extended Kalman filter) restart at zero with their ``P0`` block
        whenever the model changes: they carried the error of the old model, which a recalibrated
        or newly identified model has taken in. Carried over, they counted that error twice: on
        blockage_large with the engineer's heuristic, a recalibration on the healthy generator's
        record at 185 min left its filter predicting it 4.2 K too hot after one cycle at 7 A; the
        sensor watch took the -4.35 K innovation for a stuck winding sensor and masked it, and with
        offset-free planning the manager then switched the healthy generator off.
        """
        if id(generator) not in self._filters:
            self._filters[id(generator)] = self._make(generator, flown_model(), self.dt_s)
        self.generator, new = generator, self._filters[id(generator)]
        if self._names != new.state_names:
            nodes = dict(zip(self._names or generator.model.state_names, self.z))
            self.z = np.array([nodes.get(name, 0.0) for name in new.state_names])
            self.P, self._names = new.P0, list(new.state_names)
        elif new is not self.filter and isinstance(new, ExtendedKalmanFilter):
            nx = new.model.n_states
            self.z = np.concatenate([self.z[:nx], np.zeros(len(self.z) - nx)])
            P = np.array(new.P0, dtype=float)
            P[:nx, :nx] = self.P[:nx, :nx]
            self.P = P
        self.filter = new

    def update(self, y) -> None:
        """Measurement update with the measured winding and iron temperatures ``y`` (°C); keeps the
        innovation and its predicted standard deviation (K)."""
        H = self.filter.H if isinstance(self.filter, ExtendedKalmanFilter) else self.filter.C
        self.innovation_std = np.sqrt(np.diag(H @ self.P @ H.T + self.filter.R))
        step = self.filter.update(self.z, self.P, y)
        self.z, self.P, self.innovation = step.x, step.P, step.innovation

    def predict(self, currents_A, inlets_C, ambient_C) -> None:
        """Time updates over the applied phase currents and the measured inlet and ambient
        temperatures (°C; the ambient one per step or one for all), one per step."""
        ambients = np.broadcast_to(np.asarray(ambient_C, dtype=float), np.shape(currents_A))
        for current, inlet, ambient in zip(currents_A, inlets_C, ambients):
            self.z, self.P = self.filter.predict(self.z, self.P, self.generator.input(current, inlet, float(ambient)))


def believed_model(base, effects):
    """``base`` (a nonlinear model) with ``effects`` (``(name, ((parameter, value), ...))`` pairs)
    applied in order."""
    for name, values in effects:
        base = base.with_effect(name, **dict(values))
    return base
