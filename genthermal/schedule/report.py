"""Summaries (the JSON keys of ``genthermal plan`` / ``fly``: docs/guide/flight-reference.md),
plots and the scheduler comparison table. Main objects: :func:`flight_summary`,
:func:`plot_flight`, :func:`summary_text`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..plots import finish_figure, plt
from .planning.shed import not_served

if TYPE_CHECKING:
    from .flight.flight_result import FlightResult


def flight_summary(result: FlightResult) -> dict:
    """The summary keys (module docstring) of a flown or planned mission."""
    system = result.system
    names = system.generator_names
    dt = float(np.diff(result.time_s[:2])[0]) if result.time_s.size > 1 else 0.0
    above = result.temperatures_C[:, :, 1:] > system.limit_C
    moved_off = np.clip(result.nominal_A[None, :] - result.currents_A, 0.0, None)[:, ~result.resting]
    lost = not_served(result.nominal_A, result.currents_A, result.resting)
    solve_times = [plan["solve_s"] for plan in result.plans]
    cpu_times = [plan["solve_cpu_s"] for plan in result.plans if "solve_cpu_s" in plan]
    lowest = [plan["lowest_peak_C"] for plan in result.plans if "lowest_peak_C" in plan]
    summary = {
        "scheduler": result.scheduler,
        "planner_model": None if result.settings is None else result.settings.planner_model,
        "closed_loop": result.closed_loop,
        "mission_time_s": float(result.time_s[-1]),
        "added_rest_s": float(result.time_s[-1] - system.mission.duration_s),
        "rested_s": float(np.count_nonzero(result.resting) * dt),
        "max_T_winding": {n: float(result.temperatures_C[g, 0].max()) for g, n in enumerate(names)},
        "max_T_iron": {n: float(result.temperatures_C[g, 1].max()) for g, n in enumerate(names)},
        "breach_s": float(np.count_nonzero(above.any(axis=(0, 1))) * dt),
        "replans": len(result.plans),
        "median_solve_s": float(np.median(solve_times)) if solve_times else 0.0,
        "median_solve_cpu_s": float(np.median(cpu_times)) if cpu_times else None,
        "displaced_Ah": float((moved_off.sum() - lost.sum()) * dt / 3600.0),
        "feasible": bool(all(plan["feasible"] for plan in result.plans) and not result.shed_events
                         and not lost.any() and getattr(result, "plant_fault", None) is None
                         and (result.preflight is None or result.preflight["feasible"])),
        "lowest_reachable_peak_C": float(max(lowest)) if lowest else None,
        "manager_response": list(dict.fromkeys(plan["response"] for plan in result.plans if plan.get("response"))),
        "rest_budget_s": float(result.rest_budget_s),
        "shed": shed_summary(result, lost, dt),
        "management_cycles": int(result.cycles),
        "warnings": list(dict.fromkeys(result.warnings)),
    }
    if result.closed_loop:
        summary["preflight"] = result.preflight
        summary["plant_fault"] = getattr(result, "plant_fault", None)
        if getattr(result, "replay", None) is not None:
            summary["replay"] = result.replay
    if result.closed_loop and result.monitor is not None:
        summary.update(detection_summary(result))
    if getattr(result, "sensor_watch", None) is not None:
        summary["sensor_faults"] = result.sensor_watch.to_dict(names)
    return summary


def shed_summary(result: FlightResult, lost: np.ndarray, dt_s: float) -> dict:
    """The ``shed`` block (module docstring) from the load not served ``lost`` (n_gen, n), A."""
    names = result.system.generator_names
    steps = np.flatnonzero(lost.sum(axis=0) > 1e-9)
    return {"events": list(result.shed_events),
            "generators": list(dict.fromkeys(n for event in result.shed_events for n in event["shedding"])),
            "switched_off": list(dict.fromkeys(n for event in result.shed_events for n in event["switched_off"])),
            "not_served_As": {n: float(lost[g].sum() * dt_s) for g, n in enumerate(names)},
            "not_served_Ah": {n: float(lost[g].sum() * dt_s / 3600.0) for g, n in enumerate(names)},
            "first_s": float(result.time_s[steps[0]]) if steps.size else None,
            "last_s": float(result.time_s[steps[-1] + 1]) if steps.size else None}


def detection_summary(result: FlightResult) -> dict:
    """The detection keys (module docstring) of a closed-loop flight."""
    system, monitor = result.system, result.monitor
    names = system.generator_names

    def onset(g, t_s):
        started = [f.onset_s for f in system.faults if f.generator == g and f.onset_s <= t_s + 1e-9]
        return min(started) if started else None
    true_alarms = [(a["time_s"], onset(a["generator"], a["time_s"])) for a in monitor.alarms
                   if onset(a["generator"], a["time_s"]) is not None]
    first = min(true_alarms, default=None)
    return {"tell_fault": bool(result.settings.tell_fault),
            "detected_at_s": None if first is None else float(first[0]),
            "detect_delay_s": None if first is None else float(first[0] - first[1]),
            "identified": [i.to_dict(names) for i in monitor.identifications],
            "false_alarms": len(monitor.alarms) - len(true_alarms),
            "recalibrations": [{"time_s": c["time_s"], "generator": names[c["generator"]],
                                "parameters": c["parameters"],
                                "error_model": None if c.get("error_model") is None else c["error_model"].to_dict()}
                               for c in monitor.calibrations]}


def summary_text(summary: dict, limit_C: float) -> str:
    """A few lines for the terminal."""
    peaks = ", ".join(f"{name} {summary['max_T_winding'][name]:.1f}/{summary['max_T_iron'][name]:.1f}"
                      for name in summary["max_T_winding"])
    lines = [f"mission time {summary['mission_time_s'] / 60:.1f} min "
             f"(added rest {summary['added_rest_s'] / 60:.1f} min); "
             f"peak winding/iron °C: {peaks}",
             f"time above {limit_C:g} °C: {summary['breach_s']:.0f} s; plans: {summary['replans']}, median solve "
             f"{summary['median_solve_s']:.2f} s; displaced {summary['displaced_Ah']:.2f} A·h"]
    if "identified" in summary and not summary["tell_fault"]:
        found = "; ".join(f"{i['generator']}: {i['effect'] or 'nothing significant'} at {i['detected_at_s'] / 60:.0f} min"
                          + (f" (onset {i['onset_s'] / 60:.0f} min, {', '.join(f'{k}={v:.3g}' for k, v in i['parameters'].items())})"
                             if i["effect"] else "") for i in summary["identified"]) or "no fault alarm"
        lines.append(f"in-flight detection: {found}; false alarms {summary['false_alarms']}")
    shed = summary.get("shed") or {}
    if shed.get("events"):
        served = ", ".join(f"{n} {v:.2f} A·h" for n, v in shed["not_served_Ah"].items() if v > 0)
        when = ", ".join(f"{event['time_s'] / 60:.0f} min" for event in shed["events"])
        off = f"; switched off {', '.join(shed['switched_off'])}" if shed["switched_off"] else ""
        lines.append(f"shed: load of {', '.join(shed['generators'])} shed from {when}{off}; "
                     f"load not served {served or 'none'}")
    lines += [w if w.startswith("infeasible") else f"warning: {w}" for w in summary["warnings"]]
    return "\n".join(lines)


def plot_flight(result: FlightResult, title: str = "", path=None):
    """Applied currents (rests shaded) and winding and iron temperatures of every generator."""
    system = result.system
    labels = list(system.planning_model.output_names)
    hours = result.time_s / 3600.0
    fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True, gridspec_kw={"height_ratios": [1, 1.4, 1.4]})
    steps = hours[:-1]
    axes[0].step(steps, result.nominal_A, where="post", color="k", ls=":", lw=1, label="nominal")
    for g, name in enumerate(system.generator_names):
        axes[0].step(steps, result.currents_A[g], where="post", lw=1.3, label=name)
        for panel, output in zip(axes[1:], labels):
            panel.plot(hours, result.temperatures_C[g, labels.index(output)], lw=1.3, label=name)
    for ax in axes:
        edges = np.flatnonzero(np.diff(np.concatenate([[0], result.resting.astype(int), [0]])))
        for start, end in zip(edges[::2], edges[1::2]):
            ax.axvspan(steps[start], hours[end], color="tab:green", alpha=0.15, lw=0)
        ax.grid(alpha=0.3)
    monitor = result.monitor
    for found in (monitor.identifications if monitor is not None else []):
        label = (f"{system.generator_names[found.generator]}: {found.effect} identified" if found.effect else
                 f"{system.generator_names[found.generator]}: alarm, nothing significant")
        for ax in axes:
            ax.axvline(found.detected_at_s / 3600.0, color="k" if found.effect else "grey", ls="-.", lw=1)
        axes[1].annotate(label, (found.detected_at_s / 3600.0, axes[1].get_ylim()[0]), rotation=90, fontsize=7,
                         va="bottom", ha="right")
    for panel, output in zip(axes[1:], labels):
        panel.axhline(system.limit_C, color="red", ls="--", lw=1, label=f"limit {system.limit_C:g} °C")
        panel.set_ylabel(f"{output} [°C]")
        panel.legend(loc="upper left", fontsize=8)
    axes[0].set_ylabel("phase current [A]")
    axes[0].legend(loc="lower right", fontsize=8, ncol=system.n_generators + 1)
    axes[-1].set_xlabel("time [h] (green: rest)")
    kind = "closed loop, true plant" if result.closed_loop else "open-loop plan, design model"
    axes[0].set_title(title or f"{system.mission.name}: {result.scheduler} ({kind})")
    return finish_figure(fig, path, close=True)


def comparison_table(summaries: dict) -> str:
    """Markdown table of several summaries (label → summary)."""
    header = ("| scheduler | mission min | added rest min | peak winding °C | breach s | plans | median solve s "
              "| displaced A·h |")
    rows = [header, "|" + "---|" * 8]
    for label, s in summaries.items():
        rows.append(f"| {label} | {s['mission_time_s'] / 60:.1f} | {s['added_rest_s'] / 60:.1f} | "
                    f"{max(s['max_T_winding'].values()):.1f} | {s['breach_s']:.0f} | {s['replans']} | "
                    f"{s['median_solve_s']:.2f} | {s['displaced_Ah']:.2f} |")
    return "\n".join(rows)
