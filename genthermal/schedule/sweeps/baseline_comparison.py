"""The optimal scheduler against the best baseline over the robustness grid, by rest and by the
manager's price (``rest_vs_best_baseline`` of a sweep JSON). Main object:
:func:`rest_versus_best_baseline`.
"""

from __future__ import annotations

from ..planning.price import PRICE_TOLERANCE_MIN, cost_min

#: In records without ``rested_s`` (older sweeps), added rests (mission time minus nominal
#: duration) closer than this to zero are the rounding of the actions' durations to the 10-s step
#: of the closed loop, not rest, s.
REST_RESOLUTION_S = 10.0
#: Load not served below this is no shedding, A·h: at the manager's price it costs 0.06 s of rest,
#: below the closed loop's 10-s step (the records' not-served sums carry rounding of the currents).
NOT_SERVED_RESOLUTION_AH = 1e-6
BASELINES = ("heuristic", "engineer")
#: A sweep's name for the thesis heuristic planning on the flown model (``planner_model``
#: ``nonlinear``, :mod:`~genthermal.schedule.planning.heuristic_flown`): a third baseline beside the heuristic
#: and the engineer's heuristic on the design model.
FLOWN_HEURISTIC = "heuristic_flown"
#: Baselines a case's comparison counts when the sweep flew them.
OPTIONAL_BASELINES = (FLOWN_HEURISTIC,)
#: A sweep's name for the optimal scheduler planning on the flown model (``planner_model``
#: ``nonlinear``): compared with the same baselines (:func:`rest_versus_best_baseline` with
#: ``candidate``), it meets :data:`FLOWN_HEURISTIC` with the same information, the extended Kalman
#: filter's nonlinear model, where the optimal scheduler on the design model does not.
FLOWN_OPTIMAL = "optimal_flown"
#: Summary key of :data:`FLOWN_OPTIMAL`'s comparison (a sweep's ``rest_vs_best_baseline`` is the
#: optimal scheduler's).
FLOWN_OPTIMAL_KEY = "flown_optimal_vs_best_baseline"


def baselines_of(runs: dict) -> tuple:
    """The baselines of a case's ``runs``: :data:`BASELINES` and those of :data:`OPTIONAL_BASELINES` it has."""
    return BASELINES + tuple(s for s in OPTIONAL_BASELINES if s in runs)


def finished(run: dict) -> bool:
    """True for a flight flown to the end (``status`` ``ok``)."""
    return run.get("status", "ok") == "ok"


def rest_of(run: dict) -> float:
    """Rest of a flight, s: ``rested_s``; in older records, none for a flight that never re-planned
    (it flew the nominal schedule) and ``added_rest_s`` with rounding below one step taken as none."""
    if run.get("rested_s") is not None:
        return float(run["rested_s"])
    if run.get("replans") == 0:
        return 0.0
    rest = float(run["added_rest_s"])
    return rest if rest >= REST_RESOLUTION_S else 0.0


def not_served_of(run: dict) -> float:
    """Load a flight left unserved, A·h (all generators)."""
    return float(sum(((run.get("shed") or {}).get("not_served_Ah") or {}).values()))


def cost_of(run: dict) -> float:
    """A flight's cost at the manager's price, min (:func:`~genthermal.schedule.planning.price.cost_min`)."""
    return cost_min(rest_of(run), max(not_served_of(run), 0.0))


def _ratio(numerator: float, denominator: float):
    return numerator / denominator if denominator > 0 else None


def rest_versus_best_baseline(records: list, candidate: str = "optimal") -> dict:
    """The ``rest_vs_best_baseline`` key (module docstring) over the faulty ``records`` whose
    ``candidate``, heuristic and engineer flights (and the optional baselines it has) all finished.

    ``candidate`` is the optimal scheduler the baselines meet: ``optimal`` (on the model the sweep
    gave it) or :data:`FLOWN_OPTIMAL`; the keys below say ``optimal`` for either.

    Returns
    -------
    dict
        ``per_case``: per case the optimal and best-baseline (by rest) added rest, s, their
        ``ratio`` (None when the baseline does not rest), the load each left unserved, A·h, the
        hindsight plan's rest and load not served (None when not computed), the optimal cost and
        that of the best baseline by cost (``best_baseline_by_cost``), min, their ratio
        ``cost_vs_best_baseline`` (None when that baseline costs nothing) and ``sheds`` (True when
        any of the three leaves load unserved); ``mean_ratio`` (total optimal rest / total
        best-baseline rest), the totals, ``cases_optimal_rests_more``; ``without_shedding``: the
        same rest totals and ratio over the cases where nobody sheds; ``mean_cost_ratio`` and the
        cost totals, min; ``cases_optimal_costs_more`` (more by over one 10-s step of rest).
    """
    per_case = []
    for r in records:
        runs = r["runs"]
        baselines = baselines_of(runs)
        if not r["faulty"] or not all(finished(runs[s]) for s in (*baselines, candidate)):
            continue
        best = min(baselines, key=lambda s: rest_of(runs[s]))
        cheapest = min(baselines, key=lambda s: cost_of(runs[s]))
        optimal, baseline = rest_of(runs[candidate]), rest_of(runs[best])
        optimal_cost, baseline_cost = cost_of(runs[candidate]), cost_of(runs[cheapest])
        hindsight = r.get("hindsight") or {}
        per_case.append({"case": r["name"], "optimal_rest_s": optimal, "best_baseline": best,
                         "best_baseline_rest_s": baseline, "ratio": _ratio(optimal, baseline),
                         "optimal_not_served_Ah": not_served_of(runs[candidate]),
                         "best_baseline_not_served_Ah": not_served_of(runs[best]),
                         "hindsight_rest_s": hindsight.get("rest_s"),
                         "hindsight_not_served_Ah": hindsight.get("not_served_Ah"),
                         "optimal_cost_min": optimal_cost, "best_baseline_by_cost": cheapest,
                         "best_baseline_cost_min": baseline_cost,
                         "cost_vs_best_baseline": _ratio(optimal_cost, baseline_cost),
                         "sheds": any(not_served_of(runs[s]) > NOT_SERVED_RESOLUTION_AH
                                      for s in (*baselines, candidate))})
    optimal_total = sum(c["optimal_rest_s"] for c in per_case)
    best_total = sum(c["best_baseline_rest_s"] for c in per_case)
    calm = [c for c in per_case if not c["sheds"]]
    calm_optimal = sum(c["optimal_rest_s"] for c in calm)
    calm_best = sum(c["best_baseline_rest_s"] for c in calm)
    optimal_cost = sum(c["optimal_cost_min"] for c in per_case)
    best_cost = sum(c["best_baseline_cost_min"] for c in per_case)
    return {"per_case": per_case,
            "mean_ratio": _ratio(optimal_total, best_total),
            "optimal_total_rest_s": optimal_total, "best_baseline_total_rest_s": best_total,
            "cases_optimal_rests_more": [c["case"] for c in per_case
                                         if c["optimal_rest_s"] > c["best_baseline_rest_s"]],
            "without_shedding": {"cases": len(calm), "mean_ratio": _ratio(calm_optimal, calm_best),
                                 "optimal_total_rest_s": calm_optimal, "best_baseline_total_rest_s": calm_best},
            "mean_cost_ratio": _ratio(optimal_cost, best_cost),
            "optimal_total_cost_min": optimal_cost, "best_baseline_total_cost_min": best_cost,
            "cases_optimal_costs_more": [c["case"] for c in per_case
                                         if c["optimal_cost_min"] > c["best_baseline_cost_min"] + PRICE_TOLERANCE_MIN]}
