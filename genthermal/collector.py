"""Python's cyclic garbage collector kept in the thread that runs CasADi.

CasADi releases the GIL during its calls and its symbolic core is not thread-safe, so a collection
run by another Python thread (a Dask worker's event loop, a progress display) may destroy CasADi
objects the working thread is using. :func:`collector_in_this_thread` switches automatic
collection off for a block of CasADi work and collects in the calling thread when it ends.
"""

from __future__ import annotations

import gc
from contextlib import contextmanager
from typing import Iterator


@contextmanager
def collector_in_this_thread() -> Iterator[None]:
    """Run the block with Python's automatic cyclic collection off and collect in this thread when
    it ends (module docstring), however it ends.

    Automatic collection is process-wide: it stays off in every thread while the block runs, and
    is restored to what it was before (nested blocks keep it off until the outermost ends).
    Reference counting still frees acyclic garbage at once; only cycles wait for the end.
    """
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        gc.collect()
        if was_enabled:
            gc.enable()
