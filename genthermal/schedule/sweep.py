"""Robustness sweep: closed-loop flights on plants the manager does not know, run on Dask.

Each case draws (seeded) a mission of 2-8 h, 2-4 generators, plant parameters off by up to
±30 % (``h_end_air``, ``h_top_air``, ``R0``, ``P_iron``, ``m_dot_fan``, each up or down) and one
fault the manager is not told, at a random onset on a random generator: a coolant blockage (flow
factor 0.15-0.6 and an inlet rise), a shorted turn, an end-winding stray loss or an excitation
iron loss; a share of the cases are healthy (for the false-alarm rate). Every case is flown with
every scheduler. Keys of :func:`summarise` (benchmark JSON):

``robustness.cases``                 number of cases
``robustness.breach_s``              per scheduler: the longest time above θmax over the cases (any generator), s
``robustness.breach_free_fraction``  per scheduler: share of cases with no time above θmax
``rest_vs_best_baseline``            per faulty case: optimal added rest / best of heuristic and engineer (None when both are 0)
``detect_delay_s``                   median and max over the faulty cases detected, and how many were detected
``false_alarms``                     fault alarms on generators without a started fault, total, and healthy flights flown
"""

from __future__ import annotations

import numpy as np

from ..mission import Mission

MISMATCH_PARAMETERS = ("h_end_air", "h_top_air", "R0", "P_iron", "m_dot_fan")
FAULT_TYPES = ("coolant_blockage", "phase_short_circuit", "end_winding_stray_loss", "excitation_iron_loss", "healthy")


def random_actions(rng: np.random.Generator, hours: float) -> list:
    """Mission actions of ``hours`` (h): the thesis's four 15-min start-up conditions, cruise
    (condition 5) or cruise/combat (6) legs of 20-60 min drawn from ``rng``, and a 20-min landing."""
    actions = [{"condition": c, "duration_min": 15} for c in (1, 2, 3, 4)]
    remaining = hours * 60.0 - 60.0 - 20.0
    while remaining >= 15.0:
        minutes = round(float(rng.uniform(20.0, 60.0)), 1)
        minutes = remaining if remaining - minutes < 15.0 else minutes
        actions.append({"condition": int(rng.choice([5, 6])), "duration_min": round(minutes, 1)})
        remaining -= round(minutes, 1)
    actions.append({"condition": 7, "duration_min": 20})
    return actions


def robustness_case(index: int, seed: int = 0) -> dict:
    """The mission document (with ``generators`` and ``faults``) of case ``index``."""
    rng = np.random.default_rng([seed, index])
    hours = rng.uniform(2.0, 8.0)
    actions = random_actions(rng, hours)
    count = int(rng.integers(2, 5))
    mismatch = {name: float(1.0 + rng.choice([-1.0, 1.0]) * rng.uniform(0.1, 0.3)) for name in MISMATCH_PARAMETERS}
    kind = FAULT_TYPES[index % len(FAULT_TYPES)]
    onset = float(round(rng.uniform(45.0, max(50.0, hours * 60.0 - 60.0)), 1))
    generator = int(rng.integers(1, count + 1))
    faults = []
    if kind == "coolant_blockage":
        faults.append({"generator": generator, "kind": kind, "onset_min": onset,
                       "k_flow": float(rng.uniform(0.15, 0.6)), "inlet_rise_C": float(rng.uniform(0.0, 31.0))})
    elif kind != "healthy":
        values = {"phase_short_circuit": {"R_short": rng.uniform(0.1, 0.5)},
                  "end_winding_stray_loss": {"R_stray": rng.uniform(0.1, 0.4)},
                  "excitation_iron_loss": {"k_exc": rng.uniform(30.0, 150.0)}}[kind]
        faults.append({"generator": generator, "kind": "effect", "effect": kind, "onset_min": onset,
                       "values": {k: float(v) for k, v in values.items()}})
    return {"name": f"case{index}:{kind}:{count}gen:{hours:.1f}h", "actions": actions,
            "generators": {"count": count, "plant_mismatch": mismatch}, "faults": faults}


def fly_case(document: dict, schedulers) -> dict:
    """Fly one case with every scheduler; the flight summaries by scheduler."""
    from .closed_loop import fly
    from .power_system import PowerSystem
    from .report import flight_summary

    system = PowerSystem.from_mission(Mission.from_dict(document))
    runs = {}
    for scheduler in schedulers:
        summary = flight_summary(fly(system, scheduler))
        summary.pop("warnings")
        runs[scheduler] = summary
    return {"name": document["name"], "faulty": bool(document["faults"]), "runs": runs}


def run_sweep(documents, schedulers, cluster: str | None = None, workers: int = 2, progress: bool = True) -> list:
    """Fly every case on Dask: a :class:`distributed.LocalCluster` of ``workers`` processes, or the
    scheduler at ``cluster`` (``tcp://host:8786``); a tqdm bar when ``progress``."""
    from distributed import Client, LocalCluster, as_completed
    from tqdm import tqdm

    local = None if cluster else LocalCluster(n_workers=workers, threads_per_worker=1, processes=True)
    client = Client(cluster or local)
    try:
        futures = client.map(fly_case, list(documents), schedulers=tuple(schedulers), pure=False)
        records = [f.result() for f in tqdm(as_completed(futures), total=len(futures), disable=not progress,
                                            desc="flights")]
    finally:
        client.close()
        if local is not None:
            local.close()
    return sorted(records, key=lambda r: int(r["name"].split(":")[0][4:]))


def summarise(records: list, schedulers) -> dict:
    """The robustness keys (module docstring)."""
    faulty = [r for r in records if r["faulty"]]
    healthy = [r for r in records if not r["faulty"]]
    ratios = []
    if "optimal" in schedulers and {"heuristic", "engineer"} <= set(schedulers):
        for r in faulty:
            best = min(r["runs"]["heuristic"]["added_rest_s"], r["runs"]["engineer"]["added_rest_s"])
            optimal = r["runs"]["optimal"]["added_rest_s"]
            ratios.append(None if best <= 0 and optimal <= 0 else (float("inf") if best <= 0 else optimal / best))
    delays = [r["runs"][s]["detect_delay_s"] for r in faulty for s in schedulers
              if r["runs"][s].get("detect_delay_s") is not None]
    return {
        "robustness": {
            "cases": len(records),
            "breach_s": {s: max(r["runs"][s]["breach_s"] for r in records) for s in schedulers},
            "breach_free_fraction": {s: float(np.mean([r["runs"][s]["breach_s"] == 0 for r in records]))
                                     for s in schedulers},
        },
        "rest_vs_best_baseline": ratios,
        "detect_delay_s": {"median": float(np.median(delays)) if delays else None,
                           "max": float(max(delays)) if delays else None,
                           "detected_flights": len(delays),
                           "faulty_flights": len(faulty) * len(schedulers)},
        "false_alarms": {"total": int(sum(r["runs"][s]["false_alarms"] for r in records for s in schedulers)),
                         "on_healthy_flights": int(sum(r["runs"][s]["false_alarms"] for r in healthy
                                                       for s in schedulers)),
                         "healthy_flights": len(healthy) * len(schedulers)},
    }
