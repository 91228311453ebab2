"""Load shedding, the manager's last resort when no schedule keeps a generator within θmax:
shed the least load that keeps the limit, switch off a generator still too hot at 0 A. Main
objects: :func:`shed_plan`, :func:`priced_shed_plan`. Method: docs/guide/flight-methods.md.
"""

from __future__ import annotations

import time

import numpy as np

from .engineer import predicted_violators
from .heuristic import SegmentResponse, future_room, receiver_room
from .plan import LIMIT_TOLERANCE_K, PlanningProblem, PlanResult, Schedule, evaluate, rest_available_s
from .price import PRICE_TOLERANCE_MIN, not_served_per_segment_Ah, schedule_cost_min

#: What the load manager does when even the lowest reachable peak is above θmax
#: (``ManagerSettings.when_infeasible``, scenario ``generators.when_infeasible``): ``shed``, shed
#: load (this module; the project's default: no planned breach of θmax); ``best_effort``, fly the
#: scheduler's own plan within the lowest reachable peak with all load served (the thesis
#: heuristic, which has no load shedding: thesis 7.2, Fig. 7.2, and its large blockage breaching
#: 110.7 and 111 °C in 7.3.3).
INFEASIBLE_RESPONSES = ("shed", "best_effort")

#: Smaller shortfalls of the total phase current are rounding of the schedulers' displacements, A.
NOT_SERVED_TOLERANCE_A = 1e-6
#: Standard deviations of an innovation taken as noise by :func:`unexplained_rise`. Choice of this
#: project: a Gaussian innovation exceeds three of them in 0.13 % of the cycles (one-sided), so a
#: healthy generator is rarely asked to shed for noise, and then for a fraction of a kelvin.
UNEXPLAINED_RISE_SIGMAS = 3.0


def unexplained_rise(innovation_K, innovation_std_K, sigmas: float = UNEXPLAINED_RISE_SIGMAS) -> np.ndarray:
    """The rise of a temperature over the last cycle that the filter's prediction did not explain:
    how far the innovation (measured minus predicted, K) exceeds ``sigmas`` of its predicted
    standard deviation (K); 0 where it does not, or where it is not a number (a masked sensor).

    Parameters
    ----------
    innovation_K, innovation_std_K : array-like
        Innovations of the last filter update and their standard deviations, K (same shape).
    sigmas : float
        Standard deviations taken as noise (>= 0).

    Returns
    -------
    numpy.ndarray
        Unexplained rise, K (>= 0), the shape of ``innovation_K``.
    """
    if not (np.isfinite(sigmas) and sigmas >= 0):
        raise ValueError(f"sigmas = {sigmas!r}: must be a number of standard deviations >= 0")
    innovation = np.asarray(innovation_K, dtype=float)
    std = np.asarray(innovation_std_K, dtype=float)
    if innovation.shape != std.shape:
        raise ValueError(f"innovation_K has shape {innovation.shape} and innovation_std_K {std.shape}: "
                         "they must match")
    excess = innovation - sigmas * np.where(np.isfinite(std), std, 0.0)
    return np.where(np.isfinite(excess), np.clip(excess, 0.0, None), 0.0)


def shed_plan(problem: PlanningProblem, switched_off, receiver_margin_K: float = 0.0, precool: bool = True,
              rest_s: float = 0.0, rest_segment: int = 0) -> PlanResult:
    """Plan the generators still on when ``switched_off`` ones carry nothing (module docstring).

    Parameters
    ----------
    problem : PlanningProblem
    switched_off : array-like of bool
        (n_generators,) True for a generator switched off.
    receiver_margin_K : float
        A generator takes on load of others only up to the planning limit minus this, K (its
        own load is kept within the planning limit itself).
    precool : bool
        The generators that breach the planning limit on the nominal schedule somewhere in the
        rest of the mission (:func:`~genthermal.schedule.planning.engineer.predicted_violators`) give the
        others, besides what they must shed, as much of their load as the others can take, and
        take none (module docstring); False: each sheds only the least that keeps it within the
        limit in each segment.
    rest_s : float
        Rest before segment ``rest_segment``, s (>= 0; :func:`priced_shed_plan` chooses both):
        the generators cool at the rest current first and then shed what they still must.
    rest_segment : int
        Index of the segment the rest comes before (default the first).

    Returns
    -------
    PlanResult
        ``method`` ``shed``; rest ``rest_s`` before segment ``rest_segment``, none elsewhere; ``feasible`` when every generator still on stays within
        the planning limit (the ones switched off cool at 0 A); ``details["shedding"]``: indices
        of the generators switched off or shedding load of their own.
    """
    started = time.perf_counter()
    off = np.array(switched_off, dtype=bool)
    if not (np.isfinite(rest_s) and rest_s >= 0):
        raise ValueError(f"rest_s = {rest_s!r}: must be a rest in s >= 0")
    if not 0 <= rest_segment < max(len(problem.segments), 1):
        raise ValueError(f"rest_segment = {rest_segment!r}: must index one of the {len(problem.segments)} segments")
    if off.shape != (problem.n_generators,):
        raise ValueError(f"switched_off has shape {off.shape}; expected ({problem.n_generators},)")
    on = [g for g in range(problem.n_generators) if not off[g]]
    n_seg = len(problem.segments)
    displaced = np.zeros((problem.n_generators, n_seg))
    x = problem.x0.copy()
    shedding = set()
    violators = set(predicted_violators(problem)) & set(on) if precool else set()
    precooling = violators if len(violators) < len(on) else set()  # someone must be left to take the load
    for k, segment in enumerate(problem.segments):
        low, high = problem.displacement_bounds(k)
        responses = {g: SegmentResponse(problem, g, k, x[g], rest_s if k == rest_segment else 0.0) for g in on}
        if k == 0 and problem.unexplained_rise_K is not None:
            for g in on:
                _add_next_cycle_rise(responses[g], problem, problem.unexplained_rise_K[g])
        must_shed = {g: min(_least_shed(responses[g], problem.limit_C), high) for g in on}
        shedding |= {g for g in on if must_shed[g] > 0}
        receiver_limit_C = problem.limit_C - receiver_margin_K
        room = {g: (max(min(-low, receiver_room(responses[g], receiver_limit_C),
                            future_room(problem, g, k, responses[g], receiver_limit_C)), 0.0)
                    if must_shed[g] <= 0 and g not in precooling else 0.0) for g in on}
        offered = np.count_nonzero(off) * segment.low_A + sum(must_shed.values())
        total_room = sum(room.values())
        taken = min(offered, total_room)
        # pre-cooling: the room left after what must go is filled with the precooling generators' load
        spare = {g: max(high - must_shed[g], 0.0) if g in precooling else 0.0 for g in on}
        extra = min(total_room - taken, sum(spare.values()))
        for g in on:
            given = extra * spare[g] / sum(spare.values()) if extra > 0 else 0.0
            received = (taken + extra) * room[g] / total_room if total_room > 0 else 0.0
            displaced[g, k] = must_shed[g] + given - received
        x = np.array([responses[g].x_end0 + displaced[g, k] * responses[g].x_end_d if g in responses else x[g]
                      for g in range(problem.n_generators)])
    rests = np.zeros(n_seg)
    rests[rest_segment] = rest_s
    schedule = Schedule(displaced, rests, off)
    result = evaluate(problem, schedule, "shed", time.perf_counter() - started)
    result.details["shedding"] = sorted(set(np.flatnonzero(off)) | shedding)
    return result


def shed_switching_off(problem: PlanningProblem, switched_off, limit_C: float, receiver_margin_K: float = 0.0,
                       rest_s: float = 0.0, rest_segment: int = 0) -> PlanResult:
    """:func:`shed_plan` with ``switched_off`` generators off and, while the plan still breaches
    ``limit_C`` (θmax, °C) on a generator still on, that one switched off too; ``schedule.switched_off``
    says which are off in the end."""
    off = np.array(switched_off, dtype=bool)
    result = shed_plan(problem, off, receiver_margin_K, rest_s=rest_s, rest_segment=rest_segment)
    # a receiver filled to the planning limit sits on it to rounding: with no margin that limit is
    # θmax, and a strict comparison switched the healthy receiver off for a 3e-14 K excess
    while result.peak_C > limit_C + LIMIT_TOLERANCE_K and not off[result.peak_generator]:
        off[result.peak_generator] = True
        result = shed_plan(problem, off, receiver_margin_K, rest_s=rest_s, rest_segment=rest_segment)
    return result


def shed_rest_candidates_s(available_s: float, step_s: float) -> np.ndarray:
    """Rests before a shed plan that :func:`priced_shed_plan` prices, s: none, ``step_s`` doubling
    (1, 2, 4, ... steps) below ``available_s``, and ``available_s`` itself (the longest rest the
    budget allows)."""
    if not (np.isfinite(step_s) and step_s > 0):
        raise ValueError(f"step_s = {step_s!r}: must be a rest step in s > 0")
    available = max(float(available_s), 0.0)
    rests = [0.0]
    rest = step_s
    while rest < available - 1e-6:
        rests.append(rest)
        rest *= 2.0
    if available > 1e-6:
        rests.append(available)
    return np.array(rests)


def priced_shed_plan(problem: PlanningProblem, switched_off, limit_C: float, receiver_margin_K: float = 0.0,
                     rest_step_s: float | None = None) -> PlanResult:
    """The shed plan (:func:`shed_switching_off`) after the rest that costs the manager least: rest
    (min) plus :data:`~genthermal.schedule.planning.price.SHED_PRICE_MIN_PER_AH` per A·h not served
    (:func:`~genthermal.schedule.planning.price.schedule_cost_min`).

    Priced are the rests of :func:`shed_rest_candidates_s` within what the flight may still rest
    (:func:`~genthermal.schedule.planning.plan.rest_available_s`) before the first segment and before the
    first segment where the plan without rest leaves load unserved: a rest right before the
    shedding cools the generator where it must shed, where one now has decayed by then. A rest is
    flown only when the load it saves from going unserved is worth more than its minutes; of two
    plans costing the same the one with less rest is kept. The closed loop re-plans every cycle
    while it sheds, so a rest planned before a later segment is priced again as it comes.

    Parameters
    ----------
    problem : PlanningProblem
    switched_off : array-like of bool
        (n_generators,) generators already off.
    limit_C : float
        θmax, °C: a generator still above it in the plan is switched off.
    receiver_margin_K : float
        As for :func:`shed_plan`, K.
    rest_step_s : float, optional
        Shortest rest priced, s; default the management cycle (``problem.window_s``).

    Returns
    -------
    PlanResult
        The cheapest plan, ``details["cost_min"]`` its cost and ``details["priced_rests"]`` the
        plans compared: segment index, rest (s) and cost (min).
    """
    step = problem.window_s if rest_step_s is None else rest_step_s
    unrested = shed_switching_off(problem, switched_off, limit_C, receiver_margin_K)
    short = np.flatnonzero(not_served_per_segment_Ah(problem.segments, unrested.schedule) > 0)
    segments = sorted({0} | ({int(short[0])} if short.size else set()))
    best = (schedule_cost_min(problem.segments, unrested.schedule), unrested)
    priced = [(0, 0.0, best[0])]
    for k in segments:
        for rest in shed_rest_candidates_s(rest_available_s(problem, k), step)[1:]:
            result = shed_switching_off(problem, switched_off, limit_C, receiver_margin_K, rest_s=float(rest),
                                        rest_segment=k)
            cost = schedule_cost_min(problem.segments, result.schedule)
            priced.append((k, float(rest), cost))
            if cost < best[0] - PRICE_TOLERANCE_MIN:
                best = (cost, result)
    cost, result = best
    result.details.update(cost_min=cost, priced_rests=priced)
    return result


def _add_next_cycle_rise(response: SegmentResponse, problem: PlanningProblem, rise_K) -> None:
    """Add to ``response``'s temperatures (plain and with the rise back-off) the unexplained rise
    ``rise_K`` (n_outputs,) K, growing linearly over the next management cycle
    (``problem.window_s``) and left out after it (the next cycle's plan has its own)."""
    rise = np.asarray(rise_K, dtype=float)
    if not np.any(rise > 0):
        return
    elapsed = problem.dt_s * np.arange(1, response.y0.shape[1] + 1)
    ramp = np.where(elapsed <= problem.window_s + 1e-9, elapsed / problem.window_s, 0.0)
    response.y0 = response.y0 + np.tile(rise, response.y0.shape[0] // rise.size)[:, None] * ramp[None, :]


def _least_shed(response: SegmentResponse, limit_C: float) -> float:
    """Least constant current (A) to shed so that every sample shedding can still cool stays
    within ``limit_C``; samples it cannot reach (the present, a machine already above the limit
    just after the decision) are left out rather than asking for the whole load."""
    relief = -response.yd
    over = (response.y0 - limit_C > LIMIT_TOLERANCE_K) & (relief > 1e-9)
    if not over.any():
        return 0.0
    return float(np.max((response.y0[over] - limit_C) / relief[over])) * (1.0 + 1e-9) + 1e-9


def not_served(nominal_A: np.ndarray, currents_A: np.ndarray, resting: np.ndarray) -> np.ndarray:
    """Phase current not served per step and per generator.

    Each generator's share of the load is the nominal current (thesis eqs. 7.3-7.4); what the
    generators carry together below their total share is not served. It is attributed to the
    generators in proportion to how far each carries below its share (a switched-off generator:
    its whole share). Rests are not counted: the load is deferred, not lost.

    Parameters
    ----------
    nominal_A : numpy.ndarray
        (n,) nominal phase current per generator, A.
    currents_A : numpy.ndarray
        (n_generators, n) applied phase currents, A.
    resting : numpy.ndarray
        (n,) True during rests.

    Returns
    -------
    numpy.ndarray
        (n_generators, n) phase current not served, A (0 during rests).
    """
    shortfall = np.clip(nominal_A[None, :] - currents_A, 0.0, None)
    unserved = currents_A.shape[0] * nominal_A - currents_A.sum(axis=0)
    unserved[unserved < NOT_SERVED_TOLERANCE_A] = 0.0  # displacements sum to zero only to rounding
    total = shortfall.sum(axis=0)
    share = np.divide(shortfall, total[None, :], out=np.zeros_like(shortfall), where=total[None, :] > 1e-12)
    result = share * unserved[None, :]
    result[:, np.asarray(resting, dtype=bool)] = 0.0
    return result
