"""The load manager's price: what a schedule costs in minutes of rest, load not served included
(:data:`SHED_PRICE_MIN_PER_AH` minutes per A·h). Main objects: :func:`schedule_cost_min`,
:func:`not_served_Ah`.
"""

from __future__ import annotations

import numpy as np

#: Rest (min) that one A·h of phase current not served costs the manager. Choice of this project,
#: not a figure of the thesis (whose heuristic has no load shedding): far above any rest the
#: flight's budget allows (a quarter of the mission: 60 min on a 4-h mission, 120 min on an 8-h
#: one), so a plan sheds load only where rest within the budget and displacement cannot keep the
#: limit, and then as little as they allow: one minute of rest is worth 1 mA·h, so 0.06 A·h not
#: served costs as much as a 60-min rest.
SHED_PRICE_MIN_PER_AH = 1000.0
#: Costs closer than this are the same to the manager, min: one 10-s step of rest (the closed
#: loop's step), so that rounding does not buy rest or shed load.
PRICE_TOLERANCE_MIN = 10.0 / 60.0


def not_served_per_segment_Ah(segments, schedule) -> np.ndarray:
    """Phase current a schedule leaves unserved in each segment, A·h (all generators, >= 0).

    Parameters
    ----------
    segments : sequence of Segment
        The plan's segments (their durations and nominal currents).
    schedule : Schedule
        Its displacements (a segment whose displacements add up to more than zero leaves the
        difference unserved) and the generators switched off (their nominal load is not
        theirs to carry; what the others take of it is a negative displacement of theirs).

    Returns
    -------
    numpy.ndarray
        (n_segments,) A·h.
    """
    displaced = np.asarray(schedule.displaced_A, dtype=float)
    if displaced.shape[1] != len(segments):
        raise ValueError(f"the schedule has {displaced.shape[1]} segments, the plan {len(segments)}")
    off = np.asarray(schedule.switched_off, dtype=bool)
    durations = np.array([s.duration_s for s in segments], dtype=float)
    nominal_As = np.array([sum(d * c for d, c in s.pieces) for s in segments], dtype=float)
    short_As = displaced[~off].sum(axis=0) * durations + np.count_nonzero(off) * nominal_As
    return np.clip(short_As, 0.0, None) / 3600.0


def not_served_Ah(segments, schedule) -> float:
    """Phase current a schedule leaves unserved, A·h (all generators and segments,
    :func:`not_served_per_segment_Ah`)."""
    return float(np.sum(not_served_per_segment_Ah(segments, schedule)))


def cost_min(rest_s: float, not_served: float, price_min_per_Ah: float = SHED_PRICE_MIN_PER_AH) -> float:
    """The manager's cost of ``rest_s`` (s) of rest and ``not_served`` (A·h) of load not served,
    in minutes of rest (module docstring)."""
    if not (np.isfinite(rest_s) and rest_s >= 0):
        raise ValueError(f"rest_s = {rest_s!r}: must be a rest in s >= 0")
    if not (np.isfinite(not_served) and not_served >= 0):
        raise ValueError(f"not_served = {not_served!r}: must be a charge in A·h >= 0")
    return rest_s / 60.0 + price_min_per_Ah * not_served


def schedule_cost_min(segments, schedule) -> float:
    """The manager's cost of ``schedule`` over ``segments``, min (:func:`cost_min`)."""
    return cost_min(schedule.added_rest_s, not_served_Ah(segments, schedule))
