"""Long, finely sampled records made fit for fitting: block averages on a coarser grid.

:func:`decimate_for_fitting` averages a record in blocks down to at most
:data:`MAX_FITTING_SAMPLES` samples, on the first of :data:`FITTING_STEPS_S` that is long enough:
currents as RMS values (the mean loss is kept), temperatures as means, sensors over a window
centred on each sample. Figures: ``docs/results/long_records.md``; method:
``docs/guide/methods.md``.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .errors import InputError
from .measurements import MeasurementData

#: Most samples a record given to calibration or diagnosis keeps: the diagnosis's cost grows with the
#: samples (``benchmarks/bench_long_record.py``); one week fits at 120-s blocks (5041 samples),
#: records of more than 8.3 days are refused (split them).
MAX_FITTING_SAMPLES = 6_000
#: Longest window a sensor is averaged over around each grid time, s.
SENSOR_WINDOW_S = 30.0
#: Block lengths tried in order, s: 10 s is the thesis logging and filter step. The longest is a
#: third of the 6.5-minute fastest slow mode of the thesis generator: the model holds a block's
#: mean input over the whole block, and a load change inside it shifts that mode's response by up
#: to a block. The true model fitted a week at 1 s to 0.05 K RMSE on 120-s blocks and to 0.29 K on
#: 300-s blocks, which missed the truth by more than the sensor noise (docs/guide/safety.md).
FITTING_STEPS_S = (10.0, 15.0, 20.0, 30.0, 60.0, 120.0)


def fitting_step(data: MeasurementData) -> float | None:
    """The block length (s) :func:`decimate_for_fitting` uses for ``data``, or None to keep it.

    Raises
    ------
    InputError
        The record is so long that even the longest block leaves more than
        :data:`MAX_FITTING_SAMPLES` samples: split it.
    """
    time_s = data.time_s
    samples = time_s.size
    if samples <= MAX_FITTING_SAMPLES:
        return None
    duration_s = float(time_s[-1] - time_s[0])
    own_step = float(np.median(np.diff(time_s)))
    for step in FITTING_STEPS_S:
        if step >= own_step and duration_s / step + 1 <= MAX_FITTING_SAMPLES:
            return step
    raise InputError(data.source, f"{samples} samples over {duration_s / 86400:.3g} days",
                     f"too long to fit in one piece (more than {MAX_FITTING_SAMPLES} samples even at "
                     f"{FITTING_STEPS_S[-1]:g} s); split the record")


def block_average(data: MeasurementData, step_s: float) -> MeasurementData:
    """Average ``data`` on the grid ``t0, t0 + step_s, ...`` (see the module docstring): inputs over
    the block that starts at each grid time, sensors over the window centred on it.
    """
    time_s = data.time_s
    elapsed = time_s - time_s[0]
    n_blocks = int(np.floor(elapsed[-1] / step_s + 1e-9)) + 1
    columns = {"time_s": time_s[0] + step_s * np.arange(n_blocks)}
    input_block = np.floor(elapsed / step_s + 1e-9).astype(np.int64)
    sensor_block = np.minimum(np.floor(elapsed / step_s + 0.5).astype(np.int64), n_blocks - 1)
    half_window_s = min(step_s, SENSOR_WINDOW_S) / 2.0
    in_window = np.abs(elapsed - sensor_block * step_s) <= half_window_s + 1e-9 * step_s
    inputs = data.interface.input_names
    rms_columns = data.interface.rms_currents  # losses go with their square
    for name in data.frame.columns:
        if name == "time_s":
            continue
        block = input_block if name in inputs else sensor_block
        values = data.frame[name].to_numpy(dtype=float)
        valid = np.isfinite(values) & (in_window | (name in inputs))
        squared = name in rms_columns
        sums = np.bincount(block, np.where(valid, values ** 2 if squared else values, 0.0), n_blocks)
        counts = np.bincount(block, valid, n_blocks)
        with np.errstate(invalid="ignore", divide="ignore"):
            mean = sums / counts
        mean = np.sqrt(mean) if squared else mean
        if name in inputs:  # a block inside a gap (flagged on loading) holds the last input
            mean = pd.Series(mean).ffill().to_numpy()
        columns[name] = mean
    frame = pd.DataFrame(columns)
    missing = {name: int(frame[name].isna().sum()) for name in data.missing_counts}
    return MeasurementData(frame, f"{data.source} averaged over {step_s:g} s blocks", missing,
                           list(data.flags), list(data.ignored_columns), data.interface)


def decimate_for_fitting(data: MeasurementData) -> tuple[MeasurementData, str | None]:
    """``data`` block-averaged to :func:`fitting_step` when it is long, and a note saying so."""
    step = fitting_step(data)
    if step is None:
        return data, None
    averaged = block_average(data, step)
    note = (f"{data.source}: {len(data.frame)} samples averaged to {len(averaged.frame)} over {step:g} s blocks "
            f"for fitting (currents as RMS); give --dt to choose the step yourself")
    return averaged, note
