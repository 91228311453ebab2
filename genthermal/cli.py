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
from .outputs import FILE_OUTPUT_OPTIONS, FOLDER_OUTPUT_OPTIONS, Terminated, check_output_paths, replacing_policy

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
DOCS_HINT = "the docs/ folder of the source tree, or the documentation site built from it (docs/contributing.md)"
EXIT_OK, EXIT_INTERNAL_ERROR, EXIT_BAD_INPUT, EXIT_INTERRUPTED, EXIT_BROKEN_PIPE = 0, 1, 2, 130, 141
#: Signals that stop a run the way Ctrl-C does (the temporary outputs are removed), exit 128 + number.
STOP_SIGNALS = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))
BUG_REPORT_HINT = "this is a bug in genthermal; please report it with the command line you ran"


class _Parser(argparse.ArgumentParser):
    """An argument parser that never accepts an abbreviated option."""

    def __init__(self, *args, **kwargs):
        kwargs["allow_abbrev"] = False
        super().__init__(*args, **kwargs)


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
                     f"Each command: genthermal COMMAND --help. Read more: {DOCS_HINT}",
                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"genthermal {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Parser)
    subparsers.required = True
    wanted = set(COMMANDS) if argv is None else {word for word in argv if word in COMMANDS}
    for name, (module, summary, page) in COMMANDS.items():
        if name in wanted:
            importlib.import_module(f"genthermal.commands.{module}").register(subparsers)
            subparser = subparsers.choices[name]
        else:
            subparser = subparsers.add_parser(name, help=summary)
        subparser.epilog = f"read more: docs/{page} in {DOCS_HINT}"
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
    # Figures go to files: no window unless the user chose a backend (a library user keeps theirs).
    os.environ.setdefault("MPLBACKEND", "Agg")
    _printable_anywhere()
    try:
        words = sys.argv[1:] if argv is None else list(argv)
        args = build_parser(words[:1] if words[:1] and words[0] in COMMANDS else words).parse_args(words)
        command = f"genthermal {args.command}"
        check_output_paths(args, args.command)
        # Imported only now: ``genthermal --help`` loads no numerical library.
        from .machines.registry import trusted_machine_files
        from .measurements import DataWarning
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
