"""Writing output files without losing data.

:func:`check_output_paths` refuses, before any work starts, an output that exists (unless
``--force``), an output that is also an input, and a link, device or FIFO; :func:`replacing` and
:func:`replacing_folder` move complete results into place only at the end, so an error or a
signal (:class:`Terminated`) leaves nothing half-written, nor does a Ctrl-C a native solver took
(:func:`check_interrupt`); :func:`write_json` writes NaN and ±inf as ``null``. The rules:
``docs/guide/safety.md``.
"""

from __future__ import annotations

import contextvars
import errno
import json
import math
import os
import shutil
import stat
import tempfile
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Iterator

from .errors import InputError

#: Option destinations that name files a command writes.
FILE_OUTPUT_OPTIONS = ("out", "json", "plot")
#: Option destinations that name folders a command writes (``--report DIR``).
FOLDER_OUTPUT_OPTIONS = ("report",)
#: Commands whose ``--out`` is a folder, not a file.
FOLDER_OUT_COMMANDS = ("codegen", "demo", "cortex-m4")
#: Whether an output that exists when it is moved into place may be replaced (``--force``).
_MAY_REPLACE: contextvars.ContextVar[bool] = contextvars.ContextVar("may_replace_outputs", default=True)


class Terminated(KeyboardInterrupt):
    """The process was asked to stop (SIGTERM, SIGHUP): unwinds like Ctrl-C, so that no partial
    output is left behind."""


#: Whether Ctrl-C reached this process during the command (set by ``genthermal.cli``'s handler). A
#: native solver may take the KeyboardInterrupt as a failed solve and return (CasADi's IPOPT does:
#: status ``NonIpopt_Exception_Thrown``); the command must not then write the interrupted result.
_INTERRUPT = {"received": False}


def note_interrupt(received: bool = True) -> None:
    """Record that Ctrl-C arrived (or, with ``received=False``, forget it: a new command starts)."""
    _INTERRUPT["received"] = bool(received)


def check_interrupt() -> None:
    """Raise KeyboardInterrupt if Ctrl-C arrived during the command, even if something took it."""
    if _INTERRUPT["received"]:
        raise KeyboardInterrupt("Ctrl-C arrived during a native solver, which returned")
#: Figure formats a ``--plot`` file may have (matplotlib's, without the raw buffer formats).
FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".svgz", ".jpg", ".jpeg", ".tif", ".tiff", ".webp", ".eps", ".ps")


def check_output_paths(args, command: str) -> None:
    """Refuse the outputs of a parsed command line before any work is done.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments; the destinations of :data:`FILE_OUTPUT_OPTIONS` and
        :data:`FOLDER_OUTPUT_OPTIONS` are the outputs, every other argument naming an existing
        path an input, and ``args.force`` (absent = False) allows replacing existing outputs.
    command : str
        The sub-command, which decides whether ``--out`` is a file or a folder.

    Raises
    ------
    InputError
        An output names an input or another output, an output file exists (or an output folder is
        not empty) without ``--force``, an output is a link, device or FIFO, an output file is a
        folder, or a ``--plot`` file has a suffix matplotlib cannot write.
    """
    force = bool(getattr(args, "force", False))
    outputs = (*FILE_OUTPUT_OPTIONS, *FOLDER_OUTPUT_OPTIONS)
    inputs = [Path(value) for name, given in vars(args).items() if name not in outputs
              for value in (given if isinstance(given, list) else [given])
              if isinstance(value, str) and value.strip() and _names_a_file(value)]
    seen: dict[Path, str] = {}
    for name in (*FILE_OUTPUT_OPTIONS, *FOLDER_OUTPUT_OPTIONS):
        value = getattr(args, name, None)
        if not isinstance(value, str):
            continue
        option = f"--{name}"
        path = Path(value)
        if value.strip() == "":
            raise InputError(option, value, "an output path cannot be empty")
        for source in inputs:
            if _same_file(path, source):
                raise InputError(option, value, f"is also an input ({source}); writing it would destroy the "
                                 "input: choose another output name")
        key = path.resolve()
        if key in seen:
            raise InputError(option, value, f"is also the {seen[key]} output; give each output its own name")
        seen[key] = option
        if name in FOLDER_OUTPUT_OPTIONS or (name == "out" and command in FOLDER_OUT_COMMANDS):
            _check_folder(option, path, force)
        else:
            _check_file(option, path, force)
            if name == "plot" and path.suffix.lower() not in FIGURE_SUFFIXES:
                raise InputError(option, value, f"a figure needs one of the suffixes {', '.join(FIGURE_SUFFIXES)}")


def _names_a_file(value: str) -> bool:
    """True when ``value`` (any argument) names an existing file or folder: an input to protect."""
    try:
        return os.path.lexists(value)
    except (ValueError, OSError):  # a NUL byte, a name too long
        return False


def _same_file(a: Path, b: Path) -> bool:
    if a.exists() and b.exists():
        return os.path.samefile(a, b)
    return a.resolve() == b.resolve()


def _not_regular(path: Path) -> str | None:
    """What ``path`` is when it exists and is not a regular file or folder (a link, device, FIFO)."""
    try:
        mode = os.lstat(path).st_mode
    except (FileNotFoundError, NotADirectoryError):
        return None
    if stat.S_ISLNK(mode):
        return "a symbolic link"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return None


def _refuse_special(option: str, path: Path) -> None:
    kind = _not_regular(path)
    if kind:
        raise InputError(option, str(path), f"is {kind}, not a regular file or folder; genthermal replaces "
                         "regular files only (even with --force): name the file itself, or remove it first")


def _check_file(option: str, path: Path, force: bool) -> None:
    _refuse_special(option, path)
    if path.is_dir():
        raise InputError(option, str(path), "is a folder; give a file name")
    _check_writable(option, path.parent, path)
    if path.exists() and not force:
        raise InputError(option, str(path), "exists; add --force to replace it, or choose another name")


def _check_folder(option: str, path: Path, force: bool) -> None:
    _refuse_special(option, path)
    if path.exists() and not path.is_dir():
        raise InputError(option, str(path), "is a file; give a folder name")
    _check_writable(option, path, path)
    if path.is_dir() and any(path.iterdir()) and not force:
        raise InputError(option, str(path), "is a folder that is not empty; add --force to replace the files "
                         "genthermal writes into it, or choose another folder")


def _check_writable(option: str, folder: Path, path: Path) -> None:
    """The nearest existing folder at or above ``folder`` must be a folder genthermal may write in."""
    existing = next((p for p in (folder, *folder.parents) if p.exists()), None)
    if existing is not None and not (existing.is_dir() and os.access(existing, os.W_OK | os.X_OK)):
        raise InputError(option, str(path), f"cannot be written: {existing} is not a writable folder")


@contextmanager
def replacing_policy(may_replace: bool) -> Iterator[None]:
    """Within the block, :func:`replacing` and :func:`replacing_folder` replace an output that
    appeared since the command started only if ``may_replace`` (the command's ``--force``)."""
    token = _MAY_REPLACE.set(bool(may_replace))
    try:
        yield
    finally:
        _MAY_REPLACE.reset(token)


def _claimed_meanwhile(path: Path) -> InputError:
    return InputError("output", str(path), "was written by another run while this one worked (without --force "
                      "neither replaces the other): this run's result was not written; run it again with "
                      "another output name, or with --force to replace it")


def _move_file_into_place(temporary: str, path: Path) -> None:
    """``os.replace``, refusing a link, device or FIFO at ``path`` and, without --force, any file."""
    _refuse_special("output", path)
    if _MAY_REPLACE.get():
        os.replace(temporary, path)
        return
    try:
        os.link(temporary, path)  # fails if a file appeared: an exclusive create, atomically
    except FileExistsError:
        raise _claimed_meanwhile(path) from None
    except OSError as error:
        if error.errno not in (errno.EPERM, errno.ENOTSUP, errno.EXDEV, errno.EOPNOTSUPP):
            raise
        if os.path.lexists(path):  # a file system without hard links: check, then move
            raise _claimed_meanwhile(path) from None
        os.replace(temporary, path)
        return
    os.unlink(temporary)


@contextmanager
def replacing(path) -> Iterator[Path]:
    """Yield a temporary file next to ``path``; move it onto ``path`` if the block completes.

    The temporary file keeps ``path``'s suffix (so matplotlib and pandas pick the right format)
    and gets the usual permissions of a new file. On any exception, Ctrl-C and SIGTERM included, it
    is deleted and ``path`` is left untouched. Missing parent folders are created. ``path`` must
    not be a link, device or FIFO; under ``replacing_policy(False)`` it must not exist when the
    file is moved into place.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix or ".tmp", dir=path.parent)
    os.close(handle)
    try:
        os.chmod(temporary, 0o666 & ~_umask())
        yield Path(temporary)
        check_interrupt()
        _move_file_into_place(temporary, path)
    except BaseException:
        _despite_interrupts(lambda: _unlink_if_present(temporary))
        raise


@contextmanager
def replacing_folder(path, stale_patterns: tuple[str, ...] = ()) -> Iterator[Path]:
    """Yield an empty temporary folder next to ``path``; move its files into ``path`` if the block completes.

    When ``path`` does not exist (or is an empty folder) the temporary folder is renamed onto it in
    one step. Otherwise each file is moved into place with one atomic rename, after all of them
    were complete, and files of ``path`` matching ``stale_patterns`` (glob patterns) that the new
    output does not hold are removed. On any exception, Ctrl-C and SIGTERM included, the temporary
    folder is deleted and ``path`` is left as it was. Under ``replacing_policy(False)`` a ``path``
    that is no longer empty when the block completes (another run filled it) is refused.

    Parameters
    ----------
    path : path-like
        The output folder.
    stale_patterns : tuple of str
        Glob patterns of files a previous run wrote that the new output replaces as a set.
    """
    path = Path(path)
    _refuse_special("output", path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
    try:
        os.chmod(temporary, 0o777 & ~_umask())
        yield temporary
        check_interrupt()
        _refuse_special("output", path)
        if path.is_dir() and not any(path.iterdir()):
            path.rmdir()
        if not path.exists():
            try:
                os.rename(temporary, path)  # onto a missing path (a folder that appeared non-empty: ENOTEMPTY)
            except OSError as error:
                if error.errno in (errno.ENOTEMPTY, errno.EEXIST) and not _MAY_REPLACE.get():
                    raise _claimed_meanwhile(path) from None
                if error.errno not in (errno.ENOTEMPTY, errno.EEXIST):
                    raise
            else:
                return
        if not _MAY_REPLACE.get():
            raise _claimed_meanwhile(path)
        new = {item.relative_to(temporary) for item in temporary.rglob("*") if not item.is_dir()}
        for name in new:
            (path / name).parent.mkdir(parents=True, exist_ok=True)
            os.replace(temporary / name, path / name)
        for pattern in stale_patterns:
            for old in path.glob(pattern):
                if old.relative_to(path) not in new and old.is_file():
                    old.unlink()
    finally:
        _despite_interrupts(lambda: shutil.rmtree(temporary, ignore_errors=True))


def _unlink_if_present(path) -> None:
    with suppress(FileNotFoundError):
        os.unlink(path)


def _despite_interrupts(cleanup) -> None:
    """Run ``cleanup`` to the end even if Ctrl-C or a stop signal arrives meanwhile.

    A second interrupt during the cleanup of a first (a signal pending while the first unwinds)
    would otherwise stop the removal half-way and leave a temporary file or folder behind. The
    interrupt is raised again once the cleanup is complete.
    """
    pending = None
    for _ in range(100):
        try:
            cleanup()
            break
        except KeyboardInterrupt as interrupt:  # Terminated included
            pending = pending or interrupt
    if pending is not None:
        raise pending


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_text(path, text: str) -> Path:
    """Write ``text`` to ``path`` through :func:`replacing`; return the path."""
    with replacing(path) as temporary:
        temporary.write_text(text)
    return Path(path)


def write_csv(frame, path, **to_csv_options) -> Path:
    """Write a DataFrame as CSV (no index) through :func:`replacing`; return the path."""
    with replacing(path) as temporary:
        frame.to_csv(temporary, index=False, **to_csv_options)
    return Path(path)


def write_json(path, document) -> list[str]:
    """Write ``document`` as indented JSON with finite numbers only; return the non-finite keys.

    numpy scalars and arrays become plain numbers and lists. A NaN or ±inf is written as ``null``
    and its place (``"a.b[2]"``) is returned, so that the caller can say so: JSON has no NaN and
    infinity, and a reader must not mistake a missing number for a value.
    """
    replaced: list[str] = []
    text = json.dumps(finite_document(document, replaced), indent=2, allow_nan=False)
    write_text(path, text + "\n")
    return replaced


def finite_document(value, replaced: list[str] | None = None, where: str = ""):
    """``value`` with numpy types made plain and non-finite floats made None (places in ``replaced``)."""
    import numpy as np  # here, not at the top: the command line's --help loads no numpy

    if isinstance(value, dict):
        return {key: finite_document(item, replaced, f"{where}.{key}" if where else str(key))
                for key, item in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [finite_document(item, replaced, f"{where}[{i}]") for i, item in enumerate(value)]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, (float, np.floating)):
        if math.isfinite(value):
            return float(value)
        if replaced is not None:
            replaced.append(f"{where} ({float(value)})")
        return None
    return value


def report_json(path, document) -> None:
    """Write ``document`` with :func:`write_json` and print what was written and what was not finite."""
    replaced = write_json(path, document)
    print(f"wrote {path}")
    if replaced:
        print(f"warning: {len(replaced)} value(s) in {path} are not finite numbers and are written as null: "
              + ", ".join(replaced[:5]) + (" ..." if len(replaced) > 5 else ""))
