"""Running a Python file the user names on the command line (a plant, a planner).

:func:`run_user_file` imports it as a module; whatever the file raises becomes an
:class:`~genthermal.errors.InputError` naming the option, the file and the line, never a traceback.
"""

from __future__ import annotations

import importlib.util
import sys
import traceback
from pathlib import Path

from .errors import InputError


def where_raised(error: BaseException, path: Path) -> str:
    """`` (line N)`` of ``path`` where ``error`` was raised, or an empty string."""
    lines = [frame.lineno for frame in traceback.extract_tb(error.__traceback__) if Path(frame.filename) == path]
    return f" (line {lines[-1]})" if lines else ""


def run_user_file(path, option: str, kind: str):
    """Import the Python file ``path`` as a module and return it.

    Parameters
    ----------
    path : path-like
        The user's file.
    option : str
        The command-line option that named it (for the error).
    kind : str
        What the file is, in words (``"plant"``, ``"planner"``), for the error and the module name.

    Raises
    ------
    InputError
        The file does not exist, or running it raised (the exception and its line are named).
    """
    path = Path(path).resolve()
    if not path.is_file():
        raise InputError(option, str(path), "no such Python file")
    name = f"genthermal_user_{kind}_{abs(hash(str(path)))}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except Exception as error:  # noqa: BLE001 - whatever the user's file raises is named, never a traceback
        sys.modules.pop(name, None)
        raise InputError(option, str(path), f"running the {kind} file raised {type(error).__name__}: {error}"
                         f"{where_raised(error, path)}") from None
    return module
