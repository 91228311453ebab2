"""Find a machine by name, entry point or file: machines are plug-ins. Main objects:
:func:`resolve_machine`, :func:`known_machines`, :data:`BUILT_IN`; running a machine file:
docs/guide/safety.md.
"""

from __future__ import annotations

import contextlib
import contextvars
import importlib.metadata
import importlib.util
import os
import types
from pathlib import Path
from typing import Iterable, Iterator

from ..errors import InputError
from . import genco_rf201a
from .interface import Machine

#: The entry-point group plug-in packages register machines in.
ENTRY_POINT_GROUP = "genthermal.machines"
#: Machines shipped with genthermal, by name.
BUILT_IN = {genco_rf201a.NAME: genco_rf201a.MACHINE}
#: Attribute a machine file or module defines.
MACHINE_ATTRIBUTE = "MACHINE"
#: Machine files (resolved paths) a data file may name in this run.
_TRUSTED_FILES: contextvars.ContextVar[frozenset] = contextvars.ContextVar("trusted_machine_files",
                                                                          default=frozenset())


@contextlib.contextmanager
def trusted_machine_files(paths: Iterable[str | os.PathLike]) -> Iterator[frozenset]:
    """Within the block, data files may name the machine files ``paths`` (and no other).

    Raises
    ------
    InputError
        A path that is not an existing ``.py`` file.
    """
    resolved = set()
    for path in map(Path, paths):
        if path.suffix != ".py" or not path.is_file():
            raise InputError("--trust-machine", str(path), "must be an existing .py machine file")
        resolved.add(path.resolve())
    token = _TRUSTED_FILES.set(_TRUSTED_FILES.get() | resolved)
    try:
        yield _TRUSTED_FILES.get()
    finally:
        _TRUSTED_FILES.reset(token)


def entry_point_names() -> list[str]:
    """Names of the machines installed packages register in :data:`ENTRY_POINT_GROUP`."""
    return sorted({ep.name for ep in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP)})


def known_machines() -> list[str]:
    """Built-in and installed machine names."""
    return [*BUILT_IN, *(name for name in entry_point_names() if name not in BUILT_IN)]


def is_machine_reference(reference: str) -> bool:
    """True when ``reference`` names a built-in or installed machine or a ``.py`` machine file."""
    return reference in BUILT_IN or reference in entry_point_names() or _file_part(reference)[0] is not None


def resolve_machine(reference, from_data: bool = False) -> Machine:
    """The :class:`Machine` named by ``reference`` (see the module docstring).

    Parameters
    ----------
    reference : str or Machine
    from_data : bool
        The reference was read from a data file: a machine file is refused (before it runs) unless
        it is trusted (:func:`trusted_machine_files`).

    Raises
    ------
    InputError
        Naming the reference for an unknown name, a missing, broken or untrusted file, or an object
        that is not a Machine.
    """
    if isinstance(reference, Machine):
        return reference
    if not isinstance(reference, str) or not reference:
        raise InputError("machine", reference, "give a machine name or the path of a .py machine file")
    if reference in BUILT_IN:
        return BUILT_IN[reference]
    entry_points = [ep for ep in importlib.metadata.entry_points(group=ENTRY_POINT_GROUP) if ep.name == reference]
    if entry_points:
        try:
            loaded = entry_points[0].load()
        except Exception as exc:  # a broken plug-in must name itself, whatever it raised
            raise InputError("machine", reference, f"entry point {entry_points[0].value} of group "
                             f"{ENTRY_POINT_GROUP} failed to load: {type(exc).__name__}: {exc}") from None
        return _as_machine(loaded, reference, f"entry point {entry_points[0].value}")
    path, attribute = _file_part(reference)
    if path is None:
        raise InputError("machine", reference, f"unknown machine; known: {', '.join(known_machines())}, or "
                         "the path of a .py file defining MACHINE")
    if from_data and path.resolve() not in _TRUSTED_FILES.get():
        raise InputError("machine", reference, "a data file may only name a registered machine "
                         f"({', '.join(known_machines())}); it names Python code, which genthermal does not "
                         "run from a data file. Run the machine file with --model FILE.py, or trust it for "
                         "this run with --trust-machine FILE.py (see docs/guide/safety.md)")
    if not path.is_file():
        raise InputError("machine file", str(path), "no such file")
    return _as_machine(getattr(_load_file(path), attribute, None), reference, f"{path} attribute {attribute}")


def _file_part(reference: str) -> tuple[Path | None, str]:
    """(path, attribute) of ``file.py`` or ``file.py:ATTRIBUTE``; (None, "") for anything else."""
    text, attribute = reference, MACHINE_ATTRIBUTE
    head, sep, tail = reference.rpartition(":")
    if sep and head.endswith(".py") and tail.isidentifier():
        text, attribute = head, tail
    return (Path(text), attribute) if text.endswith(".py") else (None, "")


def _load_file(path: Path) -> types.ModuleType:
    name = f"genthermal_user_machine_{abs(hash(str(path.resolve())))}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # the user's file: report what broke, naming it
        raise InputError("machine file", str(path), f"failed to run: {type(exc).__name__}: {exc}") from None
    return module


def _as_machine(loaded, reference: str, where: str) -> Machine:
    if isinstance(loaded, types.ModuleType):
        loaded = getattr(loaded, MACHINE_ATTRIBUTE, None)
    if not isinstance(loaded, Machine):
        raise InputError("machine", reference, f"{where} is {type(loaded).__name__}, not a "
                         "genthermal.machines.Machine (define MACHINE = Machine(...))")
    return loaded
