"""The seven generator load conditions of thesis Table 3.2, and the mission :class:`Action`.

:data:`LOAD_CONDITIONS` holds each condition's start-up level (the first 5 minutes of an action) and
continuous level, in % of the rated phase current (thesis section 3.2.6, Table 3.2). An
:class:`Action` is one block of a mission: a condition, or a constant load in %, held for a
duration; missions live in :mod:`genthermal.mission`. The table: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import numbers
from typing import Any, Mapping

from .errors import InputError

#: Length of the start-up level at the beginning of every condition action, s (thesis 3.2.6).
STARTUP_DURATION_S = 5 * 60.0
#: Shortest allowed duration of a condition action, s (thesis 3.2.6).
MIN_ACTION_DURATION_S = 15 * 60.0
#: Highest constant load accepted in an action, % of rated (overload step tests).
MAX_LOAD_PERCENT = 120.0
#: Largest multiplier of one phase's current (an unbalance, not a change of load): with the largest
#: load it keeps every phase current within 2.4 x rated, below the measurements' 3 x limit.
MAX_PHASE_SHARE = 2.0
#: Multipliers of the three phase currents for a balanced load.
BALANCED_SHARE = (1.0, 1.0, 1.0)
#: Keys of one action in a scenario file.
ACTION_KEYS = ("condition", "load_percent", "duration_min", "phase_share")
#: Where the load levels come from.
CONDITIONS_SOURCE = "thesis Table 3.2"


@dataclasses.dataclass(frozen=True)
class LoadCondition:
    """One flight-phase load condition of thesis Table 3.2.

    Parameters
    ----------
    number : int
        Condition number 1..7 as printed in the thesis.
    name : str
        Identifier used in scenario files (``"cruise_combat"``).
    title : str
        Thesis wording (``"Cruise/Combat"``).
    startup_percent : float
        Load during the first :data:`STARTUP_DURATION_S` of the action, % of rated phase current.
    continuous_percent : float
        Load for the rest of the action, % of rated phase current.
    source : str
        Where the levels come from.
    """

    number: int
    name: str
    title: str
    startup_percent: float
    continuous_percent: float
    source: str = CONDITIONS_SOURCE


#: The seven conditions, in thesis order (index ``n - 1`` holds condition ``n``).
LOAD_CONDITIONS: tuple[LoadCondition, ...] = (
    LoadCondition(1, "loading_preparation", "Loading and Preparation", 40.0, 27.3),
    LoadCondition(2, "start_warm_up", "Start and Warm-Up", 83.3, 66.7),
    LoadCondition(3, "taxi", "Taxi", 100.0, 83.3),
    LoadCondition(4, "take_off_climb", "Take-Off and Climb", 83.3, 76.7),
    LoadCondition(5, "cruise", "Cruise", 83.3, 70.0),
    LoadCondition(6, "cruise_combat", "Cruise/Combat", 86.7, 73.3),
    LoadCondition(7, "landing", "Landing", 100.0, 76.7),
)

_CONDITIONS_BY_NAME = {condition.name: condition for condition in LOAD_CONDITIONS}
_VALID_CONDITIONS_TEXT = ", ".join(f"{c.number} ({c.name})" for c in LOAD_CONDITIONS)


def find_condition(number_or_name: int | str | LoadCondition, field: str = "condition") -> LoadCondition:
    """Return the load condition with the given number or name.

    Parameters
    ----------
    number_or_name : int or str or LoadCondition
        Number 1..7, or name such as ``"cruise"`` (case, spaces and hyphens are forgiven:
        ``"Take-off climb"`` finds ``take_off_climb``). A :class:`LoadCondition` is returned as is.
    field : str
        Field named in the error message.

    Returns
    -------
    LoadCondition

    Raises
    ------
    InputError
        If no condition matches; the message lists the valid numbers and names.
    """
    if isinstance(number_or_name, LoadCondition):
        return number_or_name
    if isinstance(number_or_name, int) and not isinstance(number_or_name, bool):
        if 1 <= number_or_name <= len(LOAD_CONDITIONS):
            return LOAD_CONDITIONS[number_or_name - 1]
        raise InputError(field, number_or_name, f"no such load condition; valid: {_VALID_CONDITIONS_TEXT}")
    if isinstance(number_or_name, str):
        key = number_or_name.strip().lower().replace("-", "_").replace(" ", "_").replace("/", "_")
        if key in _CONDITIONS_BY_NAME:
            return _CONDITIONS_BY_NAME[key]
        close = difflib.get_close_matches(key, _CONDITIONS_BY_NAME, n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise InputError(field, number_or_name,
                         f"unknown load condition; {hint}valid: {_VALID_CONDITIONS_TEXT}")
    raise InputError(
        field, number_or_name, f"must be a condition number 1..7 or name; valid: {_VALID_CONDITIONS_TEXT}"
    )


def checked_number(value, field: str, expected: str = "a number") -> float:
    """Return ``value`` as a finite float.

    Parameters
    ----------
    value : object
        Candidate number (booleans, text, NaN and infinities are refused).
    field : str
        Field named in the error message.
    expected : str
        What would be accepted, with its unit (``"a number of minutes, e.g. 30"``).

    Raises
    ------
    InputError
        If ``value`` is not a finite real number.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
        raise InputError(field, value, f"must be {expected}")
    return float(value)


def reject_unknown_keys(mapping: Mapping, valid: tuple[str, ...], prefix: str) -> None:
    """Refuse any key of ``mapping`` that is not in ``valid``, suggesting the closest valid key.

    Parameters
    ----------
    mapping : mapping
        Part of a scenario document.
    valid : tuple of str
        Accepted keys.
    prefix : str
        Path of ``mapping`` in the document, prepended to the key in the error (``"actions[2]."``).

    Raises
    ------
    InputError
        For the first unknown key; field = prefix + key, value = the value under it.
    """
    for key in mapping:
        if key not in valid:
            close = difflib.get_close_matches(str(key), valid, n=1)
            hint = f"did you mean {close[0]!r}? " if close else ""
            raise InputError(f"{prefix}{key}", mapping[key],
                             f"unknown key; {hint}valid keys: {', '.join(valid)}")


def _duration_problem(duration_s: float, is_condition: bool) -> str | None:
    """Say what is wrong with an action duration.

    Parameters
    ----------
    duration_s : float
        Action duration, s.
    is_condition : bool
        True for a load-condition action (at least 15 min), False for a constant load (> 0).

    Returns
    -------
    str or None
        The reason and the fix, or None when the duration is acceptable.
    """
    if is_condition and duration_s < MIN_ACTION_DURATION_S:
        return (f"a load-condition action lasts at least {MIN_ACTION_DURATION_S / 60:g} min "
                f"(thesis 3.2.6); use duration_min: {MIN_ACTION_DURATION_S / 60:g} or more")
    if duration_s <= 0:
        return "the duration must be positive"
    return None


@dataclasses.dataclass(frozen=True)
class Action:
    """One block of a mission: a load condition, or a constant load, held for a duration.

    Parameters
    ----------
    condition : LoadCondition or int or str or None
        Load condition of thesis Table 3.2 (number 1..7 or name are looked up); None when
        ``load_percent`` is given instead.
    duration_s : float
        Duration, s; at least 15 min (900 s) for a load condition, > 0 for a constant load.
    load_percent : float or None
        Constant load, % of rated phase current, 0..120 (step tests); None for a condition.
    phase_share : tuple of 3 float
        Positive multipliers of the phase currents ``(u, v, w)``; ``(1, 1, 1)`` is balanced.
    """

    condition: LoadCondition | None
    duration_s: float
    load_percent: float | None = None
    phase_share: tuple[float, float, float] = BALANCED_SHARE

    def __post_init__(self):
        if self.condition is None and self.load_percent is None:
            raise InputError("condition", None, "give a load condition (1..7 or name) or a load_percent")
        if self.condition is not None and self.load_percent is not None:
            raise InputError("load_percent", self.load_percent,
                             "give a load condition or a load_percent, not both")
        if self.condition is not None:
            object.__setattr__(self, "condition", find_condition(self.condition))
        else:
            percent = checked_number(self.load_percent, "load_percent", "a number of % of rated current")
            if not 0.0 <= percent <= MAX_LOAD_PERCENT:
                raise InputError("load_percent", self.load_percent,
                                 f"must lie in 0..{MAX_LOAD_PERCENT:g} % of rated current")
            object.__setattr__(self, "load_percent", percent)
        duration = checked_number(self.duration_s, "duration_s", "a number of seconds")
        problem = _duration_problem(duration, self.condition is not None)
        if problem:
            raise InputError("duration_s", self.duration_s, problem)
        object.__setattr__(self, "duration_s", duration)
        object.__setattr__(self, "phase_share", self._checked_phase_share())

    def _checked_phase_share(self) -> tuple[float, float, float]:
        share = self.phase_share
        if isinstance(share, (str, bytes)) or not hasattr(share, "__len__") or len(share) != 3:
            raise InputError("phase_share", share,
                             "must be three positive multipliers [u, v, w], e.g. [1, 1, 1]")
        values = tuple(checked_number(value, f"phase_share[{i}]", "a positive number")
                       for i, value in enumerate(share))
        for i, value in enumerate(values):
            if not 0 < value <= MAX_PHASE_SHARE:
                raise InputError(f"phase_share[{i}]", share[i], "phase multipliers must be positive and at "
                                 f"most {MAX_PHASE_SHARE:g}, e.g. [1.1, 1.0, 0.9]")
        return values

    def load_steps(self) -> tuple[tuple[float, float], ...]:
        """Return the load levels of this action.

        Returns
        -------
        tuple of (float, float)
            ``(time since the start of the action, s; load, % of rated)`` for each level, in time
            order: start-up then continuous level for a condition, one level for a constant load.
        """
        if self.condition is None:
            return ((0.0, self.load_percent),)
        return (
            (0.0, self.condition.startup_percent),
            (STARTUP_DURATION_S, self.condition.continuous_percent),
        )

    def to_dict(self) -> dict[str, Any]:
        """Return the action as a scenario-file entry (``condition`` by name, ``duration_min``)."""
        if self.condition is not None:
            entry: dict[str, Any] = {"condition": self.condition.name}
        else:
            entry = {"load_percent": self.load_percent}
        entry["duration_min"] = self.duration_s / 60.0
        if self.phase_share != BALANCED_SHARE:
            entry["phase_share"] = list(self.phase_share)
        return entry

    @classmethod
    def from_dict(cls, entry: Mapping[str, Any], path: str = "action") -> "Action":
        """Build an action from a scenario-file entry (the inverse of :meth:`to_dict`).

        Parameters
        ----------
        entry : mapping
            ``{condition: 1..7 or name, duration_min: minutes}`` or ``{load_percent: % of rated,
            duration_min: minutes}``, optionally with ``phase_share: [u, v, w]``.
        path : str
            Path of the entry in the document (``"actions[3]"``), prefixed to error fields.

        Raises
        ------
        InputError
            For any problem, with field ``path.key`` (``"actions[3].duration_min"``).
        """
        if not isinstance(entry, Mapping):
            raise InputError(path, entry, "each action must be a mapping such as "
                             "{condition: cruise, duration_min: 30} or {load_percent: 100, duration_min: 60}")
        reject_unknown_keys(entry, ACTION_KEYS, prefix=f"{path}.")
        if "condition" not in entry and "load_percent" not in entry:
            raise InputError(f"{path}.condition", None,
                             "missing: give condition (1..7 or name) or load_percent")
        if "duration_min" not in entry:
            raise InputError(f"{path}.duration_min", None,
                             "missing: give the duration in minutes, e.g. duration_min: 30")
        minutes = checked_number(entry["duration_min"], f"{path}.duration_min",
                                 "a number of minutes, e.g. 30")
        problem = _duration_problem(minutes * 60.0, "condition" in entry)
        if problem:
            raise InputError(f"{path}.duration_min", entry["duration_min"], problem)
        try:
            return cls(
                condition=entry.get("condition"),
                duration_s=minutes * 60.0,
                load_percent=entry.get("load_percent"),
                phase_share=entry.get("phase_share", BALANCED_SHARE),
            )
        except InputError as error:
            raise InputError(f"{path}.{error.field}", error.value, error.reason) from None
