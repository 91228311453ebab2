"""Fit the earlier least-squares chapter-7 calibration (JSON summary on stdout; ``--write`` ships it).

    python3 benchmarks/fit_chapter7.py [--json FILE] [--write] [--n-flow N] [--managed]

Fits the assumed cooling and loss values of the Genco RF201A (h_top_air, h_end_air, R0, P_iron,
h_ambient, m_dot_fan), the large blockage's flow fraction and convection exponent, and the time
constant of its inlet rise to continuous proxies of the thesis's chapter-7 outcomes
(:mod:`studies.chapter7`), with IPOPT and exact derivatives. ``--write`` replaces
``genthermal/machines/genco_rf201a_chapter7.yaml``; the blockage values (k_flow, n_flow,
inlet_rise_tau_min) go to ``scenarios/chapter7_blockage_large.yaml`` by hand (they are printed).
``--n-flow 0.8`` holds the convection exponent at the turbulent Dittus-Boelter value instead of
fitting it (the comparison in the README's "Reproducing the thesis"). ``--managed`` adds the
managed large blockage (:mod:`studies.chapter7_managed`: displacement alone in the three
K-conditions after the fault and a 10-min rest before landing keep both generators within θmax) to
the fit; the proxies then conflict (README), so the shipped calibration is fitted without it.
Whether any calibration meets every chapter-7 outcome within the thesis's tolerances, with all
assumed values and the blockage's inlet free: ``benchmarks/chapter7_feasibility.py``; the shipped
calibration is now that study's solution with the inlet following gen1's load
(``benchmarks/chapter7_feasibility.py --inlet-follows-load --write``), so ``--write`` here would
replace it with this fit's.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import yaml

from genthermal.coolant import OUTLET_DIAMETER_MM
from genthermal.machines import build_model
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root: studies/
from studies.chapter7 import FIT_BOUNDS, PARAMETER_FILE, SOURCE, fit_chapter7

MACHINE_PARAMETERS = ("h_top_air", "h_end_air", "R0", "P_iron", "h_ambient", "m_dot_fan")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--json", help="also write the JSON here")
    parser.add_argument("--write", action="store_true", help="write the shipped parameter set")
    parser.add_argument("--n-flow", type=float, default=None,
                        help="hold the blockage's convection exponent at this value (e.g. 0.8, Dittus-Boelter) "
                        "instead of fitting it")
    parser.add_argument("--managed", action="store_true",
                        help="also fit the managed large blockage (thesis 7.3.3, Figs 7.13-7.15): the proxies conflict")
    args = parser.parse_args()
    started = time.perf_counter()
    base = build_model()
    result = fit_chapter7(base, n_flow=args.n_flow, managed=args.managed)
    result["fit_s"] = time.perf_counter() - started
    k_flow = result["values"]["k_flow"]
    ratio = (OUTLET_DIAMETER_MM / 10.0) ** 4
    result["outlet_loss_share_implied"] = (1 - k_flow**2) / (k_flow**2 * ratio - 1)
    result["at_bound"] = [n for n, v in result["values"].items()
                          if min(abs(v - FIT_BOUNDS[n][0]), abs(v - FIT_BOUNDS[n][1])) < 1e-6 * max(1.0, abs(v))]
    result["defaults"] = {n: base.parameters.value(n) for n in MACHINE_PARAMETERS}
    text = json.dumps(result, indent=2)
    print(text)
    if args.json:
        Path(args.json).write_text(text)
    if args.write:
        document = {"machine": base.spec.name, "variant": "nonlinear", "parameters": {
            n: {"value": round(result["values"][n], 4), "provenance": "fitted",
                "source": f"{SOURCE}: {FIT_BOUNDS[n][3]}, bounds {FIT_BOUNDS[n][0]:g}-{FIT_BOUNDS[n][1]:g} "
                          f"{FIT_BOUNDS[n][2]}"}
            for n in MACHINE_PARAMETERS}}
        path = Path(__file__).resolve().parents[1] / "genthermal" / "machines" / PARAMETER_FILE
        header = ("# Chapter-7 calibration of the Genco RF201A (studies.chapter7), written by\n"
                  "# benchmarks/fit_chapter7.py --write. load_model('genco_rf201a:chapter7') reads it.\n")
        path.write_text(header + yaml.safe_dump(document, sort_keys=False))


if __name__ == "__main__":
    main()
