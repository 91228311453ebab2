"""What a calibration leaves: the disturbance heat flows a filter learns on the calibration record.

:func:`learn_disturbance_prior` runs the extended Kalman filter over the calibration record once
after the fit and keeps the posterior of its disturbance states (mean and covariance) as a
:class:`DisturbancePrior`; a filter on the next flight of the machine starts from it instead of
zero. ``genthermal calibrate --out`` writes it into the model file. Guide and figures:
``docs/guide/estimation.md``.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..errors import InputError

#: Filter step used to learn the prior on the calibration record, s (the ``estimate`` default).
PRIOR_LEARNING_STEP_S = 10.0


@dataclasses.dataclass(frozen=True, eq=False)
class DisturbancePrior:
    """Mean and covariance of an EKF's disturbance states after a calibration record.

    Attributes
    ----------
    names : tuple of str
        The disturbance states, in the filter's order (``q_<node>``, ``q_load_<node>``,
        ``q_coolant_<node>``: W; ``dT_inlet``: K).
    mean : numpy.ndarray
        Their means, W (K for ``dT_inlet``).
    covariance : numpy.ndarray
        Their covariance, W² (K² and K·W for ``dT_inlet``), symmetric positive semi-definite.
    source : str
        Where it was learnt (the calibration record).
    """

    names: tuple
    mean: np.ndarray
    covariance: np.ndarray
    source: str = ""

    def __post_init__(self):
        names = tuple(self.names)
        if not names or not all(isinstance(n, str) and n for n in names) or len(set(names)) != len(names):
            raise InputError("disturbance_prior.states", list(names), "must be distinct, non-empty state names")
        try:
            mean = np.asarray(self.mean, dtype=float).reshape(-1)
            covariance = np.asarray(self.covariance, dtype=float)
        except (TypeError, ValueError):
            raise InputError("disturbance_prior", "mean/covariance", "must be numbers") from None
        if mean.shape != (len(names),) or not np.all(np.isfinite(mean)):
            raise InputError("disturbance_prior.mean", mean.tolist(), f"must be {len(names)} finite numbers")
        if covariance.shape != (len(names), len(names)) or not np.all(np.isfinite(covariance)):
            raise InputError("disturbance_prior.covariance", covariance.tolist(),
                             f"must be a {len(names)} x {len(names)} matrix of finite numbers")
        if not np.allclose(covariance, covariance.T, rtol=1e-9, atol=1e-12):
            raise InputError("disturbance_prior.covariance", covariance.tolist(), "must be symmetric")
        if np.min(np.linalg.eigvalsh(covariance)) < -1e-9 * max(1.0, np.max(np.abs(covariance))):
            raise InputError("disturbance_prior.covariance", covariance.tolist(), "must be positive semi-definite")
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "mean", mean)
        values, vectors = np.linalg.eigh(0.5 * (covariance + covariance.T))  # round-off: clip to PSD
        object.__setattr__(self, "covariance", (vectors * np.maximum(values, 0.0)) @ vectors.T)

    def to_document(self) -> dict:
        """The model-file section (plain lists, rounded to 1e-6)."""
        return {"source": self.source, "states": list(self.names),
                "mean": [round(float(v), 6) for v in self.mean],
                "covariance": [[round(float(v), 6) for v in row] for row in self.covariance]}

    @classmethod
    def from_document(cls, document, field: str = "disturbance_prior") -> "DisturbancePrior":
        """Read the section written by :meth:`to_document`; InputError naming ``field`` otherwise."""
        if not isinstance(document, dict):
            raise InputError(field, document, "must be a mapping with states, mean and covariance")
        unknown = sorted(set(document) - {"source", "states", "mean", "covariance"})
        if unknown:
            raise InputError(f"{field}.{unknown[0]}", document[unknown[0]], "unknown key; use source, states, mean, "
                             "covariance")
        missing = [key for key in ("states", "mean", "covariance") if key not in document]
        if missing:
            raise InputError(f"{field}.{missing[0]}", None, "missing")
        if not isinstance(document["states"], list):
            raise InputError(f"{field}.states", document["states"], "must be a list of state names")
        return cls(tuple(document["states"]), document["mean"], document["covariance"],
                   str(document.get("source", "")))


def learn_disturbance_prior(model, data, dt_s: float = PRIOR_LEARNING_STEP_S) -> DisturbancePrior:
    """Run the default extended Kalman filter on ``model`` over ``data`` (the calibration record)
    and return its disturbance states' mean and covariance after the last sample.

    Parameters
    ----------
    model : ThermalModel
        The calibrated model (any prior it carries is ignored: the filter starts from zero).
    data : MeasurementData
        The record the model was calibrated on; put on the ``dt_s`` grid.
    dt_s : float
        Filter step, s.
    """
    from .ekf import ExtendedKalmanFilter
    from .prediction import check_sensors, on_grid

    data = on_grid(data, dt_s)
    check_sensors(model, data)
    ekf = ExtendedKalmanFilter(model.with_disturbance_prior(None), dt_s)
    result = ekf.run(data.frame[["time_s", *model.input_names]], data.sensors)
    nx = ekf.n_nodes
    duration_h = (data.time_s[-1] - data.time_s[0]) / 3600.0
    return DisturbancePrior(tuple(ekf.disturbance_names), result.disturbances[-1],
                            result.final_covariance[nx:, nx:],
                            f"extended Kalman filter over {data.source} ({duration_h:.2f} h) after calibration")
