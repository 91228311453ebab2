"""``--prior-weight`` of ``calibrate``: one weight for every fitted parameter, or per parameter.

Items are ``W`` (every fitted parameter not named otherwise) or ``NAMES=W``, ``NAMES`` being
comma-separated parameter names or shell-style globs (``rotor_*``, ``G_gap*``) over the fitted
parameters; a later item naming a parameter again wins. Reference: docs/guide/cli.md.
"""

from __future__ import annotations

import difflib
import fnmatch
import math

from ..errors import InputError

OPTION = "--prior-weight"


def _weight(field: str, text: str) -> float:
    """``text`` as a weight, K² per unit of ln(value/start)²; InputError naming ``field``."""
    try:
        value = float(text)
    except ValueError:
        raise InputError(field, text.strip(), "a weight must be a number >= 0") from None
    if not (math.isfinite(value) and value >= 0):
        raise InputError(field, value, "a weight must be a number >= 0")
    return value


def _matched(pattern: str, model, fitted: list[str]) -> list[str]:
    """The fitted parameters ``pattern`` (a name or a glob) names; InputError when it names none."""
    field = f"{OPTION} {pattern}"
    if any(c in pattern for c in "*?["):
        chosen = fnmatch.filter(fitted, pattern)
        if not chosen:
            others = fnmatch.filter(model.parameter_names, pattern)
            where = (f"it matches only parameters not fitted ({', '.join(others)}); add them to --params" if others
                     else f"the fitted parameters are {', '.join(fitted)}")
            raise InputError(field, pattern, f"the pattern matches no fitted parameter: {where}")
        return chosen
    if pattern in fitted:
        return [pattern]
    if pattern in model.parameters:
        raise InputError(field, pattern, "not among the parameters --params fits; a prior on a fixed parameter "
                         "does nothing")
    close = difflib.get_close_matches(pattern, model.parameter_names, n=3)
    hint = f"; did you mean {', '.join(close)}?" if close else f"; its parameters: {', '.join(model.parameter_names)}"
    raise InputError(field, pattern, f"not a parameter of {model.name}{hint}")


def prior_weights(items: list[str], model, fitted: list[str]) -> dict[str, float]:
    """Weight of the prior on each of ``fitted`` from the ``--prior-weight`` items.

    Parameters
    ----------
    items : list of str
        ``W`` or ``NAMES=W`` (see the module docstring); empty: no prior.
    model : ThermalModel
        The model calibrated (its parameter names, for the messages).
    fitted : list of str
        The parameters ``--params`` fits.

    Returns
    -------
    dict
        {name: weight} for every fitted parameter, K² per unit of ln(value/start)² (0: no prior).

    Raises
    ------
    InputError
        Naming ``--prior-weight`` (and the name) for a weight that is negative or not a number, a
        second bare weight, an unknown or unfitted parameter name, or a glob matching no fitted
        parameter.
    """
    defaults = [item for item in items if "=" not in item]
    if len(defaults) > 1:
        raise InputError(OPTION, defaults[1], f"one weight for every parameter is given already ({defaults[0]}); "
                         "name the others as NAMES=W")
    default = _weight(OPTION, defaults[0]) if defaults else 0.0
    weights = {name: default for name in fitted}
    for item in items:
        names, sep, text = item.partition("=")
        if not sep:
            continue
        patterns = [p.strip() for p in names.split(",")]
        if not all(patterns):
            raise InputError(OPTION, item, "expected NAMES=W, e.g. G_gap=1000 or 'C_rotor,G_gap*=1000'")
        weight = _weight(f"{OPTION} {names.strip()}", text)
        for pattern in patterns:
            for name in _matched(pattern, model, fitted):
                weights[name] = weight
    return weights
