"""An item that fails in a forked worker fails the map in the parent with its own error, never a
hang or the pool's internal assertion (diagnose's candidate fits run this way)."""

from __future__ import annotations

import pytest

from genthermal.diagnose.parallel import WorkerError, can_fork, map_in_workers
from genthermal.errors import InputError

pytestmark = pytest.mark.skipif(not can_fork(), reason="no fork on this platform: items run in this process")


class UnpicklableError(Exception):
    """An exception whose constructor needs two arguments: it pickles, but does not unpickle (as
    some wrapped solver exceptions)."""

    def __init__(self, what, detail):
        super().__init__(f"{what}: {detail}")


def test_results_come_back_in_the_order_of_the_items():
    assert map_in_workers(lambda x: x * x, range(7), workers=2) == [x * x for x in range(7)]


def test_an_input_error_in_a_worker_reaches_the_parent_as_itself():
    def check(x):
        if x == 3:
            raise InputError("k_flow", x, "must be below 1")
        return x

    with pytest.raises(InputError, match="k_flow"):
        map_in_workers(check, range(6), workers=2)


def test_an_exception_that_does_not_unpickle_becomes_a_worker_error_naming_the_item():
    def fail(x):
        if x == 2:
            raise UnpicklableError("solver", "restoration failed")
        return x

    with pytest.raises(WorkerError) as caught:
        map_in_workers(fail, range(5), workers=2)
    text = str(caught.value)
    assert "UnpicklableError on item 2" in text and "restoration failed" in text and "worker traceback" in text
    # the pool is gone and the module free for the next map
    assert map_in_workers(lambda x: -x, [1, 2], workers=2) == [-1, -2]
