"""A healthy baseline of several records: one calibration over the set, one error model from all.

:func:`calibrate_baselines` fits the baseline parameters to every record at once, each from its own
measured initial state (:func:`~genthermal.diagnose.multi_record.fit_records`), and returns a
:class:`RecordsCalibration`; :func:`as_record_list` checks a set of baselines against the record
under test (same sensors, long enough together). The error model pooled over the set is
:func:`~genthermal.diagnose.error_model.baseline_error_model`'s. Guide: ``docs/guide/evidence.md``.
"""

from __future__ import annotations

import dataclasses

from ..errors import InputError
from ..model import ThermalModel
from .compare import as_measurements
from .error_model import MIN_BASELINE_S, check_baseline_length, check_same_sensors


@dataclasses.dataclass
class RecordsCalibration:
    """The baseline parameters fitted over several healthy records.

    Attributes
    ----------
    model : ThermalModel
        The model with the fitted values (provenance ``fitted``).
    names : list of str
    start, values : list of float
        Values before and after the fit (model units).
    fisher : dict
        Standard errors, 95 % intervals and warnings
        (:func:`~genthermal.diagnose.multi_record.records_fisher`), widened by the error model.
    converged : bool
    rmse_after : float
        RMSE over every sensor of every record after the fit, K.
    records : list of str
        The records' sources.
    """

    model: ThermalModel
    names: list
    start: list
    values: list
    fisher: dict
    converged: bool
    rmse_after: float
    records: list

    def to_dict(self) -> dict:
        """JSON-ready summary."""
        rows = [{"name": n, "unit": self.model.parameters[n].unit, "start": self.start[i], "value": self.values[i],
                 "std": self.fisher["std"][i], "ci95": list(self.fisher["ci95"][i])} for i, n in enumerate(self.names)]
        return {"model": self.model.name, "records": self.records, "parameters": rows, "converged": self.converged,
                "rmse_after": self.rmse_after, "condition_number": self.fisher["condition_number"],
                "warnings": self.fisher["warnings"]}


def as_record_list(baseline, measured, interface) -> list:
    """``baseline`` (one record or a list of them: MeasurementData, DataFrame or path) as a list of
    MeasurementData, each of the sensors of ``measured``, together at least the error model's
    minimum length (InputError naming the record, or the total, otherwise)."""
    given = list(baseline) if isinstance(baseline, (list, tuple)) else [baseline]
    if not given:
        raise InputError("baseline", "[]", "give at least one healthy record")
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


def calibrate_baselines(model: ThermalModel, records, names, dt_s: float | None = None) -> RecordsCalibration:
    """Fit ``names`` to every record of ``records`` (MeasurementData) at once, each from its own
    measured initial state, block-averaged to ``dt_s`` s when given."""
    from .multi_record import fit_records, record_from_measurements, records_fisher

    grid = [record_from_measurements(model, r, dt_s) for r in records]
    fit = fit_records(model, grid, list(names))
    fisher = records_fisher(fit)
    return RecordsCalibration(fit.model, list(names), [float(v) for v in fit.start], [float(v) for v in fit.values],
                              fisher, fit.converged, fit.rmse, [r.source for r in records])

