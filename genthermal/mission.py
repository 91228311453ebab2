"""Missions as data: ordered load actions built from the load conditions of thesis Table 3.2.

A :class:`Mission` is a list of :class:`~genthermal.conditions.Action` objects;
:meth:`Mission.to_inputs` turns it into the input time series of a thermal model.
:func:`load_mission` reads one by name (``scenarios/``, installed as ``genthermal/data/scenarios``)
or from a YAML file; every problem is an :class:`~genthermal.errors.InputError` whose field is a
path into the document (``actions[3].duration_min``). The YAML form: ``docs/guide/simulation.md``.
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
import os
from pathlib import Path
from typing import Any, Mapping

import numpy as np
import pandas as pd
import yaml

from .conditions import Action, LoadCondition, checked_number, reject_unknown_keys
from .errors import InputError
from .yaml_input import load_user_yaml, read_user_text
from .exciter import DEFAULT_POWER_FACTOR
from .machines import DEFAULT_MACHINE, MACHINES
from .machines.interface import GeneratorRole
from .resources import DEMO_DATA_DIR, SCENARIO_DIR, shipped_data_missions
from .sizes import check_grid

__all__ = [
    "Action",
    "LoadCondition",
    "Mission",
    "available_scenarios",
    "load_mission",
]

#: The generator a mission drives when none is given: the default machine's generator role.
DEFAULT_GENERATOR = MACHINES[DEFAULT_MACHINE].interface.generator
#: Its rated RMS phase current, A: load percentages refer to it unless a mission says otherwise.
DEFAULT_RATED_CURRENT_A = MACHINES[DEFAULT_MACHINE].interface.rated_current_A


def input_columns(generator: GeneratorRole = DEFAULT_GENERATOR) -> tuple:
    """Columns of :meth:`Mission.to_inputs` for ``generator``: time (s), the three phase currents
    (A RMS), the field current (A), coolant and ambient temperature (degC)."""
    return ("time_s", *generator.phase_inputs, generator.excitation_input, generator.coolant_input,
            generator.ambient_input)


#: Columns of :meth:`Mission.to_inputs` for the default generator.
INPUT_COLUMNS = input_columns()
#: Accepted range of inlet and ambient temperatures, degC.
TEMPERATURE_RANGE_C = (-60.0, 100.0)
#: Top-level keys kept unchecked in :attr:`Mission.extras`.
EXTRA_KEYS = ("extensions", "faults", "generators", "sensor_faults")
_MISSION_KEYS = ("name", "description", "rated_current_A", "power_factor", "T_inlet_C", "T_ambient_C",
                 "actions") + EXTRA_KEYS


@dataclasses.dataclass(frozen=True)
class Mission:
    """An ordered list of load actions with the conditions the generator runs in.

    Parameters
    ----------
    name : str
        Mission name.
    actions : sequence of Action
        The actions in flight order (stored as a tuple); at least one.
    rated_current_A : float
        Rated RMS phase current, A; load percentages refer to it (default: the default machine's).
    power_factor : float
        Lagging power factor of the load, in (0, 1]; sets the exciter current
        (:func:`genthermal.exciter.exciter_current`). Default 0.8, the usual rating point.
    T_inlet_C : float
        Coolant inlet temperature, degC, constant over the mission.
    T_ambient_C : float
        Ambient temperature around the machine, degC, constant over the mission.
    description : str
        Free text: where the mission comes from and what was assumed.
    extras : dict
        Unchecked top-level ``extensions``, ``faults`` and ``generators`` data of a scenario file.
    """

    name: str
    actions: tuple[Action, ...]
    rated_current_A: float = DEFAULT_RATED_CURRENT_A
    power_factor: float = DEFAULT_POWER_FACTOR
    T_inlet_C: float = 20.0
    T_ambient_C: float = 20.0
    description: str = ""
    extras: dict[str, Any] = dataclasses.field(default_factory=dict, hash=False)

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name.strip():
            raise InputError("name", self.name, "required: a non-empty text naming the mission")
        if not isinstance(self.description, str):
            raise InputError("description", self.description, "must be text")
        if not isinstance(self.actions, (list, tuple)) or not self.actions:
            raise InputError("actions", self.actions, "a mission needs a non-empty list of actions")
        for index, action in enumerate(self.actions):
            if not isinstance(action, Action):
                raise InputError(f"actions[{index}]", action,
                                 "must be an Action (use Mission.from_dict for plain data)")
        object.__setattr__(self, "actions", tuple(self.actions))
        rated = checked_number(self.rated_current_A, "rated_current_A", "a positive number of amperes")
        if rated <= 0:
            raise InputError("rated_current_A", self.rated_current_A,
                             f"must be a positive current, A (default machine: {DEFAULT_RATED_CURRENT_A:g})")
        object.__setattr__(self, "rated_current_A", rated)
        power_factor = checked_number(self.power_factor, "power_factor", "a lagging power factor in (0, 1]")
        if not 0.0 < power_factor <= 1.0:
            raise InputError("power_factor", self.power_factor, "must lie in (0, 1] (lagging load power factor)")
        object.__setattr__(self, "power_factor", power_factor)
        low, high = TEMPERATURE_RANGE_C
        for field in ("T_inlet_C", "T_ambient_C"):
            temperature = checked_number(getattr(self, field), field, "a temperature in degC")
            if not low <= temperature <= high:
                raise InputError(field, getattr(self, field), f"must lie in {low:g}..{high:g} degC")
            object.__setattr__(self, field, temperature)
        if not isinstance(self.extras, Mapping) or not set(self.extras) <= set(EXTRA_KEYS):
            raise InputError("extras", self.extras,
                             f"must be a mapping with keys among {', '.join(EXTRA_KEYS)}")
        if not isinstance(self.extras.get("extensions", {}), Mapping):
            raise InputError("extensions", self.extras["extensions"], "must be a mapping of your own keys")
        object.__setattr__(self, "extras", dict(self.extras))

    # --- time axis ------------------------------------------------------------------------------
    @property
    def duration_s(self) -> float:
        """Total mission duration, s."""
        return float(sum(action.duration_s for action in self.actions))

    def action_boundaries_s(self) -> np.ndarray:
        """Return the start times of all actions followed by the mission end, s (length n + 1)."""
        return np.concatenate(([0.0], np.cumsum([action.duration_s for action in self.actions])))

    def _load_segments(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Start times (s), loads (% of rated) and phase shares (n x 3) of the constant pieces."""
        starts, percents, shares = [], [], []
        for action, action_start in zip(self.actions, self.action_boundaries_s()):
            for offset, percent in action.load_steps():
                starts.append(action_start + offset)
                percents.append(percent)
                shares.append(action.phase_share)
        return np.array(starts), np.array(percents), np.array(shares)

    def _load_at(self, t_s) -> tuple[np.ndarray, np.ndarray]:
        """Load (% of rated) and phase shares (... x 3) in force at times ``t_s`` (s)."""
        times = np.asarray(t_s, dtype=float)
        end = self.duration_s
        outside = ~((times >= 0.0) & (times <= end * (1.0 + 1e-12)))
        if np.any(outside):
            raise InputError("t_s", times[outside].flat[0], f"time must lie in the mission, 0..{end:g} s")
        starts, percents, shares = self._load_segments()
        index = np.searchsorted(starts, times, side="right") - 1
        return percents[index], shares[index]

    # --- load ----------------------------------------------------------------------------------
    def phase_current(self, t_s):
        """Balanced RMS phase current at times ``t_s``.

        Piecewise constant and right-continuous: at an action boundary the new action's value
        applies. A condition action runs at its start-up level for its first 300 s and at its
        continuous level after; at the mission end the last level is held. ``phase_share`` is not
        applied (see :meth:`phase_currents`).

        Parameters
        ----------
        t_s : float or array_like
            Times since the mission start, s, within ``0..duration_s``.

        Returns
        -------
        float or numpy.ndarray
            Phase current, A RMS; same shape as ``t_s``.
        """
        percent, _ = self._load_at(t_s)
        current = percent / 100.0 * self.rated_current_A
        return float(current) if current.ndim == 0 else current

    def phase_currents(self, t_s) -> np.ndarray:
        """RMS currents of phases u, v, w at times ``t_s``, with each action's ``phase_share``.

        Parameters
        ----------
        t_s : float or array_like
            Times since the mission start, s, within ``0..duration_s``.

        Returns
        -------
        numpy.ndarray
            Currents, A RMS, shape ``np.shape(t_s) + (3,)``.
        """
        percent, shares = self._load_at(t_s)
        return (percent / 100.0 * self.rated_current_A)[..., np.newaxis] * shares

    def to_inputs(self, dt_s: float, generator: GeneratorRole = DEFAULT_GENERATOR) -> pd.DataFrame:
        """Sample the mission as model inputs with a zero-order hold.

        Samples lie at ``0, dt, 2 dt, ...`` up to the mission end (included when the duration is a
        multiple of ``dt_s``). Row k holds the inputs applied over ``[t_k, t_k + dt)``, i.e. their
        value at ``t_k``; a load change that falls strictly inside a step therefore takes effect
        at the next sample (choose ``dt_s`` dividing 300 s to avoid this).

        Parameters
        ----------
        dt_s : float
            Sample period, s (> 0); the grid may have at most
            :data:`genthermal.sizes.MAX_GRID_SAMPLES` samples.
        generator : GeneratorRole
            The machine's generator role (``model.spec.interface.generator``): its input names and
            AVR exciter law; default the default machine's.

        Returns
        -------
        pandas.DataFrame
            Float columns :func:`input_columns`: ``time_s`` (s), the three phase currents (A RMS),
            the field current (A, the generator's exciter law of the mean phase current), the
            coolant and ambient temperatures (degC).
        """
        step = checked_number(dt_s, "dt_s", "a positive number of seconds")
        if step <= 0:
            raise InputError("dt_s", dt_s, "the sample period must be positive, s")
        n_steps = check_grid(self.duration_s, step, f"mission {self.name} at dt_s", dt_s) - 1
        times = np.arange(n_steps + 1, dtype=float) * step
        currents = self.phase_currents(np.minimum(times, self.duration_s))
        columns = {"time_s": times}
        columns.update({name: currents[:, i] for i, name in enumerate(generator.phase_inputs)})
        columns[generator.excitation_input] = generator.exciter_law(currents.mean(axis=1), self.power_factor,
                                                                    self.rated_current_A)
        columns[generator.coolant_input] = np.full(times.shape, self.T_inlet_C)
        columns[generator.ambient_input] = np.full(times.shape, self.T_ambient_C)
        return pd.DataFrame(columns, columns=list(input_columns(generator)), dtype=float)

    # --- plain data ----------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """Return the mission as a scenario document (the inverse of :meth:`from_dict`)."""
        document: dict[str, Any] = {
            "name": self.name,
            "description": self.description,
            "rated_current_A": self.rated_current_A,
            "power_factor": self.power_factor,
            "T_inlet_C": self.T_inlet_C,
            "T_ambient_C": self.T_ambient_C,
            "actions": [action.to_dict() for action in self.actions],
        }
        document.update(copy.deepcopy(self.extras))
        return document

    @classmethod
    def from_dict(cls, document: Mapping[str, Any], source: str = "<dict>") -> "Mission":
        """Build a mission from a scenario document (the schema is in the module docstring).

        Parameters
        ----------
        document : mapping
            Parsed scenario, e.g. from YAML.
        source : str
            Where the document came from; appended to error messages.

        Raises
        ------
        InputError
            For any problem; the field is a path into the document (``actions[2].condition``).
        """
        try:
            return _mission_from_document(document, source)
        except InputError as error:
            where = "" if source == "<dict>" else f" (in {source})"
            raise InputError(error.field, error.value, f"{error.reason}{where}") from None

    @classmethod
    def from_yaml(cls, path: str | os.PathLike) -> "Mission":
        """Read a mission from a YAML scenario file.

        Parameters
        ----------
        path : str or os.PathLike
            Scenario file (schema in the module docstring).

        Returns
        -------
        Mission

        Raises
        ------
        InputError
            If the file is missing (field ``scenario``), is not valid YAML (field = the path, the
            reason gives the line) or does not follow the schema.
        """
        path = Path(path)
        try:
            text = read_user_text(path, "scenario")
        except FileNotFoundError:
            raise InputError("scenario", str(path), f"file not found; {_available_text()}") from None
        except (OSError, UnicodeDecodeError) as error:
            raise InputError("scenario", str(path), f"cannot read the file: {error}") from None
        try:
            document = load_user_yaml(text, str(path))
        except yaml.YAMLError as error:
            raise _yaml_syntax_error(path, text, error) from None
        return cls.from_dict(document, source=str(path))


def _yaml_syntax_error(path: Path, text: str, error: yaml.YAMLError) -> InputError:
    """InputError for a YAML syntax error: field = file, value = offending line, reason with line."""
    problem = getattr(error, "problem", None) or str(error)
    marks = [getattr(error, "problem_mark", None), getattr(error, "context_mark", None)]
    marks = [mark for mark in marks if mark is not None]
    if not marks:
        return InputError(str(path), None, f"YAML syntax error: {problem}")
    lines = text.splitlines()
    shown = next((mark for mark in marks if mark.line < len(lines) and lines[mark.line].strip()), marks[0])
    line_text = lines[shown.line].strip() if shown.line < len(lines) else ""
    where = f"line {marks[0].line + 1}, column {marks[0].column + 1}"
    context = f" ({error.context} at line {marks[1].line + 1})" if len(marks) > 1 else ""
    return InputError(str(path), line_text, f"YAML syntax error at {where}: {problem}{context}; "
                      "check indentation, colons and brackets")


def _mission_from_document(document: Any, source: str) -> Mission:
    if not isinstance(document, Mapping):
        raise InputError(source, document, "a scenario must be a mapping with at least 'name' and 'actions'")
    reject_unknown_keys(document, _MISSION_KEYS, prefix="")
    for key in ("name", "actions"):
        if key not in document:
            raise InputError(key, None, f"missing required key {key!r}")
    entries = document["actions"]
    if not isinstance(entries, list) or not entries:
        raise InputError("actions", entries,
                         "must be a non-empty list such as [{condition: 1, duration_min: 15}]")
    actions = tuple(Action.from_dict(entry, f"actions[{index}]") for index, entry in enumerate(entries))
    settings = {key: document[key] for key in ("description", "rated_current_A", "power_factor", "T_inlet_C",
                                               "T_ambient_C")
                if key in document}
    extras = {key: copy.deepcopy(document[key]) for key in EXTRA_KEYS if key in document}
    return Mission(name=document["name"], actions=actions, extras=extras, **settings)


def available_scenarios() -> list[str]:
    """Return the names of the shipped scenario files (:data:`SCENARIO_DIR`, and the missions beside
    the shipped data), sorted."""
    return sorted([*(path.stem for path in SCENARIO_DIR.glob("*.yaml")), *shipped_data_missions()])


def _available_text() -> str:
    return f"available scenarios: {', '.join(available_scenarios()) or '(none)'}"


def load_mission(name_or_path: str | os.PathLike) -> Mission:
    """Load a shipped scenario by name, or any scenario file by path.

    Parameters
    ----------
    name_or_path : str or os.PathLike
        A bare name such as ``"thesis_fig_7_7"`` (looked up as ``scenarios/<name>.yaml``), or a
        path to a YAML file (anything with a directory part or a ``.yaml``/``.yml`` suffix).

    Returns
    -------
    Mission

    Raises
    ------
    InputError
        If no such scenario exists (field ``scenario``; the message lists the available names), or
        if the file is not a valid scenario.
    """
    if not isinstance(name_or_path, (str, os.PathLike)):
        raise InputError("scenario", name_or_path,
                         f"must be a scenario name or a file path; {_available_text()}")
    text = os.fspath(name_or_path)
    looks_like_path = isinstance(name_or_path, os.PathLike) or any(sep in text for sep in ("/", os.sep))
    if looks_like_path or text.endswith((".yaml", ".yml")):
        return Mission.from_yaml(text)
    path = SCENARIO_DIR / f"{text}.yaml"
    if not path.is_file() and text in shipped_data_missions():
        path = DEMO_DATA_DIR / f"{text}.yaml"
    if not path.is_file():
        close = difflib.get_close_matches(text, available_scenarios(), n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise InputError("scenario", text, f"no shipped scenario of that name; {hint}{_available_text()}; "
                         "or give the path to a YAML file")
    return Mission.from_yaml(path)
