"""An in-flight record put on the coarser grid that calibration and identification fit on: each
grid row gets the RMS of each current and the mean of the other inputs over the interval it is
held for. Main objects: :func:`on_fit_grid`, :func:`check_fit_step`.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import pandas as pd

from ...errors import InputError


def check_fit_step(field: str, fit_dt_s: float, step_s: float) -> int:
    """Steps of ``step_s`` per grid step ``fit_dt_s`` (s); InputError naming ``field`` unless it
    is a whole number >= 1."""
    factor = float(fit_dt_s) / float(step_s)
    if not np.isfinite(factor) or factor < 1.0 or abs(factor - round(factor)) > 1e-9 * factor:
        raise InputError(field, fit_dt_s, f"must be a whole multiple (>= 1) of the record's step {step_s:g} s "
                         "(the record is averaged over whole steps for the fits)")
    return int(round(factor))


def on_fit_grid(record: pd.DataFrame, fit_dt_s: float, current_columns: Sequence[str],
                sensor_columns: Sequence[str]) -> pd.DataFrame:
    """``record`` on a grid of ``fit_dt_s`` with each row's inputs averaged over the interval the
    row is held for (module docstring).

    Parameters
    ----------
    record : pandas.DataFrame
        A flight record in the measurement schema on a uniform step: ``time_s`` (s), one row per
        step, its inputs those in force during the step that ends at ``time_s`` and its sensors
        read at ``time_s``.
    fit_dt_s : float
        Grid step, s: an integer multiple of the record's step.
    current_columns : sequence of str
        Input columns that are currents, A (averaged as root mean square).
    sensor_columns : sequence of str
        Sensor columns, °C (taken at the grid times, NaN kept).

    Returns
    -------
    pandas.DataFrame
        Same columns, rows at ``time_s[0] + j·fit_dt_s`` up to the record's end; a last row whose
        interval runs past the record's end repeats the record's last step for the steps missing.
    """
    time_s = record["time_s"].to_numpy(dtype=float)
    if time_s.size < 2:
        raise InputError("record", f"{time_s.size} row(s)", "need at least two steps to put a record on a grid")
    step_s = float(time_s[1] - time_s[0])
    if step_s <= 0.0 or not np.allclose(np.diff(time_s), step_s, rtol=1e-9, atol=1e-9 * step_s):
        raise InputError("record.time_s", f"steps {np.unique(np.diff(time_s))[:3]} s",
                         "must be uniform and increasing (one row per simulation step)")
    factor = check_fit_step("fit_dt_s", fit_dt_s, step_s)
    missing = [c for c in (*current_columns, *sensor_columns) if c not in record.columns]
    if missing:
        raise InputError("record columns", missing, f"not in the record (it has {', '.join(record.columns)})")
    rows = np.arange(0, time_s.size, factor)
    held = np.minimum(rows[:, None] + 1 + np.arange(factor)[None, :], time_s.size - 1)
    grid = {"time_s": time_s[rows]}
    for column in record.columns.drop("time_s"):
        values = record[column].to_numpy(dtype=float)
        if column in sensor_columns:
            grid[column] = values[rows]
        elif column in current_columns:
            grid[column] = np.sqrt(np.mean(values[held] ** 2, axis=1))
        else:
            grid[column] = np.mean(values[held], axis=1)
    return pd.DataFrame(grid)[list(record.columns)]
