"""``genthermal fly SCENARIO --scheduler heuristic|optimal|milp --json FILE [--plot FILE]``.

Closed-loop load management (thesis 7.2) on the true plant: every cycle a Kalman filter update from
noisy measurements, a prediction to the end of the mission and a re-plan when a violation is
predicted. The true plant differs from the design model (scenario ``generators.plant_mismatch``).
"""

from __future__ import annotations

from ..schedule.report import flight_summary
from .plan import add_schedule_arguments, settings_from_args, write_outputs


def register(subparsers) -> None:
    """Add the ``fly`` sub-command."""
    parser = subparsers.add_parser("fly", help="fly a mission with closed-loop load management",
                                   description=__doc__.split("\n\n")[1])
    add_schedule_arguments(parser)
    parser.add_argument("--seed", default=0, type=int, help="seed of the measurement noise (default 0)")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Fly and print the summary."""
    from ..schedule.closed_loop import fly

    system, settings = settings_from_args(args)
    print(system.describe())
    result = fly(system, args.scheduler, settings)
    summary = flight_summary(result)
    summary["plans"] = result.plans
    write_outputs(args, summary, result, system.limit_C)
    return 0
