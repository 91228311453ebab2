"""Reading a user's input file with a size limit: a record, a scenario or a model file.

:func:`read_bounded` refuses a device (``/dev/zero``, ``/dev/urandom``, a terminal) at once, a
regular file larger than the limit before reading it, and a pipe once it has given more than the
limit, each with an :class:`~genthermal.errors.InputError` naming the file and the limit.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from .errors import InputError

#: Largest record (CSV) read, bytes: 5 million rows of 100 characters, the most samples a time
#: grid may have (:data:`genthermal.sizes.MAX_GRID_SAMPLES`).
MAX_RECORD_BYTES = 512 * 2**20
#: Largest scenario or model file read, bytes (the largest shipped one is a few kB).
MAX_YAML_BYTES = 4 * 2**20


def read_bounded(path: str | os.PathLike, what: str, limit_bytes: int) -> bytes:
    """The content of ``path``, at most ``limit_bytes`` bytes.

    Parameters
    ----------
    path : path-like
    what : str
        What the file is (``"scenario"``, ``"model file"``, ``"data file"``), for the message.
    limit_bytes : int

    Raises
    ------
    InputError
        ``path`` is a device or a folder, or holds more than ``limit_bytes`` bytes.
    FileNotFoundError, PermissionError
        As :func:`open` raises them.
    """
    path = Path(path)
    with open(path, "rb") as file:
        mode = os.fstat(file.fileno()).st_mode
        if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
            raise InputError(what, str(path), "is a device, not a file: give the path of a file")
        if stat.S_ISDIR(mode):
            raise InputError(what, str(path), "is a folder: give the path of a file")
        if stat.S_ISREG(mode) and os.fstat(file.fileno()).st_size > limit_bytes:
            raise InputError(what, str(path), f"is {os.fstat(file.fileno()).st_size / 2**20:.1f} MiB, more than "
                             f"the {limit_bytes / 2**20:g} MiB a {what} may have: split it")
        content = file.read(limit_bytes + 1)
    if len(content) > limit_bytes:
        raise InputError(what, str(path), f"holds more than the {limit_bytes / 2**20:g} MiB a {what} may have: "
                         "split it")
    return content
