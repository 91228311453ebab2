r"""The optimal scheduler's tie-breaker: keep the windings cool where rest does not depend on it.

Both transcriptions (:mod:`genthermal.schedule.optimal` on the design model,
:mod:`genthermal.schedule.optimal_nlp` on the flown model) minimise the rest first and add

.. math::
    \frac{w_h}{60}\;\overline{\left(\frac{\theta - \theta_{amb}}{\theta_{lim} - \theta_{amb}}\right)^2},

the mean over generators, temperature outputs and running time (each grid temperature weighted by
the length of its interval, rests left out) of the squared rise above the ambient as a fraction of
the rise the limit allows, :math:`w_h` in seconds of rest (the objective is in minutes). The mean
is 0..1 while every temperature lies between the ambient and the planning limit, so the term is
worth at most :math:`w_h` seconds of rest: with :data:`DEFAULT_HEADROOM_WEIGHT_S` below the
optimal scheduler's smallest rest (:data:`~genthermal.schedule.optimal.MIN_REST_S`, 1 s) and the
flight's 10-s step, it never buys rest; it only chooses among schedules that rest the same.

Why: where the rest does not depend on it (healthy generators with room), the rest-only optimum is
not unique and the older tie-breaker, the least displacement (:math:`\sum d^2`), kept the faulty
winding right at the planning limit. The plant's surprises (model mismatch, a fault identified
late) then cost rest later. The square of the rise is largest on the hottest winding, so the term
moves load from the hotter generator to the cooler one until their marginal costs match, and
leaves a winding below the limit where it can. Measured on ``bench_scheduler.py``'s
long_combat@120min/k0.2+31 (per-interval planning in both runs): 210 s of rest with the least
displacement, 90 s with this term, against the engineer's heuristic's 140 s.
"""

from __future__ import annotations

import numpy as np

#: :math:`w_h`, seconds of rest the headroom term is worth at most (0.5 s: half of the smallest
#: rest the optimal scheduler keeps, :data:`genthermal.schedule.optimal.MIN_REST_S`). A choice of
#: this project, not a thesis value.
DEFAULT_HEADROOM_WEIGHT_S = 0.5
#: Smallest span of the normalisation, K (a limit at or below the ambient would divide by zero).
MIN_SPAN_K = 1.0


def headroom_scale(problem) -> np.ndarray:
    """``(reference °C, span K)`` of the headroom term for ``problem`` (a
    :class:`~genthermal.schedule.plan.PlanningProblem`): the ambient temperature, and the planning
    limit above it (at least :data:`MIN_SPAN_K`)."""
    return np.array([problem.ambient_C, max(problem.limit_C - problem.ambient_C, MIN_SPAN_K)])
