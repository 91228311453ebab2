r"""The error a calibrated model leaves on a healthy record, and the evidence measured against it.

:class:`ErrorModel` describes each sensor's residual after the baseline calibration as an AR(1)
process (level: the *discrepancy floor*; lag-1 correlation :math:`\phi`); :class:`WhitenedBIC`
scores every hypothesis on :math:`N_{eff} = N (1-\phi)/(1+\phi)` effective samples, and
:func:`widened_calibration` widens calibration intervals by the same factor. The derivation and
the minimum baseline length: ``docs/guide/evidence.md``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..errors import InputError
from .criterion import BIC

#: Shortest healthy baseline the error model is estimated from, s.
MIN_BASELINE_S = 3600.0
#: ... and it must span this many correlation times of its residual.
MIN_CORRELATION_TIMES = 5.0
#: Against the floor, the residual after the findings is "unexplained" above this many floors over
#: every sensor, or above :data:`STRUCTURE_OVER_FLOOR` of its own floor on one sensor with structure
#: (:func:`~genthermal.diagnose.residual.residual_tests`): a calibrated model's error on another
#: mission than its baseline's is larger than on the baseline (up to 3 × on the healthy
#: independent records), which is not missing physics.
UNEXPLAINED_OVER_FLOOR = 3.0
STRUCTURE_OVER_FLOOR = 4.0
#: Largest lag-1 autocorrelation used (a residual that never decorrelates has no effective samples).
MAX_PHI = 0.995


@dataclasses.dataclass(frozen=True)
class SensorError:
    """The AR(1) error of one sensor: ``level_K`` (RMS), ``phi`` (lag-1 autocorrelation at
    ``dt_s``), ``noise_K`` (the sensor noise of the same record, second differences)."""

    sensor: str
    level_K: float
    phi: float
    noise_K: float

    @property
    def innovation_K(self) -> float:
        """Standard deviation of the AR(1) innovation, K."""
        return self.level_K * math.sqrt(max(1.0 - self.phi ** 2, 0.0))

    def to_dict(self) -> dict:
        return {"sensor": self.sensor, "floor_K": self.level_K, "lag1_autocorrelation": self.phi,
                "noise_K": self.noise_K, "innovation_K": self.innovation_K,
                "floor_over_noise": self.level_K / self.noise_K if self.noise_K > 0 else float("inf")}


@dataclasses.dataclass(frozen=True)
class ErrorModel:
    """Per-sensor AR(1) model error of a calibrated model (module docstring).

    Attributes
    ----------
    sensors : tuple of SensorError
    dt_s : float
        Sample period the correlations were estimated at, s.
    source : str
        The record it was estimated on.
    phase_spread : PhaseSpread or None
        The level of the phase sensors' spread residual, when they are fitted one by one
        (:mod:`~genthermal.diagnose.phase_spread`).
    """

    sensors: tuple
    dt_s: float
    source: str = ""
    phase_spread: object = None

    @classmethod
    def from_residual(cls, residual: np.ndarray, names, dt_s: float, source: str = "") -> "ErrorModel":
        """Estimate the error model from a healthy residual (n_sensors, N), K, at ``dt_s`` s.

        Raises
        ------
        InputError
            When the residual is shorter than :data:`MIN_BASELINE_S` or than
            :data:`MIN_CORRELATION_TIMES` correlation times of its most correlated sensor (the
            message names the minimum length).
        """
        return cls.from_residuals([residual], names, dt_s, source)

    @classmethod
    def from_residuals(cls, residuals, names, dt_s: float, source: str = "") -> "ErrorModel":
        """Estimate the error model from the residuals of several healthy records (each
        (n_sensors, N_i), K, at ``dt_s`` s): the level over all samples, the lag-1 correlation from
        the pairs of neighbouring samples within each record; their total length must meet the
        minima of :meth:`from_residual`."""
        from .search import noise_std

        residuals = [np.atleast_2d(np.asarray(r, dtype=float)) for r in residuals]
        duration = sum(r.shape[1] for r in residuals) * float(dt_s)
        check_baseline_length(duration)
        sensors = []
        for i, name in enumerate(names):
            parts = [r[i][np.isfinite(r[i])] for r in residuals]
            e = np.concatenate(parts)
            if e.size < 10:
                raise InputError("baseline", name, "has fewer than 10 valid samples: no error model for it")
            level = float(np.sqrt(np.mean(e ** 2)))
            lagged = sum(float(p[1:] @ p[:-1]) for p in parts)
            phi = float(np.clip(lagged / max(e @ e, 1e-300), 0.0, MAX_PHI))
            sensors.append(SensorError(str(name), level, phi, noise_std(e[None, :])))
        model = cls(tuple(sensors), float(dt_s), source)
        needed = max(MIN_BASELINE_S, MIN_CORRELATION_TIMES * model.correlation_time_s)
        if duration < needed:
            raise InputError("baseline", f"{duration / 3600:.2f} h" + (f" over {len(residuals)} records"
                                                                       if len(residuals) > 1 else ""),
                             f"too short to estimate the model's error: its residual stays correlated for "
                             f"{model.correlation_time_s / 60:.0f} min, so the healthy baseline must cover at least "
                             f"{needed / 3600:.1f} h ({MIN_CORRELATION_TIMES:.0f} correlation times)")
        return model

    def check_sensors(self, names, field: str = "error_model") -> None:
        """Raise :class:`~genthermal.errors.InputError` naming ``field`` unless this model
        describes exactly the sensors ``names`` (an error model of another sensor set)."""
        own, given = [s.sensor for s in self.sensors], [str(n) for n in names]
        if sorted(own) != sorted(given):
            raise InputError(field, ", ".join(own), f"describes other sensors than the record's "
                             f"({', '.join(given)}): estimate it on a healthy record of the same sensors")

    def sensor(self, name: str) -> SensorError | None:
        """The error of sensor ``name`` (None when not modelled)."""
        return next((s for s in self.sensors if s.sensor == name), None)

    @property
    def floor_K(self) -> float:
        """The discrepancy floor: RMS of the healthy residual over every sensor, K."""
        return float(math.sqrt(np.mean([s.level_K ** 2 for s in self.sensors])))

    @property
    def noise_K(self) -> float:
        """The sensor noise of the baseline pooled like the floor, K."""
        return float(math.sqrt(np.mean([s.noise_K ** 2 for s in self.sensors])))

    @property
    def correlation_time_s(self) -> float:
        """The longest correlation time :math:`-\\Delta t/\\ln\\phi` of the sensors, s."""
        return max(-self.dt_s / math.log(s.phi) if 0 < s.phi < 1 else self.dt_s for s in self.sensors)

    def effective_fraction(self, dt_s: float | None = None) -> float:
        """Effective samples per sample, :math:`(1-\\phi)/(1+\\phi)` pooled over the sensors with
        their share of the RSS (:math:`s^2`) as weights; at sample period ``dt_s`` the correlation
        is :math:`\\phi^{dt/\\Delta t}`."""
        ratio = 1.0 if dt_s is None else float(dt_s) / self.dt_s
        weights = np.array([s.level_K ** 2 for s in self.sensors])
        phis = np.array([s.phi ** ratio for s in self.sensors])
        fractions = (1 - phis) / (1 + phis)
        return float(np.clip(weights @ fractions / max(weights.sum(), 1e-300), 1e-4, 1.0))

    def criterion(self, dt_s: float | None = None, evidence_limit: float = -10.0) -> "WhitenedBIC":
        """The BIC on effective samples at sample period ``dt_s``."""
        return WhitenedBIC(evidence_limit=evidence_limit, effective_fraction=self.effective_fraction(dt_s))

    def to_dict(self) -> dict:
        return {"source": self.source, "dt_s": self.dt_s, "floor_K": self.floor_K, "noise_K": self.noise_K,
                "effective_fraction": self.effective_fraction(), "correlation_time_s": self.correlation_time_s,
                "per_sensor": [s.to_dict() for s in self.sensors],
                "phase_spread": self.phase_spread.to_dict() if self.phase_spread is not None else None,
                "form": "AR(1) per sensor fitted to the healthy baseline's residual after calibration"}

    def summary(self) -> str:
        """One line: floor beside the noise, correlation, effective samples."""
        worst = max(self.sensors, key=lambda s: s.phi)
        return (f"discrepancy floor {self.floor_K:.3f} K (sensor noise {self.noise_K:.3f} K; "
                f"lag-1 autocorrelation up to {worst.phi:.2f} on {worst.sensor}): one sample in "
                f"{1 / self.effective_fraction():.0f} is an independent one")


@dataclasses.dataclass(frozen=True)
class WhitenedBIC(BIC):
    """BIC on effective samples :math:`N_{eff} = f N` (module docstring).

    Attributes
    ----------
    effective_fraction : float
        :math:`f` in (0, 1] (:meth:`ErrorModel.effective_fraction`).
    """

    effective_fraction: float = 1.0
    name: str = "BIC (AR(1) error, effective samples)"

    def __post_init__(self):
        if not 0 < self.effective_fraction <= 1:
            raise InputError("effective_fraction", self.effective_fraction, "must lie in (0, 1]")

    def effective(self, n: int) -> float:
        """Effective samples of ``n`` raw samples."""
        return max(self.effective_fraction * n, 2.0)

    def delta(self, rss_after: float, rss_before: float, n: int, k: int) -> float:
        """:math:`N_{eff}\\ln(RSS_{after}/RSS_{before}) + k\\ln N_{eff}`."""
        if not (rss_before > 0 and rss_after > 0):
            raise InputError("rss", (rss_after, rss_before), "residual sums of squares must be > 0 (K²)")
        n_eff = self.effective(n)
        return n_eff * math.log(rss_after / rss_before) + k * math.log(max(n_eff, k + 1.0))

    def scale(self, delta_white: float, n: int, k: int) -> float:
        """A white-noise ΔBIC (:math:`N\\ln(\\cdot) + k\\ln N`) of ``k`` parameters over ``n``
        samples, restated on effective samples."""
        n_eff = self.effective(n)
        log_ratio = (delta_white - k * math.log(max(n, 2))) / max(n, 1)
        return n_eff * log_ratio + k * math.log(max(n_eff, k + 1.0))


def ar1(e) -> tuple:
    """Level (RMS, units of ``e``) and lag-1 autocorrelation, clipped to [0, :data:`MAX_PHI`], of
    the finite samples of the series ``e``: the AR(1) description of one error series."""
    e = np.asarray(e, dtype=float)
    e = e[np.isfinite(e)]
    level = float(np.sqrt(np.mean(e ** 2))) if e.size else float("nan")
    phi = float(np.clip((e[1:] @ e[:-1]) / max(e @ e, 1e-300), 0.0, MAX_PHI)) if e.size > 1 else 0.0
    return level, phi


def widened_calibration(fisher: dict, values, error: ErrorModel) -> dict:
    """The calibration's ``fisher`` summary (:func:`~genthermal.diagnose.calibrate.fisher_summary`)
    with standard errors and 95 % intervals under the AR(1) error: variances × :math:`1/f`."""
    inflation = 1.0 / math.sqrt(error.effective_fraction())
    std = [float(s) * inflation for s in fisher["std"]]
    ci = [(float(v - 1.96 * s), float(v + 1.96 * s)) for v, s in zip(values, std)]
    return {**fisher, "std": std, "ci95": ci, "std_white_noise": list(fisher["std"]),
            "interval_inflation": inflation,
            "interval_note": "95 % intervals under the AR(1) model error of the baseline residual "
                             "(white-noise intervals × 1/sqrt(effective fraction))"}


def check_baseline_length(duration_s: float) -> None:
    """Raise :class:`~genthermal.errors.InputError` naming the minimum when a baseline of
    ``duration_s`` seconds is shorter than :data:`MIN_BASELINE_S`."""
    if duration_s < MIN_BASELINE_S:
        raise InputError("baseline", f"{duration_s / 3600:.2f} h",
                         f"too short to estimate the model's error (level and correlation in time): the "
                         f"healthy baseline must cover at least {MIN_BASELINE_S / 3600:.1f} h")


def check_same_sensors(measured, baseline) -> None:
    """Raise :class:`~genthermal.errors.InputError` when the baseline record does not log the
    sensors the record under test logs (another machine or sensor set): its error model would
    describe other sensors."""
    frames = [getattr(m, "frame", None) for m in (measured, baseline)]
    if any(f is None for f in frames):
        return
    columns = [{c for c in f.columns if c != "time_s" and f[c].notna().any()} for f in frames]
    missing, extra = sorted(columns[0] - columns[1]), sorted(columns[1] - columns[0])
    if missing or extra:
        detail = "; ".join(part for part in (f"lacks {', '.join(missing)}" if missing else "",
                                             f"has {', '.join(extra)} that the record has not" if extra else "") if part)
        raise InputError("baseline", getattr(baseline, "source", "baseline"),
                         f"is not a record of the same sensor set as the data: it {detail}; calibrate on a "
                         "healthy record of the same machine and sensors")


def baseline_records(baseline, measured, interface) -> list:
    """``baseline`` (one record or a list of them: MeasurementData, DataFrame or path) as a list of
    MeasurementData, each of the sensors of ``measured``, together at least the error model's
    minimum length (InputError naming the record, or the total, otherwise)."""
    given = list(baseline) if isinstance(baseline, (list, tuple)) else [baseline]
    if not given:
        raise InputError("baseline", "[]", "give at least one healthy record")
    from .compare import as_measurements

    records = [as_measurements(b, interface) for b in given]
    for record in records:
        check_same_sensors(measured, record)
        if record.time_s.size < 2:
            raise InputError("baseline", record.source, "has fewer than two samples")
    durations = [float(r.time_s[-1] - r.time_s[0]) for r in records]
    if len(records) == 1:
        check_baseline_length(durations[0])
    elif sum(durations) < MIN_BASELINE_S:
        names = "; ".join(f"{r.source} ({d / 3600:.2f} h)" for r, d in zip(records, durations))
        raise InputError("baseline", f"together {sum(durations) / 3600:.2f} h",
                         f"too short to estimate the model's error: the healthy records must cover at least "
                         f"{MIN_BASELINE_S / 3600:.1f} h together ({names})")
    return records


def baseline_error_model(model, viewed, baseline, dt_s, view, catalogue) -> ErrorModel:
    """The error model of the calibrated ``model`` (``viewed`` through the diagnosis' sensor
    ``view``) on the healthy ``baseline`` record, or list of records (pooled:
    :meth:`ErrorModel.from_residuals`): the residual of the model with each record's initial state
    fitted, as the diagnosis fits the record under test
    (:meth:`~genthermal.diagnose.search.EffectSearch.fit_found`), with the phase sensors' spread
    level when they are fitted one by one."""
    from .discover import series_for
    from .phase_spread import PhaseSpread
    from .phase_winding import phase_sensor
    from .search import EffectSearch

    residuals, sources, steps = [], [], set()
    for record in baseline if isinstance(baseline, (list, tuple)) else [baseline]:
        series = series_for(viewed, record, dt_s)
        search = EffectSearch(model, series, [], {}, catalogue, BIC(), view).fit_found()
        residuals.append(search.predicted_before - series.outputs)
        sources.append(series.source)
        steps.add(round(series.dt_s, 9))
    if len(steps) > 1:
        raise InputError("baseline", ", ".join(sources), f"the records have different sample periods "
                         f"({', '.join(f'{s:g}' for s in sorted(steps))} s): give one step (--dt or --fit-step)")
    dt_s = steps.pop()
    error = ErrorModel.from_residuals(residuals, viewed.output_names, dt_s, ", ".join(sources))
    reader = phase_sensor(model)
    spread = None if reader is None else PhaseSpread.from_residual(np.concatenate(residuals, axis=1),
                                                                   viewed.output_names, reader.columns, dt_s)
    return dataclasses.replace(error, phase_spread=spread)
