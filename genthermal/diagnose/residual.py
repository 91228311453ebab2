"""Is something still missing? Tests of the residual left after the chosen effects.

:func:`residual_tests` checks the residual's level against the noise, its whiteness (lag-1
autocorrelation) and its correlation with the inputs and temperatures per sensor, and says where
and when it is largest. A slow error that tracks the load or a temperature is missing physics;
one that does not is input noise. Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .compare import MeasuredSeries

LEVEL_FACTOR = 2.0
STRUCTURE_LEVEL_FACTOR = 1.3
MAX_AUTOCORRELATION = 0.5
MAX_CORRELATION = 0.3
#: Window of the moving average that locates the largest residual, s.
SMOOTHING_S = 600.0


def correlation(a: np.ndarray, b: np.ndarray) -> float:
    """Pearson correlation of ``a`` and ``b`` over the samples where both are finite (0 if undefined)."""
    ok = np.isfinite(a) & np.isfinite(b)
    if ok.sum() < 3 or np.std(a[ok]) == 0 or np.std(b[ok]) == 0:
        return 0.0
    return float(np.corrcoef(a[ok], b[ok])[0, 1])


def _regressors(series: MeasuredSeries, output_names, interface) -> dict:
    inputs = series.inputs
    currents = interface.load_currents
    regressors = {"mean I^2": np.mean([inputs[p].to_numpy(dtype=float) ** 2 for p in currents], axis=0)}
    others = [name for name in interface.input_names if name not in currents]
    regressors.update({name: inputs[name].to_numpy(dtype=float) for name in others})
    for name, measured in zip(output_names, series.outputs):
        regressors[f"measured {name}"] = measured
    return regressors


def residual_tests(series: MeasuredSeries, predicted: np.ndarray, noise: float, output_names, interface,
                   reference: str = "the sensor noise", levels: dict | None = None,
                   factors: tuple = (LEVEL_FACTOR, STRUCTURE_LEVEL_FACTOR)) -> dict:
    """Run the three tests of the module docstring on ``predicted - series.outputs``.

    Parameters
    ----------
    series : MeasuredSeries
    predicted : numpy.ndarray
        Model outputs with the chosen effects, (n_outputs, N), °C.
    noise : float
        Estimated sensor noise standard deviation, K.
    output_names : sequence of str
    interface : MachineInterface
        The model's (``model.spec.interface``): the inputs the residual is correlated with.
    reference : str
        What ``noise`` is, for the summary ("the discrepancy floor" when it is the level of the
        calibrated model's error, :mod:`genthermal.diagnose.error_model`).
    levels : dict, optional
        Sensor → its own level (K, its discrepancy floor) for the per-sensor tests; default
        ``noise`` for every sensor.
    factors : (float, float)
        The level test's factor on ``noise`` and the structure test's on each sensor's level
        (default :data:`LEVEL_FACTOR`, :data:`STRUCTURE_LEVEL_FACTOR`; against the discrepancy
        floor the diagnosis uses those of :mod:`genthermal.diagnose.error_model`).

    Returns
    -------
    dict
        JSON-ready: ``unexplained`` (bool), ``per_sensor`` (``rmse_K``, ``rmse_over_noise``,
        ``lag1_autocorrelation``, ``correlations``, ``follows``, ``level_ok``, ``white``),
        ``largest`` (``sensor``, ``time_h``, ``residual_K`` of the smoothed residual) and ``summary``.
    """
    residual = np.asarray(predicted, dtype=float) - series.outputs
    regressors = _regressors(series, output_names, interface)
    window = max(1, int(round(SMOOTHING_S / series.dt_s)))
    per_sensor, largest = {}, None
    overall = float(np.sqrt(np.nanmean(residual ** 2)))
    level_factor, structure_factor = factors
    level_ok = bool(overall <= level_factor * noise)
    levels = levels or {}
    for name, e in zip(output_names, residual):
        own = max(float(levels.get(name, noise)), 1e-12)
        ok = np.isfinite(e)
        rmse = float(np.sqrt(np.mean(e[ok] ** 2)))
        centred = e[ok] - e[ok].mean()
        lag1 = float(centred[1:] @ centred[:-1] / max(centred @ centred, 1e-300))
        correlations = {r: correlation(e, v) for r, v in regressors.items()}
        follows = max(correlations, key=lambda r: abs(correlations[r]))
        structured = (rmse > structure_factor * own and lag1 > MAX_AUTOCORRELATION
                      and abs(correlations[follows]) > MAX_CORRELATION)
        per_sensor[name] = {"rmse_K": rmse, "rmse_over_noise": rmse / own,
                            "lag1_autocorrelation": lag1, "correlations": correlations, "follows": follows,
                            "structured": bool(structured)}
        smooth = pd.Series(e).rolling(window, center=True, min_periods=1).mean().to_numpy()
        k = int(np.nanargmax(np.abs(smooth)))
        if largest is None or abs(smooth[k]) > abs(largest["residual_K"]):
            largest = {"sensor": name, "time_h": float((series.time_s[k] - series.time_s[0]) / 3600.0),
                       "residual_K": float(smooth[k])}
    unexplained = not level_ok or any(s["structured"] for s in per_sensor.values())
    return {"unexplained": bool(unexplained), "rmse_K": overall, "rmse_over_noise": overall / noise if noise > 0
            else float("inf"), "level_ok": level_ok, "per_sensor": per_sensor, "largest": largest,
            "thresholds": {"rmse_over_noise_at_most": level_factor, "structure_rmse_over_noise": structure_factor,
                           "lag1_autocorrelation_at_most": MAX_AUTOCORRELATION,
                           "abs_correlation_at_most": MAX_CORRELATION},
            "summary": _summary(per_sensor, largest, overall / noise if noise > 0 else float("inf"), unexplained,
                                reference)}


def _summary(per_sensor: dict, largest: dict, level: float, unexplained: bool, reference: str) -> str:
    short = reference.replace("the ", "").replace("sensor ", "")
    if not unexplained:
        return (f"The residual is {level:.1f}× {reference} and follows no input or temperature: nothing "
                "is left for another effect to explain.")
    failing = [f"{name} (RMSE {s['rmse_over_noise']:.1f}× {short}, lag-1 autocorrelation "
               f"{s['lag1_autocorrelation']:.2f}, follows {s['follows']} r = {s['correlations'][s['follows']]:+.2f})"
               for name, s in per_sensor.items()]
    return (f"Something is still missing: the residual is {level:.1f}× {reference}; {'; '.join(failing)}. "
            f"It is largest on {largest['sensor']} at t = {largest['time_h']:.2f} h "
            f"({'model hot' if largest['residual_K'] > 0 else 'model cold'} by {abs(largest['residual_K']):.2f} K, "
            f"{SMOOTHING_S / 60:.0f}-min average). Do not read the effects found as the whole answer.")
