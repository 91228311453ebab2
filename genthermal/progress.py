"""One progress policy for every long command: a display on a terminal, nothing anywhere else.

Progress goes to stderr and only when stderr is a terminal, so pipes, log files, CI and the tests
see nothing but a command's final lines. ``GENTHERMAL_PROGRESS=0`` or ``genthermal --quiet``
(:func:`quiet`) turns it off on a terminal too. :func:`working` shows work of unknown length,
:func:`counter` a tqdm bar of known length, :func:`say` a line. Reference: docs/guide/cli.md.
"""

from __future__ import annotations

import os
import shutil
import sys
import threading
from contextlib import contextmanager
from typing import Iterator

#: Seconds between refreshes of a :func:`working` display.
REFRESH_S = 0.5
#: The environment variable that turns progress off when it is ``0`` (worker processes inherit it).
ENVIRONMENT_SWITCH = "GENTHERMAL_PROGRESS"


def enabled() -> bool:
    """True when progress is shown: stderr is a terminal and ``GENTHERMAL_PROGRESS`` is not 0."""
    if os.environ.get(ENVIRONMENT_SWITCH, "1").strip() == "0":
        return False
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):
        return False


@contextmanager
def quiet(on: bool = True) -> Iterator[None]:
    """Within the block (when ``on``), no progress at all: ``GENTHERMAL_PROGRESS=0``, restored after.

    Set in the environment, so that worker processes started in the block are quiet too.
    """
    if not on:
        yield
        return
    before = os.environ.get(ENVIRONMENT_SWITCH)
    os.environ[ENVIRONMENT_SWITCH] = "0"
    try:
        yield
    finally:
        if before is None:
            os.environ.pop(ENVIRONMENT_SWITCH, None)
        else:
            os.environ[ENVIRONMENT_SWITCH] = before


def say(text: str) -> None:
    """Print one progress line on stderr, above any :func:`working` display; only on a terminal."""
    if enabled():
        from tqdm import tqdm

        tqdm.write(text, file=sys.stderr)


def _size() -> dict:
    """Terminal width and height, 80 x 24 where the terminal reports 0 x 0 (tqdm would then print
    nothing)."""
    size = shutil.get_terminal_size()
    return {"ncols": size.columns, "nrows": size.lines}


def counter(total: int, description: str, show: bool = True):
    """A tqdm bar counting ``total`` items, shown only when :func:`enabled` (and ``show``).

    Parameters
    ----------
    total : int
        Number of items (cases, flights, ...).
    description : str
        Label of the bar.
    show : bool
        The caller's own switch; False hides the bar whatever the terminal.

    Returns
    -------
    tqdm.tqdm
        Use it as a context manager and call ``update(n)``; a disabled bar prints nothing.
    """
    from tqdm import tqdm

    return tqdm(total=total, desc=description, disable=not (show and enabled()), file=sys.stderr, **_size())


class _LinesAboveTheBar:
    """A stdout that writes whole lines above a progress display on the same terminal: the display
    is cleared, the lines written and the display drawn again, so the two never share a line."""

    def __init__(self, stream, bar):
        self._stream, self._bar, self._pending = stream, bar, ""

    def write(self, text: str) -> int:
        self._pending += text
        if "\n" in self._pending:
            lines, _, self._pending = self._pending.rpartition("\n")
            with self._bar.get_lock():
                self._bar.clear(nolock=True)
                self._stream.write(lines + "\n")
                self._stream.flush()
                self._bar.refresh(nolock=True)
        return len(text)

    def flush(self) -> None:
        """Whole lines are flushed as they come; a partial line waits for its end (or :meth:`close`)."""

    def close(self) -> None:
        """Write what is left of a partial line."""
        if self._pending:
            self._stream.write(self._pending)
            self._pending = ""
        self._stream.flush()

    def __getattr__(self, name):
        return getattr(self._stream, name)


def _is_terminal(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


@contextmanager
def working(description: str) -> Iterator[None]:
    """Show ``description`` with the elapsed time while the block runs (work of unknown length).

    Lines the block prints on the terminal (results on stdout, warnings on stderr) appear whole
    above the display. The display is removed when the block ends, however it ends.
    """
    if not enabled():
        yield
        return
    from tqdm import tqdm

    from .collector import collector_in_this_thread

    bar = tqdm(desc=description, total=None, bar_format="{desc}: working, {elapsed} elapsed", leave=False,
               file=sys.stderr, **_size())
    stop = threading.Event()

    def refresh() -> None:
        while not stop.wait(REFRESH_S):
            bar.refresh()

    thread = threading.Thread(target=refresh, daemon=True)
    streams = {name: getattr(sys, name) for name in ("stdout", "stderr") if _is_terminal(getattr(sys, name))}
    above = {name: _LinesAboveTheBar(stream, bar) for name, stream in streams.items()}
    thread.start()
    try:
        for name, stream in above.items():
            setattr(sys, name, stream)
        with collector_in_this_thread():  # the refresh thread allocates: no collection there
            yield
    finally:
        stop.set()
        thread.join()
        for name, stream in streams.items():
            setattr(sys, name, stream)
        bar.close()
        for stream in above.values():
            stream.close()
