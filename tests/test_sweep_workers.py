"""A sweep flies in worker processes of one thread each: no port, no restarted worker, twice over.

CasADi's symbolic core is not thread-safe; on a Dask local cluster a ``sweep --cases 2`` had a
worker abort with glibc's "corrupted double-linked list" and be restarted, and the run still ended
with exit code 0. The default now needs no Dask at all.
"""

import os
import threading

import pytest

from genthermal.cli import main
from genthermal.errors import InputError
from genthermal.schedule.sweeps import sweep, sweep_workers

try:
    import psutil  # lists the sockets of the worker processes
except ImportError:
    psutil = None

SHORT_CASES = [
    {"name": "short0:healthy:2gen:0.5h", "actions": [{"condition": c, "duration_min": 15} for c in (4, 5)],
     "generators": {"count": 2, "plant_mismatch": {"h_end_air": 0.8, "R0": 1.2}}, "faults": []},
    {"name": "short1:blockage:2gen:0.5h", "actions": [{"condition": c, "duration_min": 15} for c in (4, 6)],
     "generators": {"count": 2, "plant_mismatch": {"h_end_air": 1.2, "R0": 0.8}},
     "faults": [{"generator": 1, "kind": "coolant_blockage", "onset_min": 5, "k_flow": 0.3, "inlet_rise_C": 20}]},
]


class PortWatch:
    """Inet sockets listening in this process or any of its children, polled while a block runs."""

    def __init__(self):
        self.listening, self.children, self._stop = set(), set(), threading.Event()
        self._thread = threading.Thread(target=self._poll, daemon=True)

    def _poll(self):
        me = psutil.Process()
        while not self._stop.is_set():
            for process in [me] + me.children(recursive=True):
                try:
                    sockets = process.net_connections(kind="inet")
                except (psutil.NoSuchProcess, psutil.AccessDenied):
                    continue
                if process.pid != me.pid:
                    self.children.add(process.pid)
                self.listening |= {(process.pid, s.laddr) for s in sockets if s.status == psutil.CONN_LISTEN}
            self._stop.wait(0.1)

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()


@pytest.mark.slow
def test_a_small_sweep_runs_twice_in_single_threaded_processes_with_no_port_and_no_restart():
    if psutil is None:
        pytest.skip("psutil lists the worker processes' sockets (pip install psutil)")
    with PortWatch() as watch:
        pids, peaks = [], []
        for _ in range(2):
            records = sweep.run_sweep(SHORT_CASES, ("engineer",), workers=2, progress=False, hindsight=False)
            runs = [record["runs"]["engineer"] for record in records]
            assert [r["status"] for r in runs] == ["ok", "ok"], runs
            assert all(r["worker_threads"] == 1 for r in runs)  # the flight's thread is the worker's only one
            assert os.getpid() not in {r["worker_pid"] for r in runs}
            pids.append({r["worker_pid"] for r in runs})
            peaks.append([r["max_T_winding"] for r in runs])
    assert peaks[0] == peaks[1] and peaks[0][0]["gen1"] > 40.0  # the same seeded flights, flown
    assert watch.listening == set()
    assert all(len(p) <= 2 for p in pids) and not pids[0] & pids[1]  # a fresh pool per sweep, nobody restarted
    assert {pid for p in pids for pid in p} <= watch.children


def _die(document, *arguments):
    os._exit(3)  # a worker killed mid-flight, as by glibc's abort


def test_a_worker_that_dies_is_recorded_not_restarted():
    records = sweep_workers.fly_cases_in_processes(_die, SHORT_CASES[:1], [0], (), ("engineer",), 1, None, _Bar())
    assert len(records) == 1 and records[0]["status"] == "error" and "worker process died" in records[0]["error"]
    assert "not flown again" in records[0]["error"]


class _Bar:
    def update(self):
        pass


def test_dask_options_name_the_extra_when_dask_is_missing(monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_dask(name, *args, **kwargs):
        if name.split(".")[0] in ("dask", "distributed"):
            raise ImportError(f"No module named {name!r}", name=name)
        return real_import(name, *args, **kwargs)
    monkeypatch.setattr(builtins, "__import__", no_dask)
    with pytest.raises(InputError, match=r"--cluster.*genthermal\[sweep\]"):
        sweep_workers.fly_cases_on_dask(sweep.fly_case, [], [], (), "tcp://127.0.0.1:1", 1, None, None, _Bar())
    with pytest.raises(InputError, match=r"--dashboard.*genthermal\[sweep\]"):
        sweep_workers.fly_cases_on_dask(sweep.fly_case, [], [], (), None, 1, ":8787", None, _Bar())


def test_dashboard_and_cluster_together_are_refused(capsys):
    assert main(["sweep", "--cases", "1", "--cluster", "tcp://127.0.0.1:1", "--dashboard"]) == 2
    assert "--dashboard" in capsys.readouterr().err
