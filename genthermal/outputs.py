"""Writing output files without losing data.

Three rules, applied by every command:

* **Nothing is replaced by surprise.** An output file that exists, or an output folder that is not
  empty, is refused unless the command was given ``--force`` (:func:`check_output_paths`, called
  by the CLI before any work starts, so a long run never ends in a refusal).
* **Inputs are never outputs.** An output path that names one of the command's input files, or two
  outputs that name the same file, is refused even with ``--force``.
* **Nothing is left half-written.** Every file is written to a temporary file in the same folder
  and moved into place only when it is complete (:func:`replacing`); an error or Ctrl-C leaves the
  old file as it was and no partial file behind. A command that writes several files into a folder
  (C sources and library, a report) builds them in a temporary folder next to it and moves them in
  only when all are complete (:func:`replacing_folder`).

JSON output holds finite numbers only: :func:`write_json` writes NaN and ±inf as ``null`` and
returns where it did so, for the command to say.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import tempfile
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Iterator

import numpy as np

from .errors import InputError

#: Option destinations that name files a command writes.
FILE_OUTPUT_OPTIONS = ("out", "json", "plot")
#: Option destinations that name folders a command writes (``--report DIR``).
FOLDER_OUTPUT_OPTIONS = ("report",)
#: Commands whose ``--out`` is a folder, not a file.
FOLDER_OUT_COMMANDS = ("codegen", "demo")
#: Option and argument destinations that name files a command reads.
INPUT_OPTIONS = ("scenario", "data", "train", "validation", "model", "baseline")
#: Figure formats a ``--plot`` file may have (matplotlib's, without the raw buffer formats).
FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".svgz", ".jpg", ".jpeg", ".tif", ".tiff", ".webp", ".eps", ".ps")


def check_output_paths(args, command: str) -> None:
    """Refuse the outputs of a parsed command line before any work is done.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed arguments; the destinations of :data:`FILE_OUTPUT_OPTIONS`,
        :data:`FOLDER_OUTPUT_OPTIONS` and :data:`INPUT_OPTIONS` that it has are checked, and
        ``args.force`` (absent = False) allows replacing existing outputs.
    command : str
        The sub-command, which decides whether ``--out`` is a file or a folder.

    Raises
    ------
    InputError
        An output names an input or another output, an output file exists (or an output folder is
        not empty) without ``--force``, an output file is a folder, or a ``--plot`` file has a
        suffix matplotlib cannot write.
    """
    force = bool(getattr(args, "force", False))
    inputs = [Path(value) for name in INPUT_OPTIONS if isinstance(value := getattr(args, name, None), str)]
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


def _same_file(a: Path, b: Path) -> bool:
    if a.exists() and b.exists():
        return os.path.samefile(a, b)
    return a.resolve() == b.resolve()


def _check_file(option: str, path: Path, force: bool) -> None:
    if path.is_dir():
        raise InputError(option, str(path), "is a folder; give a file name")
    _check_writable(option, path.parent, path)
    if path.exists() and not force:
        raise InputError(option, str(path), "exists; add --force to replace it, or choose another name")


def _check_folder(option: str, path: Path, force: bool) -> None:
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
def replacing(path) -> Iterator[Path]:
    """Yield a temporary file next to ``path``; move it onto ``path`` if the block completes.

    The temporary file keeps ``path``'s suffix (so matplotlib and pandas pick the right format)
    and gets the usual permissions of a new file. On any exception, Ctrl-C included, it is deleted
    and ``path`` is left untouched. Missing parent folders are created.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix or ".tmp", dir=path.parent)
    os.close(handle)
    try:
        os.chmod(temporary, 0o666 & ~_umask())
        yield Path(temporary)
        os.replace(temporary, path)
    except BaseException:
        with suppress(FileNotFoundError):
            os.unlink(temporary)
        raise


@contextmanager
def replacing_folder(path, stale_patterns: tuple[str, ...] = ()) -> Iterator[Path]:
    """Yield an empty temporary folder next to ``path``; move its files into ``path`` if the block completes.

    When ``path`` does not exist (or is an empty folder) the temporary folder is renamed onto it in
    one step. Otherwise each file is moved into place with one atomic rename, after all of them
    were complete, and files of ``path`` matching ``stale_patterns`` (glob patterns) that the new
    output does not hold are removed. On any exception, Ctrl-C included, the temporary folder is
    deleted and ``path`` is left as it was.

    Parameters
    ----------
    path : path-like
        The output folder.
    stale_patterns : tuple of str
        Glob patterns of files a previous run wrote that the new output replaces as a set.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
    try:
        os.chmod(temporary, 0o777 & ~_umask())
        yield temporary
        if path.is_dir() and not any(path.iterdir()):
            path.rmdir()
        if not path.exists():
            os.replace(temporary, path)
            return
        new = {item.relative_to(temporary) for item in temporary.rglob("*") if not item.is_dir()}
        for name in new:
            (path / name).parent.mkdir(parents=True, exist_ok=True)
            os.replace(temporary / name, path / name)
        for pattern in stale_patterns:
            for old in path.glob(pattern):
                if old.relative_to(path) not in new and old.is_file():
                    old.unlink()
    finally:
        shutil.rmtree(temporary, ignore_errors=True)


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
