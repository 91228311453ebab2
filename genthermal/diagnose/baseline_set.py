"""A healthy baseline of several records: one calibration over the set, one error model from all.

:func:`calibrate_baselines` fits the baseline parameters to every record at once, each from its own
measured initial state (:func:`~genthermal.diagnose.multi_record.fit_records`), and returns its
:class:`~genthermal.diagnose.multi_record.RecordsFit`. The checks of a set against the record
under test (:func:`~genthermal.diagnose.error_model.baseline_records`) and the error model pooled
over it (:func:`~genthermal.diagnose.error_model.baseline_error_model`) are the error model's.
"""

from __future__ import annotations

from ..model import ThermalModel


def calibrate_baselines(model: ThermalModel, records, names, dt_s: float | None = None):
    """Fit ``names`` to every record of ``records`` (MeasurementData) at once, each from its own
    measured initial state, block-averaged to ``dt_s`` s when given.

    Returns
    -------
    RecordsFit
        Named by the records' sources, with its Fisher summary.
    """
    from .multi_record import fit_records, record_from_measurements

    return fit_records(model, [record_from_measurements(model, r, dt_s) for r in records], list(names))
