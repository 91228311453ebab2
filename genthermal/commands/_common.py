"""Arguments and helpers shared by the sub-commands that build a model.

Every command that uses a model names it the same way: ``--model NAME|FILE`` (a built-in or
plug-in machine, optionally with its variant, ``genco_rf201a`` or ``genco_rf201a:linear``, a
``.py`` machine file, or a model file written by ``calibrate --out`` / ``diagnose --out``:
:func:`genthermal.model_file.load_model`), and ``--param NAME=VALUE`` overrides parameters on top
of it (to make a mismatched plant for ``synth`` or a what-if for ``simulate``; provenance
``assumed``).
"""

from __future__ import annotations

import argparse
import math

from ..errors import InputError
from ..machines import known_machines
from ..model import ThermalModel
from ..model_file import load_model

DEFAULT_MODEL = "genco_rf201a"


def add_model_arguments(parser: argparse.ArgumentParser, what: str = "the model") -> None:
    """Add ``--model NAME|FILE`` and ``--param NAME=VALUE`` to ``parser``."""
    builtin = ", ".join(f"{m}, {m}:linear" for m in known_machines())
    parser.add_argument("--model", default=DEFAULT_MODEL, metavar="NAME|FILE",
                        help=f"{what}: a machine ({builtin}), a .py machine file, or a YAML model file "
                        f"written by calibrate --out or diagnose --out (default {DEFAULT_MODEL})")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                        help="override a parameter of the model (SI units), e.g. --param h_end_air=15; repeatable")


def parse_assignments(items: list[str], option: str = "--param") -> dict[str, float]:
    """Parse ``NAME=VALUE`` strings into a dict, raising InputError naming the bad item."""
    values = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep or not name.strip():
            raise InputError(option, item, "expected NAME=VALUE, e.g. h_end_air=15")
        try:
            values[name.strip()] = float(text)
        except ValueError:
            raise InputError(f"{option} {name.strip()}", text, "the value must be a number") from None
    return values


def model_from_args(args: argparse.Namespace, source: str = "set on the command line") -> ThermalModel:
    """Load ``--model`` and apply the ``--param`` overrides (checked for physical values).

    Raises
    ------
    InputError
        Naming ``--model`` for an unknown name or a bad model file, ``--param NAME`` for a bad
        override.
    """
    try:
        model = load_model(args.model)
    except InputError as exc:
        if exc.field == "model":
            raise InputError("--model", exc.value, exc.reason) from None
        raise InputError(f"--model {args.model}: {exc.field}", exc.value, exc.reason) from None
    overrides = parse_assignments(args.param)
    unknown = [name for name in overrides if name not in model.parameters]
    if unknown:
        raise InputError(f"--param {unknown[0]}", unknown[0], f"not a parameter of {model.name}")
    if overrides:
        model = model.with_parameters(provenance="assumed", source=source, **overrides)
    return model


def positive_float(option: str, text: str) -> float:
    """Parse a finite, strictly positive number for ``option`` or raise InputError naming it."""
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise InputError(option, text, "must be a positive number") from None
    if not (math.isfinite(value) and value > 0):
        raise InputError(option, text, "must be a positive number")
    return value


def non_negative_float(option: str, text: str) -> float:
    """Parse a finite number >= 0 for ``option`` or raise InputError naming it."""
    try:
        value = float(text)
    except (TypeError, ValueError):
        raise InputError(option, text, "must be a number >= 0") from None
    if not (math.isfinite(value) and value >= 0):
        raise InputError(option, text, "must be a number >= 0")
    return value

