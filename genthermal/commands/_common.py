"""Options shared by the sub-commands, spelt one way: ``--model``, ``--param``, ``--json``, ``--out``
and choices.

Only light modules are imported here: a command's ``register`` must not load the numerical
libraries (``genthermal CMD --help`` stays fast). Reference: docs/guide/cli.md.
"""

from __future__ import annotations

import argparse
import math

from ..errors import InputError
from ._vocabulary import BUILT_IN_MACHINES, DEFAULT_MODEL, cli_spelling

#: What ``--out`` writes, by kind: (metavar, help text with ``{what}``). Each command's --out is
#: one of these; ``genthermal.outputs.FOLDER_OUT_COMMANDS`` lists the commands of kind "folder".
OUT_KINDS = {
    "csv": ("FILE.csv", "writes a CSV table: {what}"),
    "folder": ("DIR", "writes a folder: {what} (created; it appears whole or not at all)"),
    "model": ("FILE.yaml", "writes a YAML model file: {what} (load it with --model FILE.yaml)"),
    "fmu": ("FILE.fmu", "writes an FMI 2.0 FMU: {what}"),
}


def add_model_arguments(parser: argparse.ArgumentParser, what: str = "the model",
                        default: str | None = DEFAULT_MODEL) -> None:
    """Add ``--model NAME|FILE`` and ``--param NAME=VALUE`` to ``parser``.

    Parameters
    ----------
    parser : argparse.ArgumentParser
    what : str
        What the model is for, opening the help text.
    default : str or None
        The default ``--model``; None when the command takes it from elsewhere (a scenario), and
        then ``what`` says from where.
    """
    builtin = ", ".join(f"{m}, {m}:linear" for m in BUILT_IN_MACHINES)
    said = f" (default {default})" if default else ""
    parser.add_argument("--model", default=default, metavar="NAME|FILE",
                        help=f"{what}: a machine ({builtin}, or an installed plug-in), a .py machine file, or a "
                        f"YAML model file written by calibrate --out or diagnose --out{said}")
    parser.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                        help="override a parameter of --model (SI units), e.g. --param h_end_air=15; repeatable")


#: Block length records logged faster are averaged to before fitting or scoring, s (compare, calibrate).
DEFAULT_FIT_STEP_S = 10.0


def add_record_set_arguments(parser, fitting: bool = False) -> None:
    """``--columns FILE`` and ``--fit-step S``; with ``fitting``, ``--weight`` and ``--prior-weight`` too."""
    parser.add_argument("--columns", metavar="FILE", help="column map (YAML) of a logger's CSV: which column is "
                        "which input or sensor, in which unit (default: the machine's own map, if it has one)")
    if fitting:
        parser.add_argument("--weight", action="append", default=[], metavar="SENSOR=W",
                            help="weight of a sensor in the sum of squares (default 1), e.g. --weight T_rotor=4; "
                            "repeatable")
        parser.add_argument("--prior-weight", action="append", default=[], metavar="[NAMES=]W",
                            help="weight of a prior pulling a fitted parameter towards its start value, K² per unit "
                            "of ln(value/start)² (default 0: none); keeps the directions the records hardly see "
                            "near the machine's estimate. W: every fitted parameter; NAMES=W: the parameters named, "
                            "comma-separated names or globs, e.g. --prior-weight 30 --prior-weight "
                            "'C_rotor,G_gap*=1000'; repeatable, a later item naming a parameter again wins")
    parser.add_argument("--fit-step", metavar="S", help=f"average records logged faster to this step, s, before "
                        f"fitting, scoring or filtering (default {DEFAULT_FIT_STEP_S:g} s)")


def add_json_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """Add ``--json FILE.json``: write ``what`` as a JSON document."""
    parser.add_argument("--json", metavar="FILE.json", help=f"write {what} as a JSON document to FILE.json")


def add_out_argument(parser: argparse.ArgumentParser, kind: str, what: str, **kwargs) -> None:
    """Add ``--out`` of one of the :data:`OUT_KINDS`, its help saying what it writes."""
    metavar, text = OUT_KINDS[kind]
    parser.add_argument("--out", metavar=metavar, help=text.format(what=what), **kwargs)


class _Choice:
    """argparse ``type`` of a choice option: maps an old spelling (hidden) to the current one."""

    def __init__(self, choices):
        self.choices = tuple(choices)

    def __call__(self, text: str) -> str:
        return cli_spelling(text)


class _ChoicesOrFile(tuple):
    """The named choices, and any file name ending in ``suffix`` (a plug-in the user gives)."""

    def __new__(cls, choices, suffix: str):
        made = super().__new__(cls, choices)
        made.suffix = suffix
        return made

    def __contains__(self, item) -> bool:
        return tuple.__contains__(self, item) or str(item).endswith(self.suffix)


def add_choice_argument(parser: argparse.ArgumentParser, option: str, choices, help: str,
                        or_file: str | None = None, **kwargs) -> None:
    """Add an option taking one of ``choices`` (lower-case, hyphenated), shown as ``{a,b}``.

    An unknown value is a usage error naming the option and the value (exit code 2); the old
    spellings of :data:`~genthermal.commands._vocabulary.OLD_SPELLINGS` are accepted. With
    ``or_file`` (a suffix such as ``".py"``) a file name with that suffix is accepted too, shown as
    ``{a,b}|FILE.py``.
    """
    if or_file is None:
        parser.add_argument(option, choices=tuple(choices), type=_Choice(choices), help=help, **kwargs)
        return
    parser.add_argument(option, choices=_ChoicesOrFile(choices, or_file), type=_Choice(choices), help=help,
                        metavar="{" + ",".join(choices) + "}|FILE" + or_file, **kwargs)


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


def with_overrides(model, items: list[str], source: str = "set on the command line"):
    """``model`` with the ``--param NAME=VALUE`` overrides ``items`` (provenance ``assumed``).

    Raises
    ------
    InputError
        Naming ``--param NAME`` for a malformed item, an unknown name or an unphysical value.
    """
    overrides = parse_assignments(items)
    unknown = [name for name in overrides if name not in model.parameters]
    if unknown:
        raise InputError(f"--param {unknown[0]}", unknown[0], f"not a parameter of {model.name}")
    if overrides:
        model = model.with_parameters(provenance="assumed", source=source, **overrides)
    return model


def load_model_option(option: str, reference: str):
    """The model a ``--model`` (or ``--plant``) names; InputError names the option."""
    from ..model_file import load_model

    try:
        return load_model(reference)
    except InputError as exc:
        if exc.field == "model":
            raise InputError(option, exc.value, exc.reason) from None
        raise InputError(f"{option} {reference}: {exc.field}", exc.value, exc.reason) from None


def model_from_args(args: argparse.Namespace, source: str = "set on the command line"):
    """Load ``--model`` and apply the ``--param`` overrides (checked for physical values).

    Raises
    ------
    InputError
        Naming ``--model`` for an unknown name or a bad model file, ``--param NAME`` for a bad
        override.
    """
    parse_assignments(args.param)  # a malformed --param is refused before the model is built
    return with_overrides(load_model_option("--model", args.model), args.param, source)


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
