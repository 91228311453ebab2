"""Benchmark: fault detection and identification in flight (issue 9, item 1).

Flies short closed-loop missions (2-4 h, 2-3 generators) on plants whose ``h_end_air``, ``h_top_air``, ``R0``, ``P_iron`` and ``m_dot_fan``
are each off by 10-30 % in a random direction, shared by every generator of a flight (the manager
plans on the nominal model and is not told the faults):

* ``--healthy`` flights without a fault: every fault alarm is a false alarm;
* ``--faulty`` flights with one fault at a random onset on a random generator, cycling through
  the four types the manager watches for: coolant blockage (flow factor 0.3-0.6 with the effect's
  default convection exponent, inlet rise 0-15 K), shorted turn (R_short 0.1-0.5 Ω), end-winding
  stray loss (R_stray 0.1-0.4 Ω), excitation iron loss (k_exc 30-100). The blockage range is the
  milder part of the robustness grid's (0.15-0.6, 0-31 K): a plant that stays above θmax even at
  rest sends the closed loop into a minimum-peak re-plan every cycle, minutes per flight, which a
  detection benchmark does not need to measure.

The manager flies the nominal schedule by default (``ManagerSettings.replan`` False: the filter and
detector run, nothing is re-planned, so the benchmark measures detection, not the schedulers);
``--scheduler engineer`` re-plans with the engineer's heuristic, so that generators carry
different loads once one is found faulty. Cases are seeded (``--seed``), so a run is
reproducible. JSON keys:

``healthy_flights``, ``faulty_flights``   flights flown
``false_alarms``                 fault alarms on generators without a started fault, all flights
``false_alarms_healthy``         of which on the healthy flights
``detected``                     faulty flights with an alarm on the faulty generator after the onset
``detect_delay_s``               median and max of (first such alarm − onset) over the detected flights, s
``identified_correct``           faulty flights whose first identification names the true effect
                                 (and, for a blockage, k_flow within ±``--k-flow-tolerance``)
``identified_correct_or_equivalent``  or lists it among the equivalent explanations (ΔBIC within 2:
                                 a shorted turn and an end-winding stray loss, both ∝ I² in the
                                 winding, are not told apart by the two sensors)
``last_identified_correct``      faulty flights whose last identification (the model flown at the end)
                                 names the true effect
``healthy_peak_statistic``       per node, the highest detector statistic r on the healthy flights
``healthy_peak_sum_over_threshold``  per node, the highest CUSUM sum / threshold there (< 1: no alarm)
``per_type``                     the same per fault type
``flights``                      one record per faulty flight: truth, delay, first identification
``median_flight_s``              median wall-clock time of one flight, s
``scheduler``                    the scheduler (``none``: no re-planning)
``wall_s``                       wall-clock time of the benchmark, s
``provenance``                   the command line and the git commit it ran at
``baseline``                     the same flights judged by the detector the disturbance detector replaced
                                 (:mod:`genthermal.schedule.monitoring.innovation_detector`, a CUSUM on the linear
                                 Kalman filter's differential winding innovations, run on each flight's
                                 record): ``false_alarms``, ``false_alarms_healthy``, ``detected``,
                                 ``detect_delay_s`` (median, max), ``per_type`` delays, ``flights_with_false_alarms``
``versus_baseline``              disturbance detector / baseline: ratios of the median and max delays
                                 and of the false alarms (None where the baseline's figure is 0 or missing),
                                 and the faulty flights each detects that the other misses

Usage::

    python benchmarks/bench_detection.py --json bench_detection.json [--healthy 24 --faulty 12]

Targets (issue 9): median delay ≤ 600 s and 0 false alarms on ≥ 20 healthy flights.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

from genthermal.mission import Mission
from genthermal.commands.sweep import source_commit
from genthermal.schedule.flight.closed_loop import fly
from genthermal.schedule.flight.manager_settings import SCHEDULERS, ManagerSettings
from genthermal.schedule.monitoring.innovation_detector import innovation_cusum_alarms
from genthermal.schedule.power_system import PowerSystem
from genthermal.schedule.report import flight_summary
from genthermal.schedule.sweeps.sweep import K_EXC_MAX, MISMATCH_PARAMETERS, random_actions

FAULT_TYPES = ("coolant_blockage", "phase_short_circuit", "end_winding_stray_loss", "excitation_iron_loss")
#: Fault parameter ranges: the robustness grid's (``genthermal.schedule.sweeps.sweep.robustness_case``).
FAULT_RANGES = {"phase_short_circuit": ("R_short", 0.1, 0.5),
                "end_winding_stray_loss": ("R_stray", 0.1, 0.4),
                "excitation_iron_loss": ("k_exc", 30.0, K_EXC_MAX)}


def detection_case(index: int, kind: str | None, seed: int = 0) -> dict:
    """Mission document of case ``index``: a 2-4 h mission, 2-3 generators, a random plant
    mismatch and, unless ``kind`` is None, one fault of that kind at a random onset."""
    rng = np.random.default_rng([seed, index])
    hours = rng.uniform(2.0, 4.0)
    actions = random_actions(rng, hours)
    count = int(rng.integers(2, 4))
    mismatch = {name: float(1.0 + rng.choice([-1.0, 1.0]) * rng.uniform(0.1, 0.3)) for name in MISMATCH_PARAMETERS}
    onset = float(round(rng.uniform(40.0, hours * 60.0 - 50.0), 1))
    generator = int(rng.integers(1, count + 1))
    faults = []
    if kind == "coolant_blockage":
        faults.append({"generator": generator, "kind": kind, "onset_min": onset,
                       "k_flow": float(rng.uniform(0.3, 0.6)), "inlet_rise_C": float(rng.uniform(0.0, 15.0))})
    elif kind is not None:
        name, low, high = FAULT_RANGES[kind]
        faults.append({"generator": generator, "kind": "effect", "effect": kind, "onset_min": onset,
                       "values": {name: float(rng.uniform(low, high))}})
    return {"name": f"detection{index}:{kind or 'healthy'}:{count}gen:{hours:.1f}h", "actions": actions,
            "generators": {"count": count, "plant_mismatch": mismatch}, "faults": faults}


def flight_record(result):
    """``(currents_A, inlet_C, measured_C)`` (n_generators, ..., n) of a flight: what its manager
    applied and measured, from the fault monitor's record."""
    system, monitor = result.system, result.monitor
    interface = system.planning_model.spec.interface
    frames = [monitor.frame(g) for g in range(system.n_generators)]
    currents = np.array([f[interface.generator.phase_inputs[0]].to_numpy() for f in frames])
    inlet = np.array([f[interface.generator.coolant_input].to_numpy() for f in frames])
    measured = np.array([[f[sensor.columns[0]].to_numpy() for sensor in interface.sensors] for f in frames])
    return currents, inlet, measured


def judge_alarms(system, alarms: list) -> dict:
    """``false_alarms`` (alarms on a generator with no fault started by then) and ``detect_delay_s``
    (first alarm on a generator whose fault had started, minus that fault's onset; None: none) of
    ``alarms`` (``time_s``, ``generator``), as :func:`genthermal.schedule.report.detection_summary`
    judges the flight's own."""
    def onset(g, t_s):
        started = [f.onset_s for f in system.faults if f.generator == g and f.onset_s <= t_s + 1e-9]
        return min(started) if started else None
    true = [(a["time_s"], onset(a["generator"], a["time_s"])) for a in alarms
            if onset(a["generator"], a["time_s"]) is not None]
    first = min(true, default=None)
    return {"false_alarms": len(alarms) - len(true), "detect_delay_s": None if first is None else float(first[0] - first[1])}


def baseline_detection(result, settings: ManagerSettings) -> dict:
    """The baseline detector run on ``result``'s record, judged by :func:`judge_alarms`."""
    system = result.system
    alarms = innovation_cusum_alarms(system.design_generator_for(()), *flight_record(result),
                                     system.mission.T_ambient_C, settings.dt_s,
                                     max(int(round(settings.cycle_s / settings.dt_s)), 1))
    return {**judge_alarms(system, alarms), "alarms": alarms}


def fly_case(document: dict, k_flow_tolerance: float, scheduler: str = "none") -> dict:
    """Fly one case (``scheduler`` ``none``: no re-planning); its detection record."""
    system = PowerSystem.from_mission(Mission.from_dict(document))
    started = time.perf_counter()
    settings = ManagerSettings(replan=scheduler != "none")
    result = fly(system, "engineer" if scheduler == "none" else scheduler, settings)
    summary = flight_summary(result)
    detector = result.monitor.detector
    baseline = baseline_detection(result, settings)
    print(f"{document['name']}: {time.perf_counter() - started:.1f} s, delay {summary['detect_delay_s']}, "
          f"false alarms {summary['false_alarms']}; baseline: delay {baseline['detect_delay_s']}, false alarms "
          f"{baseline['false_alarms']}", file=sys.stderr, flush=True)
    record = {"name": document["name"], "false_alarms": summary["false_alarms"],
              "detect_delay_s": summary["detect_delay_s"], "flight_s": time.perf_counter() - started,
              "baseline": baseline,
              "peak_statistic": dict(zip(result.monitor.node_roles, detector.peak_statistic.tolist())),
              "peak_sum_over_threshold": dict(zip(result.monitor.node_roles,
                                                  (detector.peak_sum / detector.threshold).tolist()))}
    if not system.faults:
        return record
    fault = system.faults[0]
    name = system.generator_names[fault.generator]
    first = next((i for i in summary["identified"] if i["generator"] == name and i["effect"]), None)
    last = next((i for i in reversed(summary["identified"]) if i["generator"] == name and i["effect"]), None)

    def judged(found):
        """(names the true effect, names it or lists it as equivalent)."""
        if found is None:
            return False, False
        if fault.effect == "coolant_flow_reduction" and found["effect"] == fault.effect:
            right = abs(found["parameters"]["k_flow"] - fault.values["k_flow"]) <= k_flow_tolerance
            return right, right
        return found["effect"] == fault.effect, fault.effect in [found["effect"], *found["confidence"]["equivalent"]]
    correct, equivalent = judged(first)
    record.update(last_identification=last, last_identified_correct=judged(last)[0])
    record.update(type=fault.effect, truth={"generator": name, "onset_s": fault.onset_s, **fault.values,
                                             "inlet_rise_C": fault.inlet_rise_C},
                  first_identification=first, identified_correct=bool(correct),
                  identified_correct_or_equivalent=bool(equivalent),
                  identifications=len(summary["identified"]), breach_s=summary["breach_s"])
    return record


def summarise(healthy: list, faulty: list, scheduler: str, wall_s: float) -> dict:
    """The benchmark keys (module docstring)."""
    def delays(records):
        values = [r["detect_delay_s"] for r in records if r["detect_delay_s"] is not None]
        return {"median": float(np.median(values)) if values else None,
                "max": float(max(values)) if values else None, "detected": len(values), "flights": len(records)}
    per_type = {}
    for kind in sorted({r["type"] for r in faulty}):
        records = [r for r in faulty if r["type"] == kind]
        per_type[kind] = {"detect_delay_s": delays(records),
                          "identified_correct": sum(r["identified_correct"] for r in records),
                          "identified_correct_or_equivalent": sum(r["identified_correct_or_equivalent"]
                                                                  for r in records)}
    overall = delays(faulty)
    baseline = baseline_summary(healthy, faulty)
    return {"healthy_flights": len(healthy), "faulty_flights": len(faulty),
            "false_alarms": int(sum(r["false_alarms"] for r in healthy + faulty)),
            "false_alarms_healthy": int(sum(r["false_alarms"] for r in healthy)),
            "detected": overall["detected"],
            "detect_delay_s": {"median": overall["median"], "max": overall["max"]},
            "identified_correct": int(sum(r["identified_correct"] for r in faulty)),
            "identified_correct_or_equivalent": int(sum(r["identified_correct_or_equivalent"] for r in faulty)),
            "last_identified_correct": int(sum(r["last_identified_correct"] for r in faulty)),
            "healthy_peak_statistic": {role: max((r["peak_statistic"][role] for r in healthy), default=None)
                                       for role in ("winding", "iron")},
            "healthy_peak_sum_over_threshold": {role: max((r["peak_sum_over_threshold"][role] for r in healthy),
                                                          default=None) for role in ("winding", "iron")},
            "per_type": per_type, "flights": faulty,
            "median_flight_s": float(np.median([r["flight_s"] for r in healthy + faulty])),
            "scheduler": scheduler, "wall_s": wall_s,
            "baseline": baseline, "versus_baseline": versus_baseline(healthy, faulty, overall, baseline)}


def baseline_summary(healthy: list, faulty: list) -> dict:
    """The ``baseline`` key (module docstring) from the flights' ``baseline`` records."""
    def delays(records):
        values = [r["baseline"]["detect_delay_s"] for r in records if r["baseline"]["detect_delay_s"] is not None]
        return {"median": float(np.median(values)) if values else None,
                "max": float(max(values)) if values else None, "detected": len(values), "flights": len(records)}
    overall = delays(faulty)
    return {"false_alarms": int(sum(r["baseline"]["false_alarms"] for r in healthy + faulty)),
            "false_alarms_healthy": int(sum(r["baseline"]["false_alarms"] for r in healthy)),
            "flights_with_false_alarms": sum(r["baseline"]["false_alarms"] > 0 for r in healthy + faulty),
            "detected": overall["detected"], "detect_delay_s": {"median": overall["median"], "max": overall["max"]},
            "per_type": {kind: delays([r for r in faulty if r["type"] == kind])
                         for kind in sorted({r["type"] for r in faulty})}}


def versus_baseline(healthy: list, faulty: list, delays: dict, baseline: dict) -> dict:
    """The ``versus_baseline`` key (module docstring): the disturbance detector's figures over the
    baseline's."""
    def ratio(ours, theirs):
        return None if ours is None or not theirs else float(ours) / float(theirs)
    ours_false = int(sum(r["false_alarms"] for r in healthy + faulty))
    return {"median_delay_ratio": ratio(delays["median"], baseline["detect_delay_s"]["median"]),
            "max_delay_ratio": ratio(delays["max"], baseline["detect_delay_s"]["max"]),
            "false_alarm_ratio": ratio(ours_false, baseline["false_alarms"]),
            "detected_only_by_disturbance_detector": [r["name"] for r in faulty if r["detect_delay_s"] is not None
                                                      and r["baseline"]["detect_delay_s"] is None],
            "detected_only_by_baseline": [r["name"] for r in faulty if r["detect_delay_s"] is None
                                          and r["baseline"]["detect_delay_s"] is not None]}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--json", help="write the report here (default: print only)")
    parser.add_argument("--healthy", type=int, default=24, help="healthy flights (>= 20 for the target)")
    parser.add_argument("--faulty", type=int, default=12, help="faulty flights (the four types in turn)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--scheduler", default="none", choices=("none", *SCHEDULERS),
                        help="re-plan with this scheduler (default none: fly the nominal schedule)")
    parser.add_argument("--k-flow-tolerance", type=float, default=0.1,
                        help="a blockage counts as identified when k_flow is within this of the truth")
    args = parser.parse_args(argv)
    for name in ("healthy", "faulty"):
        if getattr(args, name) < 0:
            parser.error(f"--{name} must be >= 0, got {getattr(args, name)}")
    started = time.perf_counter()
    healthy = [fly_case(detection_case(i, None, args.seed), args.k_flow_tolerance, args.scheduler)
               for i in range(args.healthy)]
    faulty = [fly_case(detection_case(args.healthy + i, FAULT_TYPES[i % len(FAULT_TYPES)], args.seed),
                       args.k_flow_tolerance, args.scheduler) for i in range(args.faulty)]
    report = summarise(healthy, faulty, args.scheduler, time.perf_counter() - started)
    report["provenance"] = {"command": " ".join(["python", "benchmarks/bench_detection.py", *sys.argv[1:]]),
                            "commit": source_commit()}
    text = json.dumps(report, indent=2)
    print(text)
    if args.json:
        with open(args.json, "w", encoding="utf-8") as handle:
            handle.write(text + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
