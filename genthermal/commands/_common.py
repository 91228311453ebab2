"""Arguments and helpers shared by the sub-commands that build a model."""

from __future__ import annotations

import argparse
import math

from ..design import linear_design_model
from ..errors import InputError
from ..machines import MACHINES, build_model
from ..model import ThermalModel

VARIANTS = ("nonlinear", "linear")


def add_model_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--machine``, ``--variant`` and ``--param NAME=VALUE`` to ``parser``."""
    parser.add_argument("--machine", default="genco_rf201a", help=f"built-in machine ({', '.join(MACHINES)})")
    parser.add_argument("--variant", default="nonlinear", help="nonlinear (simulation model) or linear "
                        "(design model, thesis 5.2)")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                        help="override a model parameter (SI units), e.g. --param h_end_air=15; repeatable")


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


def model_from_args(args: argparse.Namespace) -> ThermalModel:
    """Build the model the command-line arguments describe (parameters checked when built)."""
    if args.variant not in VARIANTS:
        raise InputError("--variant", args.variant, f"must be one of {', '.join(VARIANTS)}")
    model = build_model(args.machine)
    overrides = parse_assignments(args.param)
    if overrides:
        model = model.with_parameters(provenance="assumed", source="set on the command line", **overrides)
    return linear_design_model(model) if args.variant == "linear" else model


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

