"""``genthermal fly SCENARIO [--scheduler NAME|FILE.py] [--plant NAME|FILE] [--json FILE] [--plot FILE]``:
closed-loop load management (thesis 7.2) on a true plant that differs from the planning model (a
model, an FMU, a Python plant or a replayed log), with detection and identification of faults the
manager is not told. Reference: docs/guide/flights.md, docs/guide/cli.md.
"""

from __future__ import annotations

import sys

from ._common import add_choice_argument
from ._vocabulary import FILTERS, MANAGER_DEFAULTS
from .plan import add_schedule_arguments, settings_from_args, write_outputs

#: What ``fly --help`` says the command does.
FLY_DESCRIPTION = ("Closed-loop load management (thesis 7.2) on the true plant: every cycle a filter update from "
                   "noisy measurements, fault detection on the innovations and identification in flight, a "
                   "prediction to the end of the mission and a re-plan when a violation is predicted. The true "
                   "plant differs from the planning model (scenario generators.plant_mismatch or --plant); the "
                   "manager is not told the faults unless --tell-fault. With --planner-model nonlinear the optimal "
                   "scheduler (or the thesis heuristic, per K-condition) plans on the filter's nonlinear model with "
                   "a back-off from the filter's covariance instead of --margin. --plant also takes an FMI 2.0 "
                   "co-simulation FMU, a Python file defining make_plant() or a recorded flight to replay (--record CSV: the "
                   "manager's decisions are then scored, not applied) (genthermal.plants); a plant that "
                   "fails in flight stops the flight with the fault recorded and the record so far written "
                   "(exit code 3).")


def register(subparsers) -> None:
    """Add the ``fly`` sub-command."""
    parser = subparsers.add_parser("fly", help="fly a mission with closed-loop load management",
                                   description=FLY_DESCRIPTION,
                                   epilog="exit codes: 0 flown, 2 bad input, 3 the plant failed in flight (the fault "
                                   "and the record so far are in --json)")
    add_schedule_arguments(parser)
    parser.add_argument("--seed", default=0, type=int, help="seed of the measurement noise (default 0)")
    parser.add_argument("--tell-fault", action="store_true", help="hand the manager each fault's effect and "
                        "parameters from the first cycle after its onset (the old behaviour, for comparison)")
    add_choice_argument(parser, "--filter", FILTERS,
                        help="filter in the loop — ekf: extended Kalman filter on the flown model (--model) with "
                        "disturbance heat flows; kf: the thesis's linear filter on its design model (default: "
                        f"the scenario's generators.filter, else {MANAGER_DEFAULTS['filter']})")
    parser.add_argument("--record", metavar="FILE.csv", help="write the flight's record (time, temperatures, "
                        "currents, rests) as CSV, kept when the plant fails; --plant FILE.csv replays it")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Fly and print the summary."""
    from ..outputs import write_csv
    from ..plants import external_plant, is_external_plant
    from ..progress import working
    from ..schedule.flight.closed_loop import fly
    from ..schedule.flight.preflight import preflight_check
    from ..schedule.report import flight_summary

    system, settings = settings_from_args(args)
    sensors = tuple(system.planning_model.output_names)
    plant = external_plant(args.plant, sensors) if is_external_plant(args.plant) else None
    print(system.describe() + (f"\n  plant: {args.plant}" if plant is not None else ""))
    if getattr(plant, "replays_log", False):
        print("note: the plant is a replayed log: the manager's decisions are recorded and scored, not applied",
              file=sys.stderr)
    elif plant is not None and any(f.effect for f in system.faults):
        print("note: genthermal applies no fault effect to this plant; its inputs carry the faults' inlet rises and "
              "its reset is told the faults (PlantSetup.faults): what they do inside is the plant's", file=sys.stderr)
    try:
        with working("before take-off"):
            preflight = preflight_check(system, args.scheduler, settings)
        print(f"{preflight['message']} (feasible: {str(preflight['feasible']).lower()}; planning on the "
              f"{preflight['planner_model']} model)")
        with working(f"fly {args.scheduler}"):
            result = fly(system, args.scheduler, settings, plant, preflight)
    finally:
        getattr(plant, "close", lambda: None)()
    summary = flight_summary(result)
    summary["plans"] = result.plans
    if args.record:
        write_csv(result.to_pandas(), args.record)
        print(f"wrote {args.record}")
    write_outputs(args, summary, result, system.limit_C)
    if result.plant_fault is not None:
        print(f"genthermal fly: plant fault at {result.plant_fault['time_s']:g} s: {result.plant_fault['message']}; "
              "the flight stopped there (the record so far is written)", file=sys.stderr)
        return 3
    return 0
