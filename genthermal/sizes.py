"""Size estimates before large arrays are allocated.

A mission of ``duration_min: 1e12`` or a step of ``1e-6`` s must be refused with a clear message
before numpy tries to allocate terabytes. Every time grid genthermal builds from user input is
checked here first.
"""

from __future__ import annotations

import math

from .errors import InputError

#: Most samples one time grid may have: 5 million (58 days at 1 s, 1.6 years at 10 s). A
#: simulation keeps about 30 floats per sample (inputs, states, outputs), so this bounds a grid's
#: results to about 1.2 GB.
MAX_GRID_SAMPLES = 5_000_000
#: Floats kept per sample by a simulation (inputs, states, node outputs), for the estimate.
FLOATS_PER_SAMPLE = 30


def check_grid(duration_s: float, step_s: float, field: str, value) -> int:
    """Return the number of samples of a grid over ``duration_s`` at ``step_s``, or refuse it.

    Parameters
    ----------
    duration_s, step_s : float
        Length of the grid and its step, s (both positive and finite).
    field, value
        What the user set that decides the size (``"--dt"``, ``"actions[0].duration_min"``) and
        its value, for the message.

    Raises
    ------
    InputError
        The grid would have more than :data:`MAX_GRID_SAMPLES` samples (the estimated memory is
        given).
    """
    ratio = float(duration_s) / float(step_s) if step_s > 0 else math.inf  # inf for a step of 5e-324 s
    samples = math.floor(ratio + 1e-9) + 1 if math.isfinite(ratio) else math.inf
    if not samples <= MAX_GRID_SAMPLES:
        gigabytes = samples * FLOATS_PER_SAMPLE * 8 / 1e9
        raise InputError(field, value, f"gives {samples:.3g} time samples ({duration_s:g} s at a {step_s:g} s step, "
                         f"about {gigabytes:.3g} GB); the limit is {MAX_GRID_SAMPLES:,} samples: use a longer "
                         "step or a shorter duration")
    return int(samples)
