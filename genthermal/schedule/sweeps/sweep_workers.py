"""Where a sweep's flights run: fresh worker processes of one thread each (CasADi is not
thread-safe), or a Dask cluster when asked. Main objects: :func:`fly_cases_in_processes`,
:func:`fly_cases_on_dask`.
"""

from __future__ import annotations

import multiprocessing
import os
import threading
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from time import monotonic

from ...errors import InputError

#: What to install for ``--cluster`` and ``--dashboard``.
SWEEP_EXTRA = "genthermal[sweep]"


def fly_case_here(fly_case, document: dict, *arguments) -> list:
    """``fly_case(document, *arguments)`` with the worker's process id and its number of Python
    threads when the flights ended in every flight record (``worker_pid``, ``worker_threads``)."""
    flights = fly_case(document, *arguments)
    for flight in flights:
        flight.update(worker_pid=os.getpid(), worker_threads=threading.active_count())
    return flights


def _failed(document: dict, schedulers, status: str, error: str) -> list:
    return [{"case": document["name"], "scheduler": s, "status": status, "error": error, "wall_s": None}
            for s in schedulers]


def fly_cases_in_processes(fly_case, documents, order, arguments: tuple, schedulers, workers: int,
                           timeout_s: float | None, bar) -> list:
    """Fly ``documents`` (in ``order``) with ``fly_case(document, *arguments)`` in ``workers``
    single-threaded processes; ``bar`` (a tqdm bar) counts the cases. A case not done within
    ``timeout_s`` (s, wall clock; None: no limit) is left out (the caller records it as
    ``unfinished``) and the workers are stopped; the cases of a worker that died are recorded with
    ``status`` ``error``."""
    flights = []
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=multiprocessing.get_context("spawn"))
    futures = {pool.submit(fly_case_here, fly_case, documents[i], *arguments): i for i in order}
    deadline = None if timeout_s is None else monotonic() + timeout_s
    pending = set(futures)
    try:
        while pending:
            left = None if deadline is None else max(deadline - monotonic(), 0.0)
            done, pending = wait(pending, timeout=left, return_when=FIRST_COMPLETED)
            if not done:  # the sweep's timeout passed
                break
            for future in done:
                try:
                    flights += future.result()
                except BrokenProcessPool as error:
                    flights += _failed(documents[futures[future]], schedulers, "error",
                                       f"worker process died ({error}); not flown again")
                bar.update()
    finally:
        for future in pending:
            future.cancel()
        if pending:  # running flights past the timeout: stop their processes, do not wait for them
            for process in list(getattr(pool, "_processes", {}).values()):
                process.terminate()
        pool.shutdown(wait=True, cancel_futures=True)
    return flights


def _dask(option: str, value):
    """``(dask.config, distributed)``, or an InputError naming ``option`` and the extra to install."""
    try:
        import dask.config
        import distributed
    except ImportError as error:
        raise InputError(option, value, f"needs Dask, which is not installed ({error.name}): "
                         f"pip install '{SWEEP_EXTRA}'; without {option} the sweep runs in local worker "
                         "processes") from None
    return dask.config, distributed


def fly_cases_on_dask(fly_case, documents, order, arguments: tuple, cluster: str | None, workers: int,
                      dashboard: str | None, timeout_s: float | None, bar) -> list:
    """Fly ``documents`` on the Dask scheduler at ``cluster``, or (None) on a local cluster of
    ``workers`` single-threaded processes serving its dashboard at ``dashboard`` (``:8787``)."""
    option, value = ("--cluster", cluster) if cluster else ("--dashboard", dashboard)
    config, distributed = _dask(option, value)
    from distributed.utils import TimeoutError as DaskTimeoutError

    local = None
    if not cluster:
        # No spilling and no pausing (the nanny still restarts a worker at 95 % of its memory): a
        # case's result is a few kB, and both make the worker's event loop call gc.collect() in its
        # own thread while a flight runs CasADi (genthermal.collector).
        with config.set({"distributed.worker.memory.target": False, "distributed.worker.memory.spill": False,
                         "distributed.worker.memory.pause": False}):
            local = distributed.LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                             dashboard_address=dashboard)
        print(f"Dask dashboard: {local.dashboard_link}")
    client = distributed.Client(cluster or local)
    flights = []
    try:
        futures = [client.submit(fly_case_here, fly_case, documents[i], *arguments, pure=False,
                                 priority=len(order) - rank, key=f"case-{i}") for rank, i in enumerate(order)]
        try:
            for future in distributed.as_completed(futures, timeout=timeout_s):
                flights += future.result()
                bar.update()
        except (TimeoutError, DaskTimeoutError):
            client.cancel([f for f in futures if not f.done()])
    finally:
        client.close()
        if local is not None:
            local.close()
    return flights
