"""A healthy baseline of several records: one calibration over the set, one error model from all.

:func:`calibrate_baselines` fits the baseline parameters to every record at once, each from its own
measured initial state (:func:`~genthermal.diagnose.multi_record.fit_records`), and returns a
:class:`RecordsCalibration`. The checks of a set against the record under test
(:func:`~genthermal.diagnose.error_model.baseline_records`) and the error model pooled over it
(:func:`~genthermal.diagnose.error_model.baseline_error_model`) are the error model's.
"""

from __future__ import annotations

import dataclasses

from ..model import ThermalModel


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


def calibrate_baselines(model: ThermalModel, records, names, dt_s: float | None = None) -> RecordsCalibration:
    """Fit ``names`` to every record of ``records`` (MeasurementData) at once, each from its own
    measured initial state, block-averaged to ``dt_s`` s when given."""
    from .multi_record import fit_records, record_from_measurements, records_fisher

    grid = [record_from_measurements(model, r, dt_s) for r in records]
    fit = fit_records(model, grid, list(names))
    fisher = records_fisher(fit)
    return RecordsCalibration(fit.model, list(names), [float(v) for v in fit.start], [float(v) for v in fit.values],
                              fisher, fit.converged, fit.rmse, [r.source for r in records])

