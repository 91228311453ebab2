"""Before take-off: can any plan hold θmax on this mission (the ``preflight`` block of a flight)?

The open-loop plan of the mission (:func:`~genthermal.schedule.flight.open_loop.plan_mission`) on
the model the manager plans on, every fault of the scenario taken as known at its onset, judged on
its own forecast (with the linear filter, also on the manager's nonlinear model). A forecast above θmax
means no plan the manager can make holds it: the flight says so before its first step. In flight the manager still detects the faults itself (unless told).
Main object: :func:`preflight_check`.
"""

from __future__ import annotations

import time
import types

import numpy as np

from ..planning.plan import within_limit
from ..power_system import PowerSystem
from ..report import flight_summary
from .manager_settings import ManagerSettings
from .open_loop import FlownOpenLoop, plan_mission


def flown_model_peak(system: PowerSystem, planned, dt_s: float) -> tuple:
    """The peak (°C) and its generator of the currents ``planned`` (an open-loop
    :class:`~genthermal.schedule.flight.flight_result.FlightResult`) flown on the planning model
    (the nonlinear model the manager holds), every fault of the scenario at its onset: a plan made
    on the design model judged by the manager's other prediction of the same flight."""
    run = FlownOpenLoop(system, dt_s)
    n_gen, n_states = system.n_generators, system.nominal_model.n_states
    start = np.hstack([np.full((n_gen, n_states), system.mission.T_ambient_C),
                       np.zeros((n_gen, len(run.filter(0, 0.0).disturbance_names)))])
    timeline = types.SimpleNamespace(currents_A=planned.currents_A, dt_s=dt_s)
    outputs, _ = run.steps(start, timeline, 0.0, planned.currents_A.shape[1])
    g = int(np.unravel_index(np.argmax(outputs), outputs.shape)[0])
    return float(outputs.max()), system.generator_names[g]


def preflight_check(system: PowerSystem, scheduler: str, settings: ManagerSettings) -> dict:
    """The verdict before take-off on flying ``system`` with ``scheduler`` (module docstring).

    Parameters
    ----------
    system : PowerSystem
        The generators, the mission and the scenario's faults.
    scheduler : str
        A registered planner.
    settings : ManagerSettings
        The flight's settings (``planner_model`` ``auto`` is resolved as the flight resolves it).

    Returns
    -------
    dict
        ``feasible`` (the plan's forecast serves every load within the planning limit), ``holds_limit``
        (its forecast peak is within θmax, by the tolerance every plan is judged with: a plan that
        sheds load may hold it), ``planned_peak_C`` (that forecast's peak, °C), ``peak_generator``,
        ``lowest_reachable_peak_C`` (the lowest peak rest and displacement reach, °C; None when the
        plan kept the planning limit), ``limit_C`` (θmax, °C), ``planner_model`` (the model planned
        on), ``flown_model_peak_C`` (with the linear filter, which no flown model corrects in
        flight, the design-model plan flown on the manager's nonlinear model, °C: above θmax, the
        plan does not hold it either; None otherwise),
        ``faults`` (how many the plan knew), ``response`` (what the manager does when no plan
        keeps the limit), ``cpu_s`` (processor time of the check, s) and ``message``.
    """
    started = time.process_time()
    # resolved with the filter the flight runs (the scenario's say), not the open-loop plan's
    filter_flown = system.manager_say.get("filter", settings.filter)
    settings = settings.for_flight(scheduler, filter_flown)
    planned = plan_mission(system, scheduler, settings)
    summary = flight_summary(planned)
    peaks = {name: max(summary["max_T_winding"][name], summary["max_T_iron"][name]) for name in summary["max_T_winding"]}
    generator = max(peaks, key=peaks.get)
    peak, lowest, limit = peaks[generator], summary["lowest_reachable_peak_C"], system.limit_C
    holds = within_limit(peak, limit)
    flown_peak = flown_generator = None
    if settings.planner_model == "affine" and filter_flown != "ekf":
        # the linear filter runs on the design model all flight: nothing in flight corrects what
        # it under-predicts (the extended filter's disturbance states would)
        flown_peak, flown_generator = flown_model_peak(system, planned, settings.dt_s)
    feasible = bool(summary["feasible"] and holds)
    response = system.manager_say.get("when_infeasible", settings.when_infeasible)
    told = f"with the scenario's {len(system.faults)} fault(s) at their onset" if system.faults else "without faults"
    if holds and not within_limit(flown_peak if flown_peak is not None else peak, limit):
        holds = feasible = False
        message = (f"before take-off: the plan on the design model holds θmax {limit:g} °C {told} (forecast "
                   f"{peak:.1f} °C), but flown on the manager's nonlinear model it reaches {flown_peak:.1f} °C on "
                   f"{flown_generator}: the design model under-predicts this mission, and the manager plans on it "
                   f"(planner_model {settings.planner_model}, filter "
                   f"{filter_flown}); fly with --filter ekf to plan on the "
                   "flown model")
    elif not holds:
        message = (f"before take-off: no plan holds θmax {limit:g} °C {told}: the lowest reachable peak is "
                   f"{(peak if lowest is None else lowest):.1f} °C; the plan's forecast reaches {peak:.1f} °C on "
                   f"{generator} ({response.replace('_', ' ')})")
    elif not feasible:
        message = (f"before take-off: no plan serves all load within the planning limit {told} (lowest reachable "
                   f"peak {(peak if lowest is None else lowest):.1f} °C); the plan holds θmax {limit:g} °C, "
                   f"forecast peak {peak:.1f} °C on {generator}" + (", shedding load" if summary["shed"]["events"] else ""))
    else:
        message = f"before take-off: a plan holds θmax {limit:g} °C {told}: forecast peak {peak:.1f} °C on {generator}"
    return {"feasible": feasible, "holds_limit": holds, "planned_peak_C": float(peak), "peak_generator": generator,
            "lowest_reachable_peak_C": lowest, "limit_C": float(limit), "planner_model": settings.planner_model,
            "flown_model_peak_C": flown_peak,
            "faults": len(system.faults), "response": response, "cpu_s": time.process_time() - started,
            "message": message}
