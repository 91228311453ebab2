"""What the thesis's managed large blockage asks of the chapter-7 plant (JSON on stdout).

    python3 benchmarks/managed_blockage.py [--json FILE] [--flights]

Thesis 7.3.3 (Figs 7.13-7.15) manages the large blockage "using only load displacement" in the
three K-conditions after the fault and a 10-min rest before landing, with breaches of 110.7 and
111 °C. :func:`studies.chapter7_managed.best_displacement` gives, on the plant (two
copies of the chapter-7 calibration, no manager and no current limit), the lowest worst winding
peak any constant displacement per K-condition reaches. This script takes it for the blockage as
shipped (``scenarios/chapter7_blockage_large.yaml``) and with one part of the fault changed at a
time (``variants``: inlet rise alone, flow reduction alone, a smaller or stepped inlet rise, the
turbulent exponent, the default calibration's orifice flow), and along the flow fraction with the
inlet's time constant refitted so that the no-action blockage still reaches 109 °C 44 min after the
fault (``flow_scan``, :func:`studies.chapter7.fit_inlet_time_constant`). ``--flights``
also flies the thesis heuristic (closed loop, the scenario's settings) on the scan's unblocked end
(flow fraction 1, inlet step) with and without the scenario's rated-current limit.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import sys
import time
from pathlib import Path

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root: studies/
from studies.chapter7 import (BLOCKAGE_INLET_RISE_C, ONSET_S, fit_inlet_time_constant,
                                          no_action_blockage_minutes)
from studies.chapter7_managed import best_displacement
from genthermal.machines import build_model
from genthermal.model_file import load_model
from genthermal.mission import load_mission
from genthermal.schedule.power_system import PowerSystem

SCENARIO = "chapter7_blockage_large"
#: Flow fractions of the scan (the orifice relation's physical range ends at 0.6, FIT_BOUNDS).
FLOW_SCAN = (0.6, 0.7, 0.8, 0.9, 1.0)
#: Current limit of the uncapped flight, % of rated (the most a scenario accepts).
UNCAPPED_PERCENT = 150.0


def _summary(result: dict) -> dict:
    return {"worst_peak_C": result["worst_peak_C"],
            "displaced_A": [c["displaced_A"] for c in result["conditions"]],
            "gen1_peaks_C": [c["gen1_peak_C"] for c in result["conditions"]],
            "gen2_peaks_C": [c["gen2_peak_C"] for c in result["conditions"]],
            "converged": result["converged"]}


def variants(chapter7, fault) -> dict:
    """Lowest reachable worst peak with one part of the fault changed at a time (the scenario's inlet
    rise and load share unless the case changes them)."""
    k, n, tau = fault.values["k_flow"], fault.values["n_flow"], fault.inlet_rise_tau_s
    rise, share = fault.inlet_rise_C, fault.inlet_load_share
    cases = {"as shipped": (chapter7, k, n, rise, tau, share),
             "inlet independent of the load (share 0)": (chapter7, k, n, rise, tau, 0.0),
             "inlet rise alone (k_flow 1)": (chapter7, 1.0, n, rise, tau, share),
             "flow reduction alone (no inlet rise)": (chapter7, k, n, 0.0, tau, share),
             "inlet +16 K": (chapter7, k, n, 16.0, tau, share),
             "inlet step (time constant 0)": (chapter7, k, n, rise, 0.0, share),
             "convection exponent 0.8": (chapter7, k, 0.8, rise, tau, share),
             "default calibration, orifice k_flow 0.11, n 0.8, inlet +31 K step": (build_model(), 0.11, 0.8,
                                                                                   BLOCKAGE_INLET_RISE_C, 0.0, 0.0)}
    return {label: {"k_flow": kf, "n_flow": nf, "inlet_rise_C": r, "inlet_rise_tau_min": t / 60.0,
                    "inlet_load_share": a,
                    **_summary(best_displacement(plant, kf, nf, r, t, ONSET_S, inlet_load_share=a))}
            for label, (plant, kf, nf, r, t, a) in cases.items()}


def flow_scan(chapter7, n_flow: float) -> list:
    """Along the flow fraction, the inlet time constant that keeps the no-action 44 min and the
    lowest reachable worst peak with it (the thesis's +31 K rise, independent of the load)."""
    rows = []
    for k in FLOW_SCAN:
        tau_s, minutes = fit_inlet_time_constant(chapter7, k, n_flow)
        rows.append({"k_flow": k, "inlet_rise_tau_min": tau_s / 60.0, "no_action_minutes": minutes,
                     "no_action_minutes_step": no_action_blockage_minutes(chapter7, k, n_flow, 0.0),
                     **_summary(best_displacement(chapter7, k, n_flow, BLOCKAGE_INLET_RISE_C, tau_s, ONSET_S))})
    return rows


def flights() -> dict:
    """The thesis heuristic on the blockage with flow fraction 1 and an inlet step, with the
    scenario's current limit and with :data:`UNCAPPED_PERCENT`."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from reproduce_thesis import flight_outcome

    document = load_mission(SCENARIO).to_dict()
    document["faults"][0].update({"k_flow": 1.0, "inlet_rise_tau_min": 0.0})
    document["name"] = f"{SCENARIO}_unblocked_flow"
    results = {}
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"{document['name']}.yaml"
        path.write_text(yaml.safe_dump(document, sort_keys=False))
        for label, limit in (("scenario current limit", None), (f"current limit {UNCAPPED_PERCENT:g} %", UNCAPPED_PERCENT)):
            outcome = flight_outcome(str(path), current_limit_percent=limit)
            results[label] = {key: outcome[key] for key in ("peak_gen1_C", "peak_gen2_C", "breach_s",
                                                            "best_effort_from_min", "added_rest_min")}
            results[label]["actions"] = outcome["actions"][4:]
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", help="also write the JSON here")
    parser.add_argument("--flights", action="store_true", help="also fly the unblocked-flow variant in closed loop")
    args = parser.parse_args()
    started = time.perf_counter()
    chapter7 = load_model("genco_rf201a:chapter7")
    fault = PowerSystem.from_mission(load_mission(SCENARIO)).faults[0]
    report = {"variants": variants(chapter7, fault), "flow_scan": flow_scan(chapter7, fault.values["n_flow"])}
    if args.flights:
        report["flights"] = flights()
    report["wall_s"] = time.perf_counter() - started
    text = json.dumps(report, indent=2)
    print(text)
    if args.json:
        Path(args.json).write_text(text)


if __name__ == "__main__":
    main()
