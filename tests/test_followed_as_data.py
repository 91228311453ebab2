"""The flight's parts receive narrow data: followed with benchmarks/bench_followed_as_data.py's tracer,
the power system enters only ``fly`` and its own methods, the manager's settings only ``fly`` and
their own split into the roles' settings; the planner, the recorder, the monitor and the plant get
neither."""

import sys

from genthermal.schedule.flight.closed_loop import fly
from genthermal.schedule.flight.manager_settings import ManagerSettings

from test_plants import HOT_MISSION, _system


def test_the_system_and_the_settings_stop_at_take_off(tmp_path, benchmark_script):
    bench = benchmark_script("bench_followed_as_data")
    system, _ = _system(tmp_path, HOT_MISSION)  # 100 min of 95-104 % load: re-planned in flight
    settings = ManagerSettings()
    trace = bench.DataTrace({"model": system.planning_model, "system": system, "settings": settings})
    sys.settrace(trace)
    try:
        # the verdict before take-off is the open-loop plan of the mission (genthermal plan's), a
        # consumer of the system before the flight: followed here is the flight itself
        result = fly(system, "engineer", settings, preflight=False)
    finally:
        sys.settrace(None)
    assert result.plans  # the planner was run
    followed = trace.summary()
    assert set(followed["system"]["files"]) == {"genthermal/schedule/flight/closed_loop.py",
                                                "genthermal/schedule/power_system.py"}
    assert set(followed["settings"]["files"]) == {"genthermal/schedule/flight/closed_loop.py",
                                                  "genthermal/schedule/flight/manager_settings.py"}
    assert followed["system"]["returns"] <= 3 and followed["settings"]["returns"] == 0
    # the model goes where it is used: the filters, the monitor, its own code; not to the planner
    assert not [f for f in followed["model"]["files"] if "/planning/" in f or "/flight/" in f]
