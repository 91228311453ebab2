"""Planners by name: ``plan_with(scheduler, ...)`` and ``fly --scheduler`` look the scheduler up here.

A planner is a function ``plan(problem, settings, previous) -> PlanResult`` on a
:class:`~genthermal.schedule.planning.plan.PlanningProblem`; a new scheduler is one file that calls
:func:`register_planner` (``fly --scheduler my_planner.py`` runs it: :func:`load_planner_file`). The built-in ones (thesis heuristic, engineer, optimal, MILP) are
registered below, each with the field of the manager's settings that holds its own settings and the
model it plans on by default (:func:`model_for`: the optimal scheduler on the flown model).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Callable

from ...errors import InputError
from ...user_files import run_user_file
from .engineer import engineer_plan
from .heuristic import heuristic_plan
from .milp import milp_plan
from .optimal import optimal_plan


@dataclasses.dataclass(frozen=True)
class Planner:
    """A registered scheduler.

    Attributes
    ----------
    name : str
        What ``--scheduler`` names it.
    plan : callable
        ``plan(problem, settings, previous)``: ``problem`` a PlanningProblem, ``settings`` its own
        settings (below), ``previous`` the schedule flown so far (a warm start) or None; returns a
        PlanResult.
    settings : object
        Its settings when no field of the manager's settings holds them.
    settings_field : str
        The field of :class:`~genthermal.schedule.flight.manager_settings.ManagerSettings` with its
        settings (``heuristic``, ``optimal``, ...), empty for a planner registered from outside.
    on_flown_model : bool
        Whether it can plan on the flown nonlinear model (``planner_model: nonlinear``).
    default_model : str
        What it plans on when the manager's ``planner_model`` is ``auto`` and the flight's filter
        is the extended Kalman filter (:func:`model_for`): ``nonlinear`` (only if
        ``on_flown_model``) or ``affine``.
    """

    name: str
    plan: Callable
    settings: object = None
    settings_field: str = ""
    on_flown_model: bool = False
    default_model: str = "affine"



_PLANNERS: dict[str, Planner] = {}
#: What a planner may declare as its :attr:`Planner.default_model`.
DEFAULT_MODELS = ("affine", "nonlinear")


def register_planner(name: str, plan: Callable, settings=None, on_flown_model: bool = False,
                     settings_field: str = "", default_model: str = "affine") -> Planner:
    """Register ``plan`` as the scheduler ``name`` (see :class:`Planner`); returns its entry.

    Raises
    ------
    InputError
        ``name`` is empty, not an identifier-like word, or already registered; ``plan`` is not
        callable; ``default_model`` is not ``affine`` or ``nonlinear``, or ``nonlinear`` for a
        planner that cannot plan on the flown model.
    """
    if not isinstance(name, str) or not name.replace("_", "").replace("-", "").isalnum():
        raise InputError("scheduler", name, "a planner's name is a word of letters, digits, '_' or '-'")
    if name in _PLANNERS:
        raise InputError("scheduler", name, "a planner of that name is registered already")
    if not callable(plan):
        raise InputError("scheduler", name, f"its plan is a {type(plan).__name__}, not a function")
    if default_model not in DEFAULT_MODELS:
        raise InputError("default_model", default_model, f"must be one of {', '.join(DEFAULT_MODELS)}")
    if default_model == "nonlinear" and not on_flown_model:
        raise InputError("default_model", default_model, f"the planner {name} does not plan on the flown model "
                         "(on_flown_model False)")
    entry = Planner(name, plan, settings, settings_field, on_flown_model, default_model)
    _PLANNERS[name] = entry
    return entry


def unregister_planner(name: str) -> None:
    """Remove the planner ``name`` registered from outside (the built-in ones stay)."""
    if name in BUILT_IN_PLANNERS:
        raise InputError("scheduler", name, "a built-in planner cannot be removed")
    _PLANNERS.pop(name, None)


def planner(name: str) -> Planner:
    """The registered planner ``name``; an InputError naming ``scheduler`` and the known names."""
    if name not in _PLANNERS:
        raise InputError("scheduler", name, f"must be one of {', '.join(_PLANNERS)}")
    return _PLANNERS[name]


def model_for(scheduler: str, planner_model: str, filter_flown: str) -> str:
    """The model ``scheduler`` plans on in a flight: ``planner_model`` itself unless it is ``auto``;
    with ``auto``, the planner's :attr:`Planner.default_model` when the flight's filter
    ``filter_flown`` is ``ekf`` (the flown model and its covariance exist), else ``affine`` (the
    thesis's linear filter has only the design model)."""
    if planner_model != "auto":
        return planner_model
    return planner(scheduler).default_model if filter_flown == "ekf" else "affine"


def planner_names() -> tuple:
    """The names of the registered planners, the built-in ones first."""
    return tuple(_PLANNERS)


def load_planner_file(path, option: str = "--scheduler") -> str:
    """Run the Python file ``path``, which registers one planner (:func:`register_planner`); its name.

    Running the file is a trust decision made on the command line (``fly --scheduler my_planner.py``),
    as for a plant file. A file whose planner is registered already in this process is not run again.

    Raises
    ------
    InputError
        Naming ``option`` and the file: it does not exist, raises on import, or registers no planner
        or more than one.
    """
    path = Path(path).resolve()
    if _LOADED_FILES.get(str(path)) in _PLANNERS:
        return _LOADED_FILES[str(path)]
    before = set(_PLANNERS)
    try:
        run_user_file(path, option, "planner")
    except InputError:
        for added in set(_PLANNERS) - before:
            _PLANNERS.pop(added)
        raise
    added = [n for n in _PLANNERS if n not in before]
    if len(added) != 1:
        for extra in added:
            _PLANNERS.pop(extra)
        raise InputError(option, str(path), f"the planner file registered {len(added)} planners "
                         f"({', '.join(added) or 'none'}); it registers one with register_planner(name, plan)")
    _LOADED_FILES[str(path)] = added[0]
    return added[0]


_LOADED_FILES: dict[str, str] = {}

register_planner("heuristic", lambda problem, settings, previous: heuristic_plan(problem, settings),
                 on_flown_model=True, settings_field="heuristic")
register_planner("engineer", lambda problem, settings, previous: engineer_plan(problem, settings),
                 settings_field="engineer")
# the optimal scheduler plans on the flown model by default: on the robustness grid it rests 0.6 of
# the best baseline there and 0.99 on the design model (docs/results/robustness-grid.md)
register_planner("optimal", optimal_plan, on_flown_model=True, settings_field="optimal", default_model="nonlinear")
register_planner("milp", lambda problem, settings, previous: milp_plan(problem, settings), settings_field="milp")

#: The planners genthermal ships.
BUILT_IN_PLANNERS = planner_names()
