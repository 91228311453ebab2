"""Independent fits in worker processes: the candidates of a search, the pairs of a joint search.

A search object holds compiled CasADi functions that do not pickle cheaply; forked workers
inherit them (and everything the parent built) instead, and send back only their results (numbers
and small dataclasses). Where ``fork`` is not available (Windows, macOS default ``spawn``), or with
one worker, the same function runs in this process, in order: the results do not depend on the
number of workers.
"""

from __future__ import annotations

import multiprocessing
from typing import Callable, Sequence

from ..errors import InputError

_TASK: tuple | None = None


def _run(index: int):
    function, items = _TASK
    return index, function(items[index])


def can_fork() -> bool:
    """True when worker processes can be forked on this platform."""
    return "fork" in multiprocessing.get_all_start_methods()


def map_in_workers(function: Callable, items: Sequence, workers: int = 1,
                   progress: Callable[[int, int, object], None] | None = None) -> list:
    """``[function(item) for item in items]``, in ``workers`` forked processes when that can help.

    Parameters
    ----------
    function : callable
        Applied to each item; may close over unpicklable state (the workers inherit it); its
        results must pickle.
    items : sequence
    workers : int
        Processes (≥ 1); 1, a single item or no ``fork`` runs in this process.
    progress : callable, optional
        ``progress(done, total, item)`` after each item, in the order they finish.

    Returns
    -------
    list
        Results in the order of ``items``.
    """
    global _TASK
    if int(workers) != workers or workers < 1:
        raise InputError("workers", workers, "must be an integer >= 1")
    items = list(items)
    report = progress or (lambda done, total, item: None)
    if workers == 1 or len(items) <= 1 or not can_fork():
        results = []
        for done, item in enumerate(items, start=1):
            results.append(function(item))
            report(done, len(items), item)
        return results
    if _TASK is not None:
        raise InputError("map_in_workers", "nested", "already inside a parallel map")
    _TASK = (function, items)
    try:
        results = [None] * len(items)
        with multiprocessing.get_context("fork").Pool(min(int(workers), len(items))) as pool:
            for done, (index, result) in enumerate(pool.imap_unordered(_run, range(len(items))), start=1):
                results[index] = result
                report(done, len(items), items[index])
        return results
    finally:
        _TASK = None
