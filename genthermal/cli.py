"""The ``genthermal`` command line.

Each sub-command lives in its own module under :mod:`genthermal.commands` and exposes
``register(subparsers)``, which adds its parser and sets ``func`` (a callable taking the parsed
arguments and returning an exit code). Errors genthermal raises on purpose are printed as one
clear line and give exit code 2; nothing reaches the user as a bare traceback.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from .errors import GenthermalError

#: Sub-command modules, in the order ``genthermal --help`` lists them.
COMMAND_MODULES = (
    "demo",
    "simulate",
    "describe",
    "codegen",
    "fmu",
    "cortex_m4",
    "synth",
    "estimate",
    "sysid",
    "compare_models",
    "compare",
    "calibrate",
    "diagnose",
    "plan",
    "fly",
    "sweep",
)


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every available sub-command registered."""
    parser = argparse.ArgumentParser(
        prog="genthermal",
        description="Thermal models of electrical generators: simulate, estimate, generate C.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    subparsers.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(f"genthermal.commands.{name}").register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the process exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except GenthermalError as exc:
        print(f"genthermal {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except (FileNotFoundError, IsADirectoryError, PermissionError) as exc:
        print(f"genthermal {args.command}: error: {exc.strerror}: {exc.filename}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
