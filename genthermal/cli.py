"""The ``genthermal`` command line.

Each sub-command lives in its own module under :mod:`genthermal.commands` and exposes
``register(subparsers)``, which adds its parser and sets ``func`` (a callable taking the parsed
arguments and returning an exit code).

Exit codes (the same for every command)

===  ===========================================================================================
0    success
2    bad input: a bad option, file, scenario, model or data value; one line on stderr names the
     field and the value (argparse's own usage errors also exit 2)
130  interrupted (Ctrl-C): one line on stderr, no partial output file (see :mod:`genthermal.outputs`)
143  terminated (SIGTERM, or SIGHUP: 129): as Ctrl-C, no partial output file or folder
141  the reader of the output went away (``genthermal describe | head``): ends quietly
1    internal error: a bug in genthermal; one line on stderr, with the path of a file holding the
     traceback to attach to a bug report
===  ===========================================================================================

Options are never abbreviated (``--param`` is not ``--params``). Every command that writes files
refuses to replace existing ones unless given ``--force``.
"""

from __future__ import annotations

import argparse
import codecs
import importlib
import os
import signal
import sys
import tempfile
import traceback
import warnings

from . import __version__
from .errors import GenthermalError
from .machines.registry import trusted_machine_files
from .measurements import DataWarning
from .outputs import FILE_OUTPUT_OPTIONS, FOLDER_OUTPUT_OPTIONS, Terminated, check_output_paths, replacing_policy
from .unit_checks import parse_unit_options, stated_units

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
EXIT_OK, EXIT_INTERNAL_ERROR, EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_BROKEN_PIPE = 0, 1, 2, 130, 141
#: Signals that stop a run the way Ctrl-C does (the temporary outputs are removed), exit 128 + number.
STOP_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))
BUG_REPORT_HINT = "this is a bug in genthermal; please report it with the command line you ran"


class _Parser(argparse.ArgumentParser):
    """An argument parser that never accepts an abbreviated option."""

    def __init__(self, *args, **kwargs):
        kwargs["allow_abbrev"] = False
        super().__init__(*args, **kwargs)


def build_parser() -> argparse.ArgumentParser:
    """Return the argument parser with every available sub-command registered.

    Every sub-parser is a :class:`_Parser` (no abbreviations), and every sub-command with an
    output option gets ``--force``.
    """
    parser = _Parser(prog="genthermal",
                     description="Thermal models of electrical generators: simulate, estimate, generate C.",
                     epilog="exit codes: 0 ok, 2 bad input, 130 interrupted, 1 internal error (a bug)")
    parser.add_argument("--version", action="version", version=f"genthermal {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    subparsers.required = True
    for name in COMMAND_MODULES:
        importlib.import_module(f"genthermal.commands.{name}").register(subparsers)
    for subparser in subparsers.choices.values():
        writes = {action.dest for action in subparser._actions} & {*FILE_OUTPUT_OPTIONS, *FOLDER_OUTPUT_OPTIONS}
        if writes and "--force" not in subparser._option_string_actions:
            subparser.add_argument("--force", action="store_true",
                                   help="replace output files (or fill an output folder) that already exist")
        if {action.dest for action in subparser._actions} & {"model", "plant", "scenario", "mission"}:
            subparser.add_argument("--trust-machine", action="append", default=[], metavar="FILE.py",
                                   help="let a model file or scenario of this run name the Python machine file "
                                   "FILE.py (machine files are code: by default a data file may only name a "
                                   "registered machine); repeatable")
        if {action.dest for action in subparser._actions} & {"data", "train", "validation"}:
            subparser.add_argument("--unit", action="append", default=[], metavar="COLUMN=UNIT",
                                   help="the unit of a record column, when it is not s, A or degC: time_s=min, "
                                   "currents=kA, temperatures=K, or a column name (converted on reading; "
                                   "time_s=s accepts the column as it is); repeatable")
    return parser


#: ASCII for the symbols genthermal prints, on a terminal that cannot show them (LANG=C).
ASCII_SPELLING = {"°": "deg", "²": "^2", "³": "^3", "×": "x", "≈": "~", "Δ": "d", "θ": "theta", "σ": "sigma",
                  "ρ": "rho", "→": "->", "←": "<-", "≤": "<=", "≥": ">=", "±": "+/-", "…": "...",
                  "−": "-",
                  "–": "-", "—": "-", "µ": "u", "Ω": "ohm", "·": "*", "√": "sqrt", "∞": "inf", "’": "'"}


def _spell_in_ascii(error: UnicodeEncodeError):
    text = error.object[error.start:error.end]
    return "".join(ASCII_SPELLING.get(character, "?") for character in text), error.end


codecs.register_error("genthermal-ascii", _spell_in_ascii)


def _printable_anywhere() -> None:
    """Let stdout and stderr print on any terminal: characters its encoding lacks are spelt in ASCII
    (``°C`` as ``degC`` with LANG=C or PYTHONIOENCODING=ascii) instead of raising."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.reconfigure(errors="genthermal-ascii")
        except (AttributeError, ValueError, OSError):  # not a text stream that can be reconfigured
            pass


def main(argv: list[str] | None = None) -> int:
    """Run the command line; return the process exit code (see the module docstring)."""
    command = "genthermal"
    _printable_anywhere()
    try:
        args = build_parser().parse_args(argv)
        command = f"genthermal {args.command}"
        check_output_paths(args, args.command)
        with warnings.catch_warnings():
            warnings.simplefilter("always", DataWarning)
            # A library's deprecation notice is for developers, not a line for the user (the floor
            # versions of mpmath/sympy raise some while the pytest warning filters are active).
            warnings.simplefilter("ignore", DeprecationWarning)
            warnings.simplefilter("ignore", PendingDeprecationWarning)
            warnings.showwarning = _warning_printer(command)
            with trusted_machine_files(getattr(args, "trust_machine", None) or []), \
                    stated_units(parse_unit_options(getattr(args, "unit", None) or [])), \
                    replacing_policy(bool(getattr(args, "force", False))), _stopping_on_signals():
                code = int(args.func(args) or 0)
        sys.stdout.flush()
        return code
    except GenthermalError as exc:
        _error(f"{command}: error: {_one_line(exc)}")
        return EXIT_BAD_INPUT
    except KeyboardInterrupt as exc:
        if isinstance(exc, Terminated):
            _error(f"\n{command}: {exc.args[0] if exc.args else 'terminated'}; no partial output file was left")
            return 128 + (exc.args[1] if len(exc.args) > 1 else signal.SIGTERM)
        _error(f"\n{command}: interrupted; no partial output file was left")
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        _silence_stdout()
        return EXIT_BROKEN_PIPE
    except (FileNotFoundError, IsADirectoryError, NotADirectoryError, PermissionError, FileExistsError) as exc:
        _error(f"{command}: error: {exc.strerror}: {exc.filename}")
        return EXIT_BAD_INPUT
    except OSError as exc:  # disk full, read-only file system, ...
        _error(f"{command}: error: {exc.strerror or exc}" + (f": {exc.filename}" if exc.filename else ""))
        return EXIT_BAD_INPUT
    except MemoryError:
        _error(f"{command}: error: not enough memory for this input; shorten the record or mission, or use "
               "a longer --dt")
        return EXIT_BAD_INPUT
    except Exception as exc:  # noqa: BLE001 - the last resort: one line and a traceback file, never a dump
        _error(f"{command}: internal error: {type(exc).__name__}: {_one_line(exc)}\n{BUG_REPORT_HINT} "
               f"(genthermal {__version__}); traceback saved in {_save_traceback()}")
        return EXIT_INTERNAL_ERROR


class _stopping_on_signals:
    """Within the block, SIGTERM and SIGHUP raise :class:`~genthermal.outputs.Terminated` in this
    process (forked workers keep the default: they just end), so cleanups run as for Ctrl-C."""

    def __enter__(self):
        self._pid, self._previous = os.getpid(), {}
        try:
            for number in STOP_SIGNALS:
                self._previous[number] = signal.signal(number, self._handle)
        except ValueError:  # not the main thread: leave the signals alone
            pass
        return self

    def _handle(self, number, frame):
        if os.getpid() != self._pid:
            signal.signal(number, signal.SIG_DFL)
            os.kill(os.getpid(), number)
            return
        raise Terminated(f"stopped by {signal.Signals(number).name}", int(number))

    def __exit__(self, *exc):
        for number, previous in self._previous.items():
            signal.signal(number, previous)
        return False


def _warning_printer(command: str):
    """A ``warnings.showwarning`` that prints one line, ``<command>: warning: <message>``, on stderr."""
    def show(message, category, filename, lineno, file=None, line=None):
        _error(f"{command}: warning: {message}")
    return show


def _one_line(exc: BaseException) -> str:
    """The message of ``exc`` on one line (a message quoting a file may span several)."""
    return "; ".join(line.strip() for line in str(exc).splitlines() if line.strip())


def _error(text: str) -> None:
    try:
        print(text, file=sys.stderr)
    except (BrokenPipeError, ValueError):
        pass


def _silence_stdout() -> None:
    """Point stdout at /dev/null so that the interpreter's final flush does not fail again."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # stdout is not a real file (e.g. captured in tests)
        pass
    finally:
        os.close(devnull)


def _save_traceback() -> str:
    handle, path = tempfile.mkstemp(prefix="genthermal-error-", suffix=".txt")
    with os.fdopen(handle, "w") as file:
        file.write(f"genthermal {__version__}\n{' '.join(sys.argv)}\n\n{traceback.format_exc()}")
    return path


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
