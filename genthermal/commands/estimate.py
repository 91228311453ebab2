"""``genthermal estimate DATA.csv [--model NAME|FILE] [--filter ekf|kf] [--json out.json]``: filter and
n-step prediction study (thesis 6.3) on rig data, against the open-loop model.

Reference: docs/guide/estimation.md and docs/guide/cli.md.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..errors import InputError
from ._common import add_choice_argument, add_json_argument, add_model_arguments, model_from_args, positive_float
from ._vocabulary import DEFAULT_EVERY_MIN, DEFAULT_MARGIN_K, FILTERS, THESIS_STARTS_MIN


def register(subparsers) -> None:
    """Add the ``estimate`` sub-command."""
    parser = subparsers.add_parser(
        "estimate", help="Kalman filter and n-step prediction on rig data (thesis 6.3)",
        description="Filter the measured winding and iron temperatures with the model (an extended "
        "Kalman filter with disturbance heat flows, or the thesis's linear filter on the design model), "
        "run the model open loop, predict from a start every 10 min, and report the prediction error "
        "at 15, 30 and 60 min against the open-loop model, the one-step error, and how long each "
        "prediction from --predict-from beats the open-loop model.")
    parser.add_argument("data", help="rig data CSV (genthermal.measurements schema)")
    add_model_arguments(parser)
    add_choice_argument(parser, "--filter", FILTERS, default="ekf",
                        help="ekf: extended Kalman filter on the model with disturbance heat flows (default); "
                        "kf: the thesis's linear filter on the model's linear design model")
    parser.add_argument("--every", default=str(DEFAULT_EVERY_MIN), metavar="MIN",
                        help=f"interval between the starts of the error-by-horizon table, min (default "
                        f"{DEFAULT_EVERY_MIN:g})")
    add_json_argument(parser, "the errors and periods of increased accuracy")
    parser.add_argument("--predict-from", default=",".join(str(s) for s in THESIS_STARTS_MIN), metavar="MIN,...",
                        help="prediction start times, min after the first sample (default 50,75,100,125,150,175)")
    parser.add_argument("--dt", default="10",
                        help="filter step in s; data on another grid are resampled to it (default 10)")
    parser.add_argument("--plot", metavar="FILE.png", help="prediction plot (thesis Figs 6.8-6.10); the filter "
                        "plot goes next to it as <name>_filter.png, the predictions against the measured winding "
                        "and the error by horizon as <name>_horizons.png")
    parser.add_argument("--steady-state", action="store_true",
                        help="use the converged (steady-state) gain (--filter kf only)")
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
    from ..design import linear_design_model
    from ..estimation.ekf import ExtendedKalmanFilter
    from ..estimation.kalman import KalmanFilter
    from ..estimation.prediction import (DEFAULT_HORIZONS_MIN, DEFAULT_SMOOTHING_MIN, check_sensors, check_start_times,
                                         horizon_starts, on_grid, prediction_study)
    from ..measurements import load_measurements
    from ..outputs import report_json

    dt = positive_float("--dt", args.dt)
    starts = parse_starts(args.predict_from)
    try:
        margin = float(args.min_improvement)
    except ValueError:
        raise InputError("--min-improvement", args.min_improvement, "must be a number of kelvin >= 0") from None
    if not (math.isfinite(margin) and margin >= 0):
        raise InputError("--min-improvement", args.min_improvement, "must be a number of kelvin >= 0")
    every = positive_float("--every", args.every)
    if args.steady_state and args.filter != "kf":
        raise InputError("--steady-state", True, "only the linear filter has a steady-state gain; add --filter kf")
    model = model_from_args(args)
    data = on_grid(load_measurements(args.data, interface=model.spec.interface), dt)
    check_start_times(starts, (data.time_s[-1] - data.time_s[0]) / 60.0, field="--predict-from")
    horizon_starts(len(data.time_s), dt, DEFAULT_HORIZONS_MIN, every)
    check_sensors(model, data, field=f"{args.data}: sensors")
    model = model if args.filter == "ekf" or model.is_affine else linear_design_model(model)
    make = (lambda **kw: ExtendedKalmanFilter(model, dt, **kw)) if args.filter == "ekf" else \
        (lambda **kw: KalmanFilter(model, dt, **kw))
    try:
        kalman = make()
    except InputError as exc:
        raise InputError("--dt" if exc.field == "dt_s" else exc.field, exc.value, exc.reason) from None
    if args.estimate_noise:
        kalman = make(R=kalman.estimate_measurement_noise(data.sensors))
    study = prediction_study(model, data, starts, dt, kalman=kalman, smoothing_min=DEFAULT_SMOOTHING_MIN,
                             margin_K=margin, steady_state=args.steady_state, every_min=every)
    result = study.filter_result
    report = {"data": str(args.data), "model": model.name, "model_source": str(args.model), "dt_s": dt,
              "samples": len(result.time_s),
              "samples_without_measurement": result.samples_without_measurement,
              "missing_counts": result.missing_counts, "steady_state_gain": bool(args.steady_state),
              "R_K2": [kalman.R[i, i] for i in range(len(kalman.output_names))],
              "disturbance_prior": (model.disturbance_prior.source if getattr(kalman, "prior_used", False)
                                    else None), **study.to_json()}
    print_summary(report, result)
    if args.json:
        report_json(args.json, report)
    if args.plot:
        plot = Path(args.plot)
        filter_plot = plot.with_name(f"{plot.stem}_filter{plot.suffix or '.png'}")
        horizons_plot = plot.with_name(f"{plot.stem}_horizons{plot.suffix or '.png'}")
        study.plot(plot)
        result.plot(filter_plot)
        study.plot_horizons(horizons_plot)
        print(f"wrote {plot}, {filter_plot} and {horizons_plot}")
    return 0


def print_summary(report: dict, result) -> None:
    """Print the errors, the periods of increased accuracy and the final unmeasured temperatures."""
    names = list(report["filter_rmse"])
    mode = "steady-state" if report["steady_state_gain"] else "time-varying"
    kind = "extended Kalman filter" if report["filter"] == "ekf" else "Kalman filter"
    print(f"{report['data']}: {report['samples']} samples every {report['dt_s']:g} s, {kind} on {report['model']} "
          f"({mode} gain), R = diag({', '.join(f'{r:.4g}' for r in report['R_K2'])}) K²")
    if report.get("disturbance_prior"):
        print(f"disturbance states start from the model file's prior: {report['disturbance_prior']}")
    print(f"samples without any measurement: {report['samples_without_measurement']}; missing per sensor: "
          + ", ".join(f"{k} {v}" for k, v in report["missing_counts"].items()))
    width = max(12, *(len(name) + 2 for name in names))  # columns fit the machine's sensor names
    print(f"\n{'RMS error [K]':26s}" + "".join(f"{name:>{width}s}" for name in names))
    for label, key in (("filtered - measured", "filter_rmse"), ("one step ahead - measured", "one_step_rmse"),
                       ("open loop - measured", "open_loop_rmse")):
        print(f"{label:26s}" + "".join(f"{report[key][name]:{width}.3f}" for name in names))
    print(f"\nprediction error by horizon [K] ({report['horizon_starts']} starts every "
          f"{report['horizon_every_min']:g} min): RMS (max) | open loop RMS")
    print(f"{'horizon [min]':26s}" + "".join(f"{name:>28s}" for name in names))
    for horizon, values in report["prediction_rmse_by_horizon"].items():
        cells = [f"{values[n]:.2f} ({report['prediction_max_by_horizon'][horizon][n]:.2f}) | "
                 f"{report['open_loop_rmse_by_horizon'][horizon][n]:.2f}" for n in names]
        print(f"{horizon:26s}" + "".join(f"{cell:>28s}" for cell in cells))
    print(f"\nperiod of increased accuracy [min] (margin {report['margin_K']:g} K, "
          f"{report['smoothing_min']:g}-min trailing mean; >= : record ended first)")
    print(f"{'start [min]':26s}" + "".join(f"{name:>{width}s}" for name in names))
    censored = report["improved_minutes_censored"]
    for start, values in report["improved_minutes"].items():
        cells = [f"{'>=' if name in censored.get(start, []) else ''}{values[name]:.1f}" for name in names]
        print(f"{start:26s}" + "".join(f"{cell:>{width}s}" for cell in cells))
    sensor_nodes = set(result.model.spec.sensors.values())
    unmeasured = [(node, result.states[-1, j]) for j, node in enumerate(result.model.state_names)
                  if node not in sensor_nodes]
    print("\nestimated unmeasured temperatures at the end [°C]: "
          + ", ".join(f"{node} {value:.1f}" for node, value in unmeasured))
    if result.disturbance_names:
        print("estimated disturbances at the end [W; q_load_*: W at rated current, scaled by load²; "
              "q_coolant_*: W at 50 K above the coolant inlet; dT_inlet: K]: "
              + ", ".join(f"{name} {value:+.1f}" for name, value in zip(result.disturbance_names,
                                                                        result.disturbances[-1])))
