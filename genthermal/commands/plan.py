"""``genthermal plan SCENARIO [--scheduler NAME] [--json FILE]``: an open-loop load-management plan
(thesis chapter 7): the mission flown as planned until the first management cycle after the fault
onset, then one schedule of displaced current and rests for the rest of it. Also the options and
settings ``fly`` shares. Reference: docs/guide/scheduling.md and docs/guide/cli.md.
"""

from __future__ import annotations

import dataclasses

from ..errors import InputError
from ._common import (add_choice_argument, add_json_argument, add_model_arguments, load_model_option,
                      parse_assignments, with_overrides)
from ._vocabulary import (DEFAULT_REST_BUDGET_FRACTION, INFEASIBLE_RESPONSES, MANAGER_DEFAULTS, PLANNER_MODELS,
                          SCHEDULERS, library_value)

#: What ``plan --description`` says (``fly`` has its own).
PLAN_DESCRIPTION = ("Open-loop load-management plan on the linear design model (thesis chapter 7): the mission is "
                    "flown as planned until the first management cycle after the fault onset, then one schedule "
                    "(displaced current per generator and rest before each action) is planned for the rest of the "
                    "mission. With --planner-model nonlinear the optimal scheduler (per management cycle) or the "
                    "thesis heuristic (per K-condition) plans and flies on the nonlinear model (back-off from the "
                    "filter's initial covariance: no measurements in open loop).")


def add_schedule_arguments(parser) -> None:
    """Arguments shared by ``plan`` and ``fly``."""
    parser.add_argument("scenario", help="scenario name (see scenarios/) or path to a YAML file with "
                        "generators and faults (see genthermal.schedule.power_system)")
    add_choice_argument(parser, "--scheduler", SCHEDULERS, default="optimal", or_file=".py",
                        help="the load manager's scheduler (default optimal), or a Python file that registers a "
                        "planner (my_planner.py: running it is your decision; see docs/guide/flights.md)")
    add_json_argument(parser, "the summary (peaks, breach, rest, shed load, plans; schedule table of plan)")
    parser.add_argument("--plot", metavar="FILE.png", help="write a plot of the currents and temperatures")
    parser.add_argument("--margin", default=None, metavar="K",
                        help="back-off margin below the limit, K (default: the scenario's generators.margin_K, "
                        f"else {MANAGER_DEFAULTS['margin_K']:g})")
    parser.add_argument("--rise-backoff", default=str(MANAGER_DEFAULTS["rise_backoff"]), metavar="FRACTION",
                        help="plans tolerate a design model that underestimates a temperature rise within one "
                        f"cycle by this fraction (default {MANAGER_DEFAULTS['rise_backoff']:g}; 0 = margin only)")
    parser.add_argument("--cycle-min", default=f"{MANAGER_DEFAULTS['cycle_min']:g}", metavar="MIN",
                        help=f"management cycle, min (default {MANAGER_DEFAULTS['cycle_min']:g}, thesis 7.2)")
    parser.add_argument("--rest-budget-min", default=None, metavar="MIN",
                        help="most rest the whole flight may add, min (default "
                        f"{100 * DEFAULT_REST_BUDGET_FRACTION:g} %% of the mission); when it is spent, or no rest "
                        "keeps a generator within the limit, the manager switches that generator off and sheds load")
    add_choice_argument(parser, "--planner-model", PLANNER_MODELS, default=MANAGER_DEFAULTS["planner_model"],
                        help="what the optimal scheduler or the heuristic plans on — auto (default): each "
                        "scheduler's own default, the flown model for the optimal scheduler with the filter ekf, else the "
                        "design model; affine: the linear design "
                        "model within θmax minus --margin, with --rise-backoff; nonlinear: the flown model "
                        "the filter runs on (--model with the faults believed), within θmax minus a back-off of "
                        "--confidence-sigmas standard deviations of the filter's covariance, displacement and rest "
                        "free per management cycle (the heuristic: per K-condition)")
    parser.add_argument("--confidence-sigmas", default=str(MANAGER_DEFAULTS["confidence_sigmas"]), metavar="N",
                        help="nonlinear planner: standard deviations of the predicted temperature kept below θmax "
                        f"(default {MANAGER_DEFAULTS['confidence_sigmas']:g})")
    add_choice_argument(parser, "--when-infeasible", INFEASIBLE_RESPONSES, default=None,
                        help="when even the lowest reachable peak is above the limit — shed: shed load (each "
                        "generator carries at most what keeps it within the limit, the rest is not served); "
                        "best-effort: fly the scheduler's own plan, all load served, breaching the limit as "
                        "predicted (the thesis heuristic has no shedding) (default: the scenario's "
                        f"generators.when_infeasible, else {MANAGER_DEFAULTS['when_infeasible']})")
    add_model_arguments(parser, what="the model the manager plans on and filters with (default: the scenario's "
                        "machine; --param changes it, and so the default plant built from it)", default=None)
    parser.add_argument("--plant", metavar="NAME|FILE", help="true plant of every generator before its faults: "
                        "a built-in name or a model file; default the planning model with the scenario's plant_mismatch. fly also "
                        "takes an FMI 2.0 co-simulation FMU (model.fmu), a recorded flight to replay (log.csv) or a "
                        "Python file defining make_plant() "
                        "(my_plant.py: running it is your decision; see docs/guide/flights.md)")


def _number_in(option: str, text: str, low: float, high: float, what: str) -> float:
    """Parse a number in ``[low, high]`` for ``option`` or raise InputError naming it."""
    try:
        value = float(text)
    except ValueError:
        raise InputError(option, text, f"must be {what} in {low:g}..{high:g}") from None
    if not low <= value <= high:
        raise InputError(option, text, f"must be {what} in {low:g}..{high:g}")
    return value


def settings_from_args(args) -> tuple[PowerSystem, ManagerSettings]:
    """The power system and settings the arguments describe; InputError names a bad option."""
    from ..mission import load_mission
    from ..plants import is_external_plant
    from ..schedule.flight.manager_settings import ManagerSettings
    from ..schedule.planning.registry import load_planner_file, planner, planner_names
    from ..schedule.power_system import PowerSystem

    parse_assignments(getattr(args, "param", None) or [])  # a malformed --param is refused before any model is built
    if str(args.scheduler).endswith(".py"):  # a planner file of the user's: registers one planner
        args.scheduler = load_planner_file(args.scheduler)
    if args.scheduler not in planner_names():
        raise InputError("--scheduler", args.scheduler, f"must be one of {', '.join(planner_names())}")
    margin = ManagerSettings.margin_K if args.margin is None else _number_in("--margin", args.margin, 0.0, 50.0,
                                                                              "a number of kelvin")
    backoff = _number_in("--rise-backoff", args.rise_backoff, 0.0, 5.0, "a fraction")
    cycle_min = _number_in("--cycle-min", args.cycle_min, 1.0, 60.0, "a number of minutes")  # 1 plan per cycle
    budget_min = None
    if getattr(args, "rest_budget_min", None) is not None:
        budget_min = _number_in("--rest-budget-min", args.rest_budget_min, 0.0, 24 * 60.0, "a number of minutes")
    planner_model = getattr(args, "planner_model", ManagerSettings.planner_model)
    if planner_model == "nonlinear" and not planner(args.scheduler).on_flown_model:
        raise InputError("--planner-model", planner_model, "only the optimal scheduler and the thesis heuristic plan "
                         "on the flown model: use --scheduler optimal or heuristic (the engineer's heuristic and the "
                         "MILP plan on the design model)")
    if planner_model == "nonlinear" and getattr(args, "filter", None) not in (None, "ekf"):
        raise InputError("--filter", args.filter, "the nonlinear planner plans on the extended Kalman filter's "
                         "model and covariance: use --filter ekf")
    sigmas = _number_in("--confidence-sigmas", getattr(args, "confidence_sigmas", "2"), 0.0, 10.0,
                        "a number of standard deviations")
    settings = ManagerSettings(cycle_s=60.0 * cycle_min, margin_K=margin, rise_backoff=backoff,
                               rest_budget_s=None if budget_min is None else 60.0 * budget_min,
                               planner_model=planner_model, confidence_sigmas=sigmas)
    if getattr(args, "seed", None) is not None:
        if int(args.seed) < 0:
            raise InputError("--seed", args.seed, "must be a whole number >= 0")
        settings = dataclasses.replace(settings, seed=int(args.seed))
    if getattr(args, "filter", None) is not None:
        settings = dataclasses.replace(settings, filter=args.filter)
    when_infeasible = getattr(args, "when_infeasible", None)
    if when_infeasible is not None:
        if when_infeasible not in INFEASIBLE_RESPONSES:  # a caller's own parser
            raise InputError("--when-infeasible", when_infeasible, f"must be one of {', '.join(INFEASIBLE_RESPONSES)}")
        settings = dataclasses.replace(settings, when_infeasible=library_value(when_infeasible))
    if getattr(args, "tell_fault", False):
        settings = dataclasses.replace(settings, tell_fault=True)
    system = PowerSystem.from_mission(load_mission(args.scenario))
    if args.margin is not None:  # the option overrides the scenario's margin
        system = dataclasses.replace(system, margin_K=None)
    if getattr(args, "filter", None) is not None:  # and --filter the scenario's filter
        system = dataclasses.replace(system, filter=None)
    if when_infeasible is not None:  # and --when-infeasible the scenario's response
        system = dataclasses.replace(system, when_infeasible=None)
    models = {}
    for option in ("model", "plant"):
        if option == "plant" and is_external_plant(getattr(args, option, None)):
            continue  # flown by fly (genthermal.plants), not loaded as a model
        if getattr(args, option, None):
            model = load_model_option(f"--{option}", getattr(args, option))
            if model.spec.variant == "linear":
                raise InputError(f"--{option}", getattr(args, option), "give a nonlinear simulation model; the "
                                 "manager derives its design model itself")
            models[option] = model
    if models:
        system = dataclasses.replace(system, **models)
    if getattr(args, "param", None):
        system = dataclasses.replace(system, model=with_overrides(system.planning_model, args.param))
    return system, settings


def write_outputs(args, summary: dict, result, limit_C: float) -> None:
    """Print the summary, write the JSON and the plot when asked."""
    from ..outputs import report_json
    from ..schedule.report import plot_flight, summary_text

    print(summary_text(summary, limit_C))
    if args.json:
        report_json(args.json, summary)
    if args.plot:
        plot_flight(result, path=args.plot)
        print(f"wrote {args.plot}")


def register(subparsers) -> None:
    """Add the ``plan`` sub-command."""
    parser = subparsers.add_parser("plan", help="plan load displacement and rests (open loop, design model)",
                                   description=PLAN_DESCRIPTION)
    add_schedule_arguments(parser)
    parser.set_defaults(func=run)


def run(args) -> int:
    """Plan, print the schedule table and the summary."""
    from ..plants import is_external_plant
    from ..progress import working
    from ..schedule.flight.open_loop import plan_mission
    from ..schedule.report import flight_summary

    if is_external_plant(args.plant):
        raise InputError("--plant", args.plant, "plan flies its plan on the planning model; an FMU, a log or a Python "
                         "plant is flown with genthermal fly")
    system, settings = settings_from_args(args)
    print(system.describe())
    with working(f"plan {args.scheduler}"):
        result = plan_mission(system, args.scheduler, settings)
    summary = flight_summary(result)
    summary["schedule"] = [] if result.schedule_table is None else result.schedule_table.to_dict("records")
    summary["plans"] = result.plans
    if result.schedule_table is not None:
        print(result.schedule_table.to_string(index=False))
    write_outputs(args, summary, result, system.limit_C)
    return 0
