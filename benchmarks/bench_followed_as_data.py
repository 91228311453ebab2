"""Followed as data: which genthermal files the ``fly`` command's model, system and settings enter.

Flies a mission the way ``genthermal fly`` does (``PowerSystem.from_mission``, ``ManagerSettings``,
``closed_loop.fly``) under :func:`sys.settrace` and records every call of a genthermal function that
receives one of the three objects as an argument (``self`` included): the **model** (the system's
planning model, a ``ThermalModel``), the **system** (``PowerSystem``) and the **settings**
(``ManagerSettings``). A file is *entered* by an object when one of its functions is called with it;
a *return* is a call into a file the object's path had already left for another file.

Usage::

    python benchmarks/bench_followed_as_data.py [--scenario step_rated] [--scheduler engineer]

Prints one JSON object: per object the files entered (repository paths), their count and the
returns; ``files_entered`` over the three (``flight_code_files_entered``: those in schedule/ and
plants/; the others are the model's own code and diagnose's calibration), and the target
(``targets``: at most 15 files).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from genthermal.mission import load_mission
from genthermal.schedule.flight.closed_loop import fly
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.power_system import PowerSystem

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = str(ROOT / "genthermal")
#: The issue's target: the files the fly command's objects enter.
TARGET_FILES = 15


class DataTrace:
    """A :func:`sys.settrace` hook that follows objects (name → object) by identity into calls."""

    def __init__(self, followed: dict):
        self.followed = {id(obj): name for name, obj in followed.items()}
        self.paths = {name: [] for name in followed}  # per object, the files of the calls it entered

    def __call__(self, frame, event, arg):
        if event != "call":
            return None
        filename = frame.f_code.co_filename
        if not filename.startswith(PACKAGE):
            return None
        code = frame.f_code
        n_args = code.co_argcount + code.co_kwonlyargcount
        local = frame.f_locals
        for name in code.co_varnames[:n_args]:
            found = self.followed.get(id(local.get(name)))
            if found is not None:
                path = self.paths[found]
                relative = str(Path(filename).relative_to(ROOT))
                if not path or path[-1] != relative:
                    path.append(relative)
        return None

    def summary(self) -> dict:
        """Per object: ``files`` (sorted), ``n_files``, ``returns``."""
        out = {}
        for name, path in self.paths.items():
            files = sorted(set(path))
            out[name] = {"n_files": len(files), "returns": len(path) - len(files), "files": files}
        return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="step_rated", help="shipped scenario or file (default step_rated)")
    parser.add_argument("--scheduler", default="engineer", help="scheduler (default engineer)")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    system = PowerSystem.from_mission(load_mission(args.scenario))
    settings = ManagerSettings()
    trace = DataTrace({"model": system.planning_model, "system": system, "settings": settings})
    sys.settrace(trace)
    try:
        result = fly(system, args.scheduler, settings)
    finally:
        sys.settrace(None)
    objects = trace.summary()
    entered = sorted(set().union(*(set(o["files"]) for o in objects.values())))
    flight_code = [f for f in entered if f.startswith(("genthermal/schedule/", "genthermal/plants/"))]
    print(json.dumps({"benchmark": "followed_as_data", "scenario": args.scenario, "scheduler": args.scheduler,
                      "cycles": result.cycles, "objects": objects, "files_entered": len(entered),
                      "files": entered, "flight_code_files_entered": len(flight_code), "target_files": TARGET_FILES,
                      "targets": {f"at_most_{TARGET_FILES}_files": len(entered) <= TARGET_FILES},
                      "wall_s": round(time.perf_counter() - started, 1)}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
