"""The words of the command line: choice spellings and the defaults its help quotes.

Importing this module loads no numerical library, so every ``genthermal CMD --help`` stays fast.
Each value repeats one of the library's (named next to it); ``tests/test_cli_dialect.py`` checks
that they agree. Choices are lower-case and hyphenated on the command line; :func:`library_value`
gives the library's spelling. Reference: docs/guide/cli.md.
"""

from __future__ import annotations

#: Built-in machines (``genthermal.machines.registry.BUILT_IN``) and the default ``--model``.
BUILT_IN_MACHINES = ("genco_rf201a",)
DEFAULT_MODEL = "genco_rf201a"

#: ``--filter`` of estimate and fly (``genthermal.schedule.state_estimator.FLIGHT_FILTERS``).
FILTERS = ("ekf", "kf")
#: ``--scheduler`` of plan and fly (``genthermal.schedule.flight.manager_settings.SCHEDULERS``).
SCHEDULERS = ("heuristic", "engineer", "optimal", "milp")
#: Schedulers that can plan on the flown model (``manager_settings.FLOWN_SCHEDULERS``).
FLOWN_SCHEDULERS = ("optimal", "heuristic")
#: ``--schedulers`` of sweep (``genthermal.schedule.sweeps.sweep.SWEEP_SCHEDULERS``, hyphenated).
SWEEP_SCHEDULERS = ("heuristic", "engineer", "optimal", "milp", "heuristic-flown", "optimal-flown")
#: ``--planner-model`` of plan, fly and sweep (``manager_settings.PLANNER_MODELS``).
PLANNER_MODELS = ("auto", "affine", "nonlinear")
#: ``--when-infeasible`` of plan and fly (``genthermal.schedule.planning.shed.INFEASIBLE_RESPONSES``, hyphenated).
INFEASIBLE_RESPONSES = ("shed", "best-effort")
#: ``--phases`` of diagnose (``genthermal.diagnose.discovery.Discovery`` ``phases``).
PHASES = ("auto", "resolved", "lumped")
#: ``--precision`` of cortex-m4 (``genthermal.embedded.mission.PRECISIONS``).
PRECISIONS = ("double", "single")
#: ``--input`` of sysid: ``auto`` or a current column of the CSV schema, spelt as the column
#: (``genthermal.estimation.arx_search.INPUT_SIGNALS``).
ARX_INPUTS = ("auto", "I_u", "I_v", "I_w", "I_exc", "I_sq")

#: The library's spelling of the choices whose command-line spelling differs.
LIBRARY_SPELLING = {"best-effort": "best_effort", "heuristic-flown": "heuristic_flown",
                    "optimal-flown": "optimal_flown"}
#: Old command-line spellings still accepted, hidden from --help (docs/results use them).
OLD_SPELLINGS = {"heuristic_flown": "heuristic-flown", "optimal_flown": "optimal-flown"}

#: Defaults the help quotes: ``ManagerSettings`` (margin_K, rise_backoff, confidence_sigmas,
#: when_infeasible, filter, cycle_s / 60), ``manager_settings.DEFAULT_REST_BUDGET_FRACTION``,
#: ``schedule.sweeps.sweep.DEFAULT_FLIGHT_CPU_LIMIT_S``, ``synth`` noise, ``estimation.prediction``,
#: ``estimation.node_observer``.
MANAGER_DEFAULTS = {"margin_K": 2.5, "rise_backoff": 0.3, "confidence_sigmas": 2.0, "when_infeasible": "shed",
                    "filter": "ekf", "cycle_min": 5.0, "planner_model": "auto"}
DEFAULT_REST_BUDGET_FRACTION = 0.25
DEFAULT_FLIGHT_CPU_LIMIT_S = 900.0
THESIS_NOISE_VARIANCE_K2 = (0.0082, 0.013)
DEFAULT_CURRENT_NOISE = 0.01
DEFAULT_EVERY_MIN = 10.0
THESIS_STARTS_MIN = (50, 75, 100, 125, 150, 175)
DEFAULT_MARGIN_K = 0.25
DEFAULT_OFFSET_STEP_K = 0.02
DEFAULT_PROCESS_STD_K = 0.2


def cli_spelling(value: str) -> str:
    """The command line's spelling of a choice: an old spelling becomes its hyphenated form."""
    return OLD_SPELLINGS.get(value, value)


def library_value(choice: str) -> str:
    """The library's spelling of a command-line choice (``best-effort`` -> ``best_effort``)."""
    return LIBRARY_SPELLING.get(choice, choice)
