"""The ``genthermal`` command line: :func:`main` and :func:`build_parser`.

Each sub-command lives in its own module under :mod:`genthermal.commands` (``register`` adds its
parser, ``run`` does the work and returns the exit code: 0 ok, 2 bad input, 130 interrupted, 1 a
bug). Only the command that runs is imported. Reference: docs/guide/cli.md.
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
from .outputs import (FILE_OUTPUT_OPTIONS, FOLDER_OUTPUT_OPTIONS, Terminated, check_interrupt, check_output_paths,
                      note_interrupt, replacing_policy)

#: Sub-commands in the order ``genthermal --help`` lists them: name -> (module under
#: :mod:`genthermal.commands`, one-line summary, the documentation page that says more). Only the
#: command that runs is imported, so ``genthermal --help`` loads no numerical library; the summary
#: is the one the module's ``register`` gives (``tests/test_cli_help.py`` checks they agree).
COMMANDS = {
    "demo": ("demo", "run the thesis blockage mission end to end", "getting-started.md"),
    "simulate": ("simulate", "simulate a mission scenario", "guide/simulation.md"),
    "describe": ("describe", "list nodes, element formulas and parameters with provenance", "guide/model.md"),
    "codegen": ("codegen", "generate C code of the model and compile it", "guide/embedded.md"),
    "fmu": ("fmu", "export the model as an FMI 2.0 FMU (model exchange and co-simulation)", "guide/embedded.md"),
    "cortex-m4": ("cortex_m4", "cross-compile the generated C for a Cortex-M4F and run it under QEMU",
                  "guide/embedded.md"),
    "synth": ("synth", "write synthetic rig data (measurement CSV schema) for a mission", "guide/estimation.md"),
    "estimate": ("estimate", "Kalman filter and n-step prediction on rig data (thesis 6.3)", "guide/estimation.md"),
    "sysid": ("sysid", "identify ARX models of the winding and iron temperatures (thesis 5.3)",
              "guide/estimation.md"),
    "compare-models": ("compare_models", "compare the physics models and an ARX model on validation data "
                       "(thesis 5.4)", "guide/estimation.md"),
    "compare": ("compare", "compare a model with measurements", "guide/calibration-diagnosis.md"),
    "calibrate": ("calibrate", "fit model parameters to measurements", "guide/calibration-diagnosis.md"),
    "diagnose": ("diagnose", "find the physical effect a model lacks", "guide/calibration-diagnosis.md"),
    "plan": ("plan", "plan load displacement and rests (open loop, design model)", "guide/scheduling.md"),
    "fly": ("fly", "fly a mission with closed-loop load management", "guide/scheduling.md"),
    "sweep": ("sweep", "robustness grid of closed-loop flights in worker processes", "results/robustness-grid.md"),
}
#: Sub-command modules, in the order ``genthermal --help`` lists them.
COMMAND_MODULES = tuple(module for module, _, _ in COMMANDS.values())
#: The command-line reference page (every command's options), under docs/.
REFERENCE_PAGE = "guide/cli.md"
DOCS_HINT = "the docs/ folder of the source tree, or the documentation site built from it (docs/contributing.md)"
EXIT_OK, EXIT_INTERNAL_ERROR, EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_BROKEN_PIPE = 0, 1, 2, 130, 141
#: Signals that stop a run the way Ctrl-C does (the temporary outputs are removed), exit 128 + number.
STOP_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))
BUG_REPORT_HINT = "this is a bug in genthermal; please report it with the command line you ran"


class UsageError(Exception):
    """A command line argparse refuses (unknown option or choice, missing argument): exit code 2."""

    def __init__(self, parser: argparse.ArgumentParser, message: str):
        super().__init__(message)
        self.parser, self.message = parser, message


class _Parser(argparse.ArgumentParser):
    """An argument parser that never accepts an abbreviated option and reports a usage error to
    :func:`main` (which prints it and returns 2) instead of exiting the interpreter."""

    def __init__(self, *args, **kwargs):
        kwargs["allow_abbrev"] = False
        super().__init__(*args, **kwargs)

    def error(self, message):
        raise UsageError(self, message)


QUIET_HELP = "no progress display, even on a terminal (as GENTHERMAL_PROGRESS=0); results are still printed"


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """Return the argument parser; the sub-command ``argv`` names is registered in full.

    The other sub-commands get a placeholder with their summary, so that ``genthermal --help``
    lists them all without importing any (``argv`` None: every sub-command in full). Every
    sub-parser is a :class:`_Parser` (no abbreviations), names its documentation page, and every
    sub-command with an output option gets ``--force``.
    """
    parser = _Parser(prog="genthermal",
                     description="Thermal models of electrical generators: simulate, estimate, diagnose, plan "
                     "and fly, generate C.",
                     epilog="exit codes: 0 ok, 2 bad input, 130 interrupted, 1 internal error (a bug). "
                     f"Each command: genthermal COMMAND --help. Read more: docs/{REFERENCE_PAGE} in {DOCS_HINT}",
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"genthermal {__version__}")
    parser.add_argument("--quiet", action="store_true", help=QUIET_HELP)
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    subparsers.required = True
    wanted = set(COMMANDS) if argv is None else {word for word in argv if word in COMMANDS}
    for name, (module, summary, page) in COMMANDS.items():
        if name in wanted:
            importlib.import_module(f"genthermal.commands.{module}").register(subparsers)
            subparser = subparsers.choices[name]
        else:
            subparser = subparsers.add_parser(name, help=summary)
        own = f"{subparser.epilog}. " if subparser.epilog else ""  # a command's own note (fly's exit code 3)
        subparser.epilog = f"{own}read more: docs/{page}, and every option in docs/{REFERENCE_PAGE}, in {DOCS_HINT}"
        # --quiet after the command too; SUPPRESS keeps a --quiet given before it
        subparser.add_argument("--quiet", action="store_true", default=argparse.SUPPRESS, help=QUIET_HELP)
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
    """Run the command line; return the process exit code (0 ok, 2 bad input, 130 interrupted, 1 a bug:
    docs/guide/cli.md)."""
    command = "genthermal"
    # Figures go to files: no window unless the user chose a backend (a library user keeps theirs).
    os.environ.setdefault("MPLBACKEND", "Agg")
    _printable_anywhere()
    try:
        words = sys.argv[1:] if argv is None else list(argv)
        named = [word for word in words if word in COMMANDS][:1]  # the command, after any global option
        args = build_parser(named or words).parse_args(words)
        command = f"genthermal {args.command}"
        check_output_paths(args, args.command)
        # Imported only now: ``genthermal --help`` loads no numerical library.
        from .machines.registry import trusted_machine_files
        from .measurements import DataWarning
        from .progress import quiet
        from .unit_checks import parse_unit_options, stated_units

        with warnings.catch_warnings():
            warnings.simplefilter("always", DataWarning)
            # A library's deprecation notice is for developers, not a line for the user (the floor
            # versions of mpmath/sympy raise some while the pytest warning filters are active).
            warnings.simplefilter("ignore", DeprecationWarning)
            warnings.simplefilter("ignore", PendingDeprecationWarning)
            warnings.showwarning = _warning_printer(command)
            with trusted_machine_files(getattr(args, "trust_machine", None) or []), \
                    stated_units(parse_unit_options(getattr(args, "unit", None) or [])), \
                    replacing_policy(bool(getattr(args, "force", False))), _stopping_on_signals(), \
                    quiet(bool(getattr(args, "quiet", False))):
                code = int(args.func(args) or 0)
                check_interrupt()  # a Ctrl-C a native solver took is an interrupt all the same
        sys.stdout.flush()
        return code
    except UsageError as exc:
        _error(f"{exc.parser.format_usage().rstrip()}\n{exc.parser.prog}: error: {exc.message}")
        return EXIT_BAD_INPUT
    except GenthermalError as exc:
        _error(f"{command}: error: {_one_line(exc)}")
        return EXIT_BAD_INPUT
    except KeyboardInterrupt as exc:
        _forget_interrupt_in_string_code()
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


def _forget_interrupt_in_string_code() -> None:
    """Clear CPython's note of an interrupt that ended code run from a string (handled here).

    CPython (3.11 here, and 3.12 by its source) notes a KeyboardInterrupt that ends code run from
    source text (``exec``/``eval`` of a string: scipy.stats attaching its distributions' methods on
    a lazy import, a named tuple being made, sympy parsing), even when a caller handles it; under
    ``python -m`` the interpreter then ends by SIGINT itself after the cleanups instead of with the
    exit code (the demo's Ctrl-C once ended -SIGINT so). Each string evaluation resets the note
    first, so an empty one forgets it.
    """
    eval("None")  # noqa: S307 - a constant string: the reset is the point


class _stopping_on_signals:
    """Within the block, SIGTERM and SIGHUP raise :class:`~genthermal.outputs.Terminated` in this
    process (forked workers keep the default: they just end), so cleanups run as for Ctrl-C; Ctrl-C
    is noted too (:func:`~genthermal.outputs.check_interrupt`)."""

    def __enter__(self):
        self._pid, self._previous = os.getpid(), {}
        note_interrupt(False)
        try:
            for number in STOP_SIGNALS:
                self._previous[number] = signal.signal(number, self._handle)
            if signal.getsignal(signal.SIGINT) is signal.default_int_handler:  # not a caller's own handler
                self._previous[signal.SIGINT] = signal.signal(signal.SIGINT, self._interrupt)
        except ValueError:  # not the main thread: leave the signals alone
            pass
        return self

    @staticmethod
    def _interrupt(number, frame):
        """Ctrl-C: noted (a native solver may take the KeyboardInterrupt and return), then raised."""
        note_interrupt()
        signal.default_int_handler(number, frame)

    def _handle(self, number, frame):
        if os.getpid() != self._pid:
            signal.signal(number, signal.SIG_DFL)
            os.kill(os.getpid(), number)
            return
        raise Terminated(f"stopped by {signal.Signals(number).name}", int(number))

    def __exit__(self, *exc):
        for number, previous in self._previous.items():
            signal.signal(number, previous)
        note_interrupt(False)  # a library call after the command writes as usual
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
