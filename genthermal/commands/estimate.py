"""``genthermal estimate DATA.csv [--json out.json]``: Kalman filter and n-step prediction study
(thesis 6.3) of the design model on rig data."""

from __future__ import annotations

import math
from pathlib import Path

from ..design import linear_design_model
from ..errors import InputError
from ..estimation.kalman import KalmanFilter
from ..estimation.prediction import (
    DEFAULT_MARGIN_K,
    DEFAULT_SMOOTHING_MIN,
    THESIS_STARTS_MIN,
    check_start_times,
    on_grid,
    prediction_study,
)
from ..machines import build_model
from ..measurements import load_measurements
from ..outputs import report_json
from ._common import positive_float


def register(subparsers) -> None:
    """Add the ``estimate`` sub-command."""
    parser = subparsers.add_parser(
        "estimate", help="Kalman filter and n-step prediction on rig data (thesis 6.3)",
        description="Filter the measured winding and iron temperatures with the linear design model, "
        "run the model open loop, predict from each start time, and report the RMS errors and how "
        "long each prediction beats the open-loop model.")
    parser.add_argument("data", help="rig data CSV (genthermal.measurements schema)")
    parser.add_argument("--json", metavar="OUT.json", help="write the errors and periods of increased accuracy as JSON")
    parser.add_argument("--predict-from", default=",".join(str(s) for s in THESIS_STARTS_MIN), metavar="MIN,...",
                        help="prediction start times, min after the first sample (default 50,75,100,125,150,175)")
    parser.add_argument("--dt", default="10",
                        help="filter step in s; data on another grid are resampled to it (default 10)")
    parser.add_argument("--plot", metavar="OUT.png", help="prediction plot (thesis Figs 6.8-6.10); the filter "
                        "plot goes next to it as <name>_filter.png")
    parser.add_argument("--steady-state", action="store_true", help="use the converged (steady-state) gain")
    parser.add_argument("--estimate-noise", action="store_true",
                        help="estimate R from the data (thesis 6.2.2) instead of using eq. 6.10")
    parser.add_argument("--min-improvement", default=str(DEFAULT_MARGIN_K), metavar="K",
                        help=f"smallest improvement over the open loop that counts, K (default {DEFAULT_MARGIN_K:g})")
    parser.set_defaults(func=run)


def parse_starts(text: str) -> list[float]:
    """Parse ``"50,75,100"`` into minutes, raising InputError naming ``--predict-from``."""
    starts = []
    for item in str(text).split(","):
        try:
            value = float(item)
        except ValueError:
            raise InputError("--predict-from", item.strip(),
                             "expected comma-separated minutes, e.g. 50,75,100") from None
        if not math.isfinite(value) or value < 0:
            raise InputError("--predict-from", item.strip(), "a start time must be a number of minutes >= 0")
        starts.append(value)
    return starts


def run(args) -> int:
    """Run the filter and the prediction study; print a summary and write the JSON (and plots)."""
    dt = positive_float("--dt", args.dt)
    starts = parse_starts(args.predict_from)
    try:
        margin = float(args.min_improvement)
    except ValueError:
        raise InputError("--min-improvement", args.min_improvement, "must be a number of kelvin >= 0") from None
    if not (math.isfinite(margin) and margin >= 0):
        raise InputError("--min-improvement", args.min_improvement, "must be a number of kelvin >= 0")
    data = on_grid(load_measurements(args.data), dt)
    check_start_times(starts, (data.time_s[-1] - data.time_s[0]) / 60.0, field="--predict-from")
    design = linear_design_model(build_model())
    kalman = KalmanFilter(design, dt)
    if args.estimate_noise:
        kalman = KalmanFilter(design, dt, R=kalman.estimate_measurement_noise(data.sensors))
    study = prediction_study(design, data, starts, dt, kalman=kalman, smoothing_min=DEFAULT_SMOOTHING_MIN,
                             margin_K=margin, steady_state=args.steady_state)
    result = study.filter_result
    report = {"data": str(args.data), "dt_s": dt, "samples": len(result.time_s),
              "samples_without_measurement": result.samples_without_measurement,
              "missing_counts": result.missing_counts, "steady_state_gain": bool(args.steady_state),
              "R_K2": [kalman.R[i, i] for i in range(len(kalman.output_names))], **study.to_json()}
    print_summary(report, result)
    if args.json:
        report_json(args.json, report)
    if args.plot:
        plot = Path(args.plot)
        filter_plot = plot.with_name(f"{plot.stem}_filter{plot.suffix or '.png'}")
        study.plot(plot)
        result.plot(filter_plot)
        print(f"wrote {plot} and {filter_plot}")
    return 0


def print_summary(report: dict, result) -> None:
    """Print the errors, the periods of increased accuracy and the final unmeasured temperatures."""
    names = list(report["filter_rmse"])
    mode = "steady-state" if report["steady_state_gain"] else "time-varying"
    print(f"{report['data']}: {report['samples']} samples every {report['dt_s']:g} s, {mode} Kalman gain, "
          f"R = diag({', '.join(f'{r:.4g}' for r in report['R_K2'])}) K²")
    print(f"samples without any measurement: {report['samples_without_measurement']}; missing per sensor: "
          + ", ".join(f"{k} {v}" for k, v in report["missing_counts"].items()))
    print(f"\n{'RMS error [K]':26s}" + "".join(f"{name:>12s}" for name in names))
    for label, key in (("filtered - measured", "filter_rmse"), ("one step ahead - measured", "one_step_rmse"),
                       ("open loop - measured", "open_loop_rmse")):
        print(f"{label:26s}" + "".join(f"{report[key][name]:12.3f}" for name in names))
    print(f"\nperiod of increased accuracy [min] (margin {report['margin_K']:g} K, "
          f"{report['smoothing_min']:g}-min trailing mean; >= : record ended first)")
    print(f"{'start [min]':26s}" + "".join(f"{name:>12s}" for name in names))
    censored = report["improved_minutes_censored"]
    for start, values in report["improved_minutes"].items():
        cells = [f"{'>=' if name in censored.get(start, []) else ''}{values[name]:.1f}" for name in names]
        print(f"{start:26s}" + "".join(f"{cell:>12s}" for cell in cells))
    sensor_nodes = set(result.model.spec.sensors.values())
    unmeasured = [(node, result.states[-1, j]) for j, node in enumerate(result.model.state_names)
                  if node not in sensor_nodes]
    print("\nestimated unmeasured temperatures at the end [°C]: "
          + ", ".join(f"{node} {value:.1f}" for node, value in unmeasured))
