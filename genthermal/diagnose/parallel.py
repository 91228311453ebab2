"""Independent fits in worker processes: the candidates of a search, the pairs of a joint search.

:func:`map_in_workers` runs items in forked workers that inherit the compiled CasADi functions and
send back only their results (an item's exception comes back as the parent's, :class:`WorkerError`
where it does not pickle); without ``fork``, or with one worker, it runs them in this process,
in order, so the results do not depend on the number of workers. :data:`WORKER_CPU` and
:func:`cpu_clock` account for the workers' CPU time.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import os
import pickle
import time
import traceback
from typing import Callable, Sequence

from ..errors import InputError

_TASK: tuple | None = None


@dataclasses.dataclass
class WorkerCPU:
    """CPU seconds used by the workers of :func:`map_in_workers` since this process started.

    Attributes
    ----------
    total_s : float
        CPU time of every item run in a worker, s.
    busiest_s : float
        Sum over the parallel maps of the CPU time of the map's busiest worker, s: the time the
        map needs at least with one free core per worker.
    maps : int
        Parallel maps run (maps that ran in this process are not counted).
    """

    total_s: float = 0.0
    busiest_s: float = 0.0
    maps: int = 0


#: The workers' CPU time of this process (:class:`WorkerCPU`), updated as each item returns.
WORKER_CPU = WorkerCPU()


@dataclasses.dataclass(frozen=True)
class CPUReading:
    """CPU time at one moment (:func:`cpu_clock`); differences of two readings time a stage.

    Attributes
    ----------
    own_s : float
        CPU time of this process, s.
    workers_s : float
        CPU time of the items run in worker processes (:attr:`WorkerCPU.total_s`), s.
    critical_s : float
        ``own_s`` plus the busiest worker's CPU time of each parallel map
        (:attr:`WorkerCPU.busiest_s`), s: the wall time the work needs at least with one core per
        worker (this process waits while its workers run).
    """

    own_s: float
    workers_s: float
    critical_s: float

    @property
    def total_s(self) -> float:
        """CPU time of this process and its workers, s."""
        return self.own_s + self.workers_s

    def __sub__(self, other: "CPUReading") -> "CPUReading":
        return CPUReading(self.own_s - other.own_s, self.workers_s - other.workers_s,
                          self.critical_s - other.critical_s)


def cpu_clock() -> CPUReading:
    """This process's CPU time and its workers' (:data:`WORKER_CPU`) now."""
    own = time.process_time()
    return CPUReading(own, WORKER_CPU.total_s, own + WORKER_CPU.busiest_s)


class WorkerError(RuntimeError):
    """An item failed in a worker with an exception that does not pickle back: its type, message
    and the worker's traceback, as text."""


@dataclasses.dataclass(frozen=True)
class _Failure:
    """What a worker returns instead of a result when its item raised (re-raised in the parent)."""

    error: BaseException


def _sendable(error: Exception, item) -> BaseException:
    """``error`` itself when it survives a pickle round trip (an InputError keeps its type), else a
    :class:`WorkerError` with its text: an exception the parent cannot unpickle kills the pool's
    result thread and leaves the map waiting for ever."""
    try:
        pickle.loads(pickle.dumps(error))
        return error
    except Exception:
        return WorkerError(f"{type(error).__name__} on item {item!r}: {error}\n"
                           f"worker traceback:\n{traceback.format_exc()}")


def _run(index: int):
    function, items = _TASK
    started = time.process_time()
    try:
        result = function(items[index])
    except Exception as error:
        result = _Failure(_sendable(error, items[index]))
    return index, result, os.getpid(), time.process_time() - started


def can_fork() -> bool:
    """True when worker processes can be forked on this platform."""
    return "fork" in multiprocessing.get_all_start_methods()


def map_in_workers(function: Callable, items: Sequence, workers: int = 1,
                   progress: Callable[[int, int, object], None] | None = None) -> list:
    """``[function(item) for item in items]``, in ``workers`` forked processes when that can help.

    Items are handed out one at a time in their order, each to the next free worker: put the
    costliest first when their costs are known, so that no worker is left with a long item at the
    end.

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

    Raises
    ------
    Exception
        The first exception an item raised, as it was raised where it pickles back (an
        :class:`~genthermal.errors.InputError` stays one), else a :class:`WorkerError` with its text
        and the worker's traceback; the other workers are stopped.
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
        busiest_before, per_worker = WORKER_CPU.busiest_s, {}
        WORKER_CPU.maps += 1
        pool = multiprocessing.get_context("fork").Pool(min(int(workers), len(items)))
        try:
            for done, (index, result, pid, cpu_s) in enumerate(pool.imap_unordered(_run, range(len(items))),
                                                                start=1):
                if isinstance(result, _Failure):
                    raise result.error
                results[index] = result
                per_worker[pid] = per_worker.get(pid, 0.0) + cpu_s
                WORKER_CPU.total_s += cpu_s
                WORKER_CPU.busiest_s = busiest_before + max(per_worker.values())
                report(done, len(items), items[index])
        except BaseException:
            try:
                pool.terminate()
            except AssertionError:  # the pool's result thread already gone: the first error tells why
                pass
            raise
        # Every result is in: the workers end on the pool's own sentinels. Terminating them instead
        # (the pool's context manager) sends SIGTERM; a worker that did not act on it left the
        # parent waiting in join for ever (a fast-tier run hung in a diagnose test).
        pool.close()
        pool.join()
        return results
    finally:
        _TASK = None
