"""Python's cyclic garbage collector kept in the thread that runs CasADi.

CasADi's Python bindings (3.8) release the GIL while a CasADi call runs, symbolic ones included
(building a Function, a Jacobian, ``depends_on``), and CasADi's symbolic core is not thread-safe:
its expression nodes carry unguarded reference counts and work marks, and constant nodes are
shared by every expression of the process. Python's cyclic collector runs in whichever thread
happens to allocate past its threshold. In a process with other Python threads (a Dask worker's
event loop and profiler, a progress display's refresh), a collection there can destroy CasADi
objects from unreachable cycles while the working thread is inside a CasADi call on nodes they
share. That is a data race on those nodes: on the robustness grid one flight in a Dask worker
stopped inside ``SXFunction::init`` with an index of 2^64 - 1.6e9
(``vector::_M_range_check``), and the same flight alone ran clean.

:func:`collector_in_this_thread` switches automatic collection off for a block of CasADi work and
collects, in the calling thread, when it ends: no other thread then ever runs CasADi destructors,
since only the calling thread holds CasADi objects.
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
