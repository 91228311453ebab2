"""Comparison of the candidate design models on validation data (thesis 5.4).

:func:`compare_design_models` predicts the winding and iron temperatures of a validation record
open loop with the nonlinear physics model, the linear design model (:mod:`genthermal.design`)
and an ARX model per output (:mod:`genthermal.estimation.arx`, chosen on the training record),
and scores each by R², RMSE and max error (K). Results: ``docs/results/thesis-reproduction.md``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..design import linear_design_model
from ..errors import InputError
from ..machines import build_model
from ..measurements import MeasurementData
from ..model import ThermalModel
from ..simulate import simulate
from .arx import arx_fit, r_squared
from .arx_search import OUTPUTS, input_signal, output_signal, select_input, training_record
from .kalman import initial_state_from_measurements
from .prediction import on_grid

#: Model labels in table order.
MODEL_LABELS = ("nonlinear physics", "linear physics", "ARX")
TABLE_COLUMNS = ["model", "sensor", "order", "R2", "rmse_K", "max_abs_error_K", "detail"]


def error_scores(measured, modelled) -> dict[str, float]:
    """``R2``, ``rmse_K`` and ``max_abs_error_K`` of ``modelled`` against ``measured`` (NaN
    samples of ``measured`` skipped)."""
    measured, modelled = np.asarray(measured, dtype=float), np.asarray(modelled, dtype=float)
    error = (modelled - measured)[np.isfinite(measured)]
    return {"R2": r_squared(measured, modelled), "rmse_K": float(np.sqrt(np.mean(error**2))),
            "max_abs_error_K": float(np.max(np.abs(error)))}


def compare_design_models(train: MeasurementData, validation: MeasurementData, plant: ThermalModel | None = None,
                          dt_s: float = 10.0, **arx_search_options) -> pd.DataFrame:
    """Score the nonlinear, linear and ARX models on ``validation`` (module docstring).

    Parameters
    ----------
    train : MeasurementData
        Record the ARX models are fitted to.
    validation : MeasurementData
        Record all models are scored on (a different load profile).
    plant : ThermalModel, optional
        Nonlinear physics model; default the built-in thesis generator. The linear model is
        :func:`~genthermal.design.linear_design_model` of it.
    dt_s : float
        Sample time, s; records on another grid are resampled to it.
    **arx_search_options
        Passed to :func:`~genthermal.estimation.arx_search.select_input` (``na_range``,
        ``integrate_input``, ``discard_before_s`` ...).

    Returns
    -------
    pandas.DataFrame
        One row per model and sensor: ``model``, ``sensor``, ``order`` (number of states),
        ``R2``, ``rmse_K``, ``max_abs_error_K`` and ``detail`` (the ARX input and structure).
    """
    for name, record in (("train", train), ("validation", validation)):
        if not isinstance(record, MeasurementData):
            raise InputError(name, type(record).__name__, "expected MeasurementData (genthermal.measurements)")
    train, validation = on_grid(train, dt_s), on_grid(validation, dt_s)
    plant = plant or build_model()
    inputs = validation.frame[["time_s", *plant.input_names]]
    measured = validation.sensors
    y0, u0 = measured.iloc[0].to_numpy(), inputs[list(plant.input_names)].iloc[0].to_numpy()
    # model output → ARX output (the first two sensors: MeasurementData.winding / .iron)
    sensors = dict(zip(plant.output_names, OUTPUTS))
    rows = []
    for label, model in ((MODEL_LABELS[0], plant), (MODEL_LABELS[1], linear_design_model(plant))):
        x0 = initial_state_from_measurements(model, y0, u0)
        result = simulate(model, inputs, x0=x0)
        for sensor in sensors:
            rows.append({"model": label, "sensor": sensor, "order": model.n_states,
                         **error_scores(measured[sensor], result[sensor]), "detail": model.name})
    options = {"ts_s": dt_s, "constant_term": True, **arx_search_options}
    discard_before_s = options.pop("discard_before_s", 0.0)
    for sensor, output in sensors.items():
        selection = select_input(train, output, discard_before_s=discard_before_s, **options)
        best = selection.candidates.iloc[0]
        y, u = training_record(train, output, selection.input_name, discard_before_s)
        arx = arx_fit(y, u, int(best.na), int(best.nb), int(best.nk), integrate_input=options.get("integrate_input", False),
                      ts_s=dt_s, constant_term=options["constant_term"])
        y_val = output_signal(validation, output)
        first = y_val[np.isfinite(y_val)]
        if first.size == 0:
            raise InputError(f"validation {sensor}", "all NaN", "the validation record has no measurement")
        simulated = arx.simulate(input_signal(validation, selection.input_name), initial_output=float(first[0]))
        na, nb, nk = arx.structure
        rows.append({"model": MODEL_LABELS[2], "sensor": sensor, "order": arx.to_state_space()[0].shape[0],
                     **error_scores(y_val, simulated),
                     "detail": f"input {selection.input_name}, na={na} nb={nb} nk={nk}"})
    return pd.DataFrame(rows, columns=TABLE_COLUMNS)
