"""Progress on a terminal for long work, silence everywhere else.

Built on tqdm. Output goes to stderr and only when stderr is a terminal, so pipes, log files, CI
and the tests see nothing; ``GENTHERMAL_PROGRESS=0`` turns it off on a terminal too.
"""

from __future__ import annotations

import os
import shutil
import sys
import threading
from contextlib import contextmanager
from typing import Iterator

from tqdm import tqdm

from .collector import collector_in_this_thread

#: Seconds between refreshes of a :func:`working` display.
REFRESH_S = 0.5


def enabled() -> bool:
    """True when progress is shown: stderr is a terminal and ``GENTHERMAL_PROGRESS`` is not 0."""
    if os.environ.get("GENTHERMAL_PROGRESS", "1") == "0":
        return False
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


def say(text: str) -> None:
    """Print one progress line on stderr, above any :func:`working` display; only on a terminal."""
    if enabled():
        tqdm.write(text, file=sys.stderr)


def _size() -> dict:
    """Terminal width and height, 80 x 24 where the terminal reports 0 x 0 (tqdm would then print
    nothing)."""
    size = shutil.get_terminal_size()
    return {"ncols": size.columns, "nrows": size.lines}


@contextmanager
def working(description: str) -> Iterator[None]:
    """Show ``description`` with the elapsed time while the block runs (work of unknown length).

    The display is removed when the block ends, however it ends.
    """
    if not enabled():
        yield
        return
    bar = tqdm(desc=description, total=None, bar_format="{desc}: working, {elapsed} elapsed", leave=False,
               file=sys.stderr, **_size())
    stop = threading.Event()

    def refresh() -> None:
        while not stop.wait(REFRESH_S):
            bar.refresh()

    thread = threading.Thread(target=refresh, daemon=True)
    thread.start()
    try:
        with collector_in_this_thread():  # the refresh thread allocates: no collection there
            yield
    finally:
        stop.set()
        thread.join()
        bar.close()
