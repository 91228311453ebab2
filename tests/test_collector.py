"""The cyclic collector kept in the thread that runs CasADi (genthermal.collector)."""

import gc
import threading
import weakref

import pytest

from genthermal.collector import collector_in_this_thread
from genthermal.schedule.sweeps import sweep


class _Node:
    """An object that can sit in a reference cycle and be watched with a weak reference."""


def _cycle() -> weakref.ref:
    node = _Node()
    node.me = node
    return weakref.ref(node)


@pytest.fixture
def collections():
    """(phase, thread id) of every collection while the test runs."""
    seen = []

    def record(phase, info):
        if phase == "start":
            seen.append(threading.get_ident())

    gc.callbacks.append(record)
    yield seen
    gc.callbacks.remove(record)


def test_no_collection_in_another_thread_while_the_block_runs(collections):
    assert gc.isenabled()
    watched = []
    with collector_in_this_thread():
        def allocate():  # far past every generation's threshold
            for _ in range(50_000):
                watched.append(_cycle()) if len(watched) < 10 else _cycle()
        other = threading.Thread(target=allocate)
        other.start()
        other.join()
        assert collections == [], "a collection ran while the block held the collector"
        assert all(ref() is not None for ref in watched), "cycles were collected inside the block"
    assert collections and set(collections) == {threading.get_ident()}, "the end's collection is this thread's"
    assert all(ref() is None for ref in watched), "the block's end did not collect its cycles"
    assert gc.isenabled()


def test_nested_blocks_keep_it_off_and_an_error_restores_it():
    with pytest.raises(RuntimeError, match="inner"):
        with collector_in_this_thread():
            with collector_in_this_thread():
                pass
            assert not gc.isenabled(), "the inner block's end switched the collector back on"
            raise RuntimeError("inner")
    assert gc.isenabled()
    gc.disable()
    try:
        with collector_in_this_thread():
            pass
        assert not gc.isenabled(), "a collector that was off before the block is left off"
    finally:
        gc.enable()


def test_a_sweep_flies_each_flight_with_the_collector_in_its_thread(monkeypatch):
    enabled = []

    def fly_flight(document, scheduler, cpu_limit_s, model):
        enabled.append(gc.isenabled())
        return {"case": document["name"], "scheduler": scheduler, "status": "ok", "summary": {"replans": 1}}

    monkeypatch.setattr(sweep, "fly_flight", fly_flight)
    records = sweep.fly_case(sweep.robustness_case(1, 0), ("heuristic", "engineer"))
    assert [r["scheduler"] for r in records] == ["heuristic", "engineer"]
    assert enabled == [False, False]
    assert gc.isenabled()
