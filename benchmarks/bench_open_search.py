"""Leave-one-effect-out evaluation of the open search for a heat flow no catalogue names.

For each catalogue effect: inject it into a 4-hour mission (the nonlinear plant; the two effects of
the linear design model into that model), diagnose with the catalogue *without* that effect (does
the residual test say something is missing?), then run the open search over the generic library
(:func:`genthermal.diagnose.open_search.open_search`) and check that it finds terms (one, or a
jointly fitted pair) that all have the right node group and form (:data:`EXPECTED`), and that the RMSE after them is
at most 2 x the estimated noise.

Usage: ``python benchmarks/bench_open_search.py [--json FILE] [--dt 60] [--only EFFECT ...]``. Prints
one JSON line per effect, then a JSON summary (found, of, seconds, cpu_seconds).
"""

from __future__ import annotations

import argparse
import json
import resource
import time
from pathlib import Path

from genthermal.design import linear_design_model
from genthermal.diagnose.catalogue import Catalogue
from genthermal.diagnose.discovery import Discovery
from genthermal.diagnose.hidden import make_hidden_effect_case
from genthermal.diagnose.open_search import describe_term, heat_flow_library
from genthermal.machines import build_model

#: The library terms that count as the right node group and form for each catalogue effect (a
#: blockage lowers both the air streams' advective conductance and the internal convection, so
#: either term alone or the two together are the right answer).
EXPECTED = {
    "coolant_flow_reduction": {"conductance_air_streams", "conductance_internal_convection"},
    "phase_short_circuit": {"heat_I_u2_slot_winding"},
    "excitation_iron_loss": {"heat_I_exc2_stator_iron"},
    "winding_insulation_degradation": {"conductance_winding_insulation"},
    "end_winding_stray_loss": {"heat_I2_end_windings"},
    "frame_cooling_change": {"conductance_frame_to_ambient"},
    "copper_resistance_temperature": {"loss_theta_copper", "heat_I2_theta_slot_winding"},
    "quadratic_copper_loss": {"loss_I2_copper", "heat_I2_slot_winding", "heat_I2_end_windings"},
}
LINEAR_EFFECTS = ("copper_resistance_temperature", "quadratic_copper_loss")


def _cpu_seconds() -> float:
    """CPU time of this process and its finished children (the fitting workers), s."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", help="write the rows and summary to this file as well")
    parser.add_argument("--dt", type=float, default=60.0, help="sample period of the records, s")
    parser.add_argument("--only", nargs="+", choices=list(EXPECTED), metavar="EFFECT",
                        help=f"run only these injected effects (of {', '.join(EXPECTED)})")
    args = parser.parse_args()
    plant = build_model()
    design = linear_design_model(plant)
    discovery, library = {}, {}  # one per model: what they build is reused across the records
    rows, started, cpu_started = [], time.perf_counter(), _cpu_seconds()
    for seed, effect in enumerate(EXPECTED, start=31):
        if args.only and effect not in args.only:
            continue
        model = design if effect in LINEAR_EFFECTS else plant
        case = make_hidden_effect_case(effect, mission="thesis_fig_7_7", dt_s=args.dt, seed=seed, plant=model,
                                       unbalance=0.3 if effect == "phase_short_circuit" else 0.0)
        t0 = time.perf_counter()
        shared = discovery.setdefault(model.name, Discovery())
        reduced = shared.with_settings(candidates=Catalogue.registered().without(effect)).fit(model, case.data)
        generic = library.setdefault(model.name, Catalogue.of(heat_flow_library(model)))
        t_open, cpu_open = time.perf_counter(), _cpu_seconds()
        found = shared.with_settings(candidates=generic).fit(model, case.data)
        t_open, cpu_open = time.perf_counter() - t_open, _cpu_seconds() - cpu_open
        top = found.iterations[0].ranked[0]
        terms = [f.effect for f in found.found]
        row = {"effect": effect, "truth": case.truth(), "catalogue_without_it": reduced.verdict,
               "unexplained_without_it": reduced.unexplained, "open_search": terms,
               "described": [describe_term(f, found.catalogue) for f in found.found],
               "top_term": top.effect, "right_group_and_form": bool(terms) and set(terms) <= EXPECTED[effect],
               "rmse_before_K": round(top.rmse_before, 4), "rmse_after_K": round(found.iterations[0].rmse_after, 4),
               "noise_K": round(found.noise_std, 4),
               "rmse_within_2_noise": bool(found.iterations[0].rmse_after <= 2 * found.noise_std),
               "seconds": round(time.perf_counter() - t0, 1), "open_search_seconds": round(t_open, 1),
               "open_search_cpu_seconds": round(cpu_open, 1)}
        rows.append(row)
        print(json.dumps(row), flush=True)
    summary = {"benchmark": "open search, leave one catalogue effect out", "dt_s": args.dt,
               "found": sum(r["right_group_and_form"] and r["rmse_within_2_noise"] for r in rows), "of": len(rows),
               "target": 6, "seconds": round(time.perf_counter() - started, 1),
               "cpu_seconds": round(_cpu_seconds() - cpu_started, 1)}
    print(json.dumps(summary))
    if args.json:
        Path(args.json).write_text(json.dumps({"rows": rows, "summary": summary}, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
