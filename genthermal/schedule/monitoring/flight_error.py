"""The model error the flight's identification scores hypotheses with: the AR(1)
:class:`~genthermal.diagnose.error_model.ErrorModel` of the recalibrated model on the healthy
generator's record it was recalibrated on (the flight's own sister generator), estimated as the
offline diagnosis estimates it on its baseline. Main object: :func:`flight_error_model`. Method:
docs/guide/flight-methods.md ("Evidence in flight").
"""

from __future__ import annotations

from ...diagnose.error_model import ErrorModel, baseline_error_model, check_baseline_length


def flight_error_model(model, record, dt_s: float) -> ErrorModel:
    """The error model of ``model`` (just recalibrated on ``record``) on ``record``.

    Parameters
    ----------
    model : ThermalModel
        The recalibrated planning model.
    record : pandas.DataFrame
        A healthy generator's record so far in the measurement schema
        (:meth:`~genthermal.schedule.monitoring.monitor.FaultMonitor.fit_record`).
    dt_s : float
        Its sample period, s (the identification's ``identify_dt_s``).

    Returns
    -------
    ErrorModel
        Per sensor of ``model``: the residual's level (the discrepancy floor, K) and lag-1
        autocorrelation at ``dt_s``.

    Raises
    ------
    InputError
        (field ``baseline``) when the record is shorter than the error model needs
        (:data:`~genthermal.diagnose.error_model.MIN_BASELINE_S`, and 5 correlation times of its
        residual), naming the minimum.
    """
    check_baseline_length(float(record["time_s"].iloc[-1] - record["time_s"].iloc[0]))
    return baseline_error_model(model, model, record, dt_s, None, {})
