r"""How far the load manager's prediction stands from the plant on the chapter-7 proxies.

The thesis defines its chapter-7 thresholds by what the **load manager** does: "the minimum fault
level required for the load management system to take action" (7.3.3). The manager acts when its
prediction (the affine design model from the filtered state, inlet held, with the rise back-off of
:class:`~genthermal.schedule.planning.plan.PlanningProblem`) passes the planning limit in some management
cycle, not when the plant does. The two differ: measured on the chapter-7 calibration, the design
model's rise over the 5-min rated-current start-up of landing is about 30 % short of the nonlinear
model's (its :math:`I^2` line has slope 8.9 A where :math:`dI^2/dI = 14` A at 7 A; the rise back-off
0.3 makes up most of it), while over the hours of cruise its steady state is 1-2 K hot (the line
is above :math:`I^2` at 4.9 A). From the first cycles after the fault, the manager's prediction of
the landing peak is about 2 K above what the plant reaches.

:func:`manager_prediction_lag` measures that difference for one proxy: the plant flies the nominal
mission (no action) with the proxy's inlet rise; at every management cycle from the fault on, the
manager's robust prediction of the rest of the mission is made from the plant's state (the
filter's estimate is within 0.2 K of it, measured in the closed loop) and its peak inside the
proxy's window is taken. The lag is the plant's peak in the window less the highest of those
predicted peaks: negative when the manager predicts hotter than the plant. The fit
(:func:`studies.chapter7.fit_chapter7`) puts each inlet proxy's plant peak at θmax plus
its lag, so that the manager's prediction just reaches θmax at the thesis's threshold.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from genthermal.mission import load_mission
from genthermal.model import ThermalModel

#: Scenario whose mission, generators and limit the measurement flies (the inlet rise is the proxy's).
SCENARIO = "chapter7_inlet_4C"
#: Plant step of the measurement, s (the closed loop's default ``ManagerSettings.dt_s``).
DT_S = 10.0


def manager_prediction_lag(model: ThermalModel, inlet_rise_C: float, window_s: tuple[float, float],
                           onset_s: float) -> dict:
    """The plant's peak and the manager's highest predicted peak inside ``window_s`` (module docstring).

    Parameters
    ----------
    model : ThermalModel
        The plant and the planning model (the chapter-7 scenarios fly the model itself, 7.3.2).
    inlet_rise_C : float
        Inlet rise of the faulty generator from ``onset_s`` on (a step), K.
    window_s : (float, float)
        Part of the mission whose peak counts, s from the mission start.
    onset_s : float
        Fault onset, s.

    Returns
    -------
    dict
        ``plant_peak_C``, ``predicted_peak_C`` (highest over the cycles), ``lag_K`` (plant − predicted),
        ``cycle_s`` (the cycle of the highest prediction, s).
    """
    from genthermal.schedule.flight.manager_settings import ManagerSettings
    from genthermal.schedule.planning.plan import (PlanningProblem, Schedule, build_timeline, mission_segments, predict,
                                 remaining_after, robust_outputs)
    from genthermal.schedule.power_system import Fault, PowerSystem
    from genthermal.simulate import simulate

    settings = ManagerSettings(dt_s=DT_S)
    system = PowerSystem.from_mission(load_mission(SCENARIO))
    fault = Fault(0, float(onset_s), "inlet_rise", float(inlet_rise_C))
    system = dataclasses.replace(system, faults=(fault,), model=model, plant=model, plant_mismatch={})
    segments = mission_segments(system.mission)
    timeline = build_timeline(segments, Schedule.nominal(1, len(segments)), system.rest_current_A, DT_S)
    inputs = system.mission.to_inputs(DT_S, model.spec.interface.generator)
    time_s = inputs["time_s"].to_numpy()
    inputs[model.spec.interface.generator.coolant_input] = system.inlet_C(0, time_s)
    run = simulate(model, inputs)
    states = run[[f"T_{name}" for name in model.state_names]].to_numpy()
    winding = run["T_winding"].to_numpy()
    inside = (time_s >= window_s[0] - 1e-9) & (time_s <= window_s[1] + 1e-9)
    generator = system.design_generator_for(())
    winding_row = list(generator.model.output_names).index("T_winding")
    best = (-np.inf, None)
    first_cycle = np.ceil(onset_s / settings.cycle_s - 1e-9) * settings.cycle_s
    for cycle_s in np.arange(first_cycle, window_s[1] + 1e-9, settings.cycle_s):
        k = int(round(cycle_s / DT_S))
        remaining, schedule = remaining_after(segments, Schedule.nominal(1, len(segments)), timeline, k)
        if not remaining:
            break
        problem = PlanningProblem(remaining, [generator], states[k][None, :], system.inlet_C(0, np.array([cycle_s])),
                                  system.mission.T_ambient_C, system.rest_current_A, system.current_limit_A,
                                  system.limit_C, dt_s=DT_S, rise_backoff=settings.rise_backoff,
                                  window_s=settings.cycle_s)
        prediction = predict(problem, schedule)
        outputs = prediction.outputs[0, winding_row]
        robust = np.maximum(outputs[1:], robust_outputs(outputs, prediction.timeline.window_start,
                                                        problem.rise_backoff))
        at = cycle_s + prediction.time_s[1:]
        mask = (at >= window_s[0] - 1e-9) & (at <= window_s[1] + 1e-9)
        if mask.any() and robust[mask].max() > best[0]:
            best = (float(robust[mask].max()), float(cycle_s))
    plant_peak = float(winding[inside].max())
    return {"plant_peak_C": plant_peak, "predicted_peak_C": best[0], "lag_K": plant_peak - best[0],
            "cycle_s": best[1]}
