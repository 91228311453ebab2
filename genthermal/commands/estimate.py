"""``genthermal estimate DATA.csv [--model NAME|FILE] [--filter ekf|kf] [--json out.json]``: filter and
n-step prediction study (thesis 6.3) on rig data, against the open-loop model; with ``--sensors``
(or several records, or a logger's column map) every node from a subset of the sensors (``_observe``).

Reference: docs/guide/estimation.md and docs/guide/cli.md.
"""

from __future__ import annotations

import math
from pathlib import Path

from ..errors import InputError
from ._common import (add_choice_argument, add_json_argument, add_model_arguments, add_record_set_arguments,
                      model_from_args, positive_float)
from ._vocabulary import (DEFAULT_EVERY_MIN, DEFAULT_MARGIN_K, DEFAULT_OFFSET_STEP_K, DEFAULT_PROCESS_STD_K, FILTERS,
                          THESIS_STARTS_MIN)

#: Step of the filters with disturbance states when --dt is not given, s.
DEFAULT_FILTER_STEP_S = 10.0


def register(subparsers) -> None:
    """Add the ``estimate`` sub-command."""
    parser = subparsers.add_parser(
        "estimate", help="Kalman filter and n-step prediction on rig data (thesis 6.3)",
        description="Filter the measured winding and iron temperatures with the model (an extended "
        "Kalman filter with disturbance heat flows, or the thesis's linear filter on the design model), "
        "run the model open loop, predict from a start every 10 min, and report the prediction error "
        "at 15, 30 and 60 min against the open-loop model, the one-step error, and how long each "
        "prediction from --predict-from beats the open-loop model. With --sensors (or several records, or a "
        "logger's file read through a column map): an extended Kalman filter of every node from the sensors "
        "named, each read with an offset state, scored on every sensor the records hold.")
    parser.add_argument("data", metavar="DATA", nargs="+", help="rig data CSV (genthermal.measurements schema, or a "
                        "logger's file read through a column map); several: with the node observer (--sensors), each "
                        "filtered on its own")
    add_model_arguments(parser)
    add_choice_argument(parser, "--filter", FILTERS, default="ekf",
                        help="ekf: extended Kalman filter on the model with disturbance heat flows (default); "
                        "kf: the thesis's linear filter on the model's linear design model")
    parser.add_argument("--every", default=str(DEFAULT_EVERY_MIN), metavar="MIN",
                        help=f"interval between the starts of the error-by-horizon table, min (default "
                        f"{DEFAULT_EVERY_MIN:g})")
    add_json_argument(parser, "the errors and periods of increased accuracy")
    parser.add_argument("--predict-from", metavar="MIN,...",
                        help="prediction start times, min after the first sample (default "
                        f"{','.join(str(s) for s in THESIS_STARTS_MIN)})")
    parser.add_argument("--dt", help=f"filter step in s; data on another grid are resampled to it (default "
                        f"{DEFAULT_FILTER_STEP_S:g}); with the node observer: the sample period of a logger's file "
                        "without a time column, as in compare (the filter steps at --fit-step)")
    parser.add_argument("--sensors", metavar="NAMES", help="node observer: the sensors the filter reads, "
                        "comma-separated, e.g. T_end_winding,T_outer_yoke (default every sensor); every node is "
                        "estimated, and every sensor the records hold is scored")
    parser.add_argument("--offset-step", action="append", default=[], metavar="[SENSOR=]K",
                        help="node observer: random-walk step of the offset state of each sensor read, K per filter "
                        f"step (default {DEFAULT_OFFSET_STEP_K:g}): K for every sensor, SENSOR=K for one, e.g. "
                        "--offset-step 0.3 --offset-step T_end_winding=0.02; repeatable. A large step lets the "
                        "offset take up the model's error at that sensor; a small one makes the reading correct "
                        "the nodes")
    parser.add_argument("--process-std", metavar="K", help="node observer: process noise of a node with a sensor, "
                        f"K per filter step (default {DEFAULT_PROCESS_STD_K:g}; nodes without one take 1 %% of it)")
    add_record_set_arguments(parser)
    parser.add_argument("--plot", metavar="FILE.png", help="prediction plot (thesis Figs 6.8-6.10); the filter "
                        "plot goes next to it as <name>_filter.png, the predictions against the measured winding "
                        "and the error by horizon as <name>_horizons.png")
    parser.add_argument("--steady-state", action="store_true",
                        help="use the converged (steady-state) gain (--filter kf only)")
    parser.add_argument("--estimate-noise", action="store_true",
                        help="estimate R from the data (thesis 6.2.2) instead of using eq. 6.10")
    parser.add_argument("--min-improvement", metavar="K",
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


def uses_node_observer(args, model) -> bool:
    """True when the call names the node observer's options, several records or a column map."""
    from ._records import uses_record_set

    return (args.sensors is not None or bool(args.offset_step) or args.process_std is not None
            or uses_record_set(args, model))


def run(args) -> int:
    """Run the node observer (:mod:`._observe`) or the filter with disturbance states and its
    prediction study; print a summary and write the JSON (and plots)."""
    model = model_from_args(args)
    if uses_node_observer(args, model):
        from ._observe import estimate_nodes

        return estimate_nodes(model, args)
    if args.fit_step is not None:
        raise InputError("--fit-step", args.fit_step, "the filter with disturbance states steps at --dt; --fit-step "
                         "is the node observer's (--sensors)")
    args.data = args.data[0]
    return prediction_run(model, args)


def prediction_run(model, args) -> int:
    """The filter with disturbance states (``--filter``) and the prediction study on one record."""
    from ..design import linear_design_model
    from ..estimation.ekf import ExtendedKalmanFilter
    from ..estimation.kalman import KalmanFilter
    from ..estimation.prediction import (DEFAULT_HORIZONS_MIN, DEFAULT_SMOOTHING_MIN, check_sensors, check_start_times,
                                         horizon_starts, on_grid, prediction_study)
    from ..measurements import load_measurements
    from ..outputs import report_json

    dt = DEFAULT_FILTER_STEP_S if args.dt is None else positive_float("--dt", args.dt)
    starts = parse_starts(",".join(str(s) for s in THESIS_STARTS_MIN) if args.predict_from is None
                          else args.predict_from)
    margin_text = str(DEFAULT_MARGIN_K) if args.min_improvement is None else args.min_improvement
    try:
        margin = float(margin_text)
    except ValueError:
        raise InputError("--min-improvement", margin_text, "must be a number of kelvin >= 0") from None
    if not (math.isfinite(margin) and margin >= 0):
        raise InputError("--min-improvement", margin_text, "must be a number of kelvin >= 0")
    every = positive_float("--every", args.every)
    if args.steady_state and args.filter != "kf":
        raise InputError("--steady-state", True, "only the linear filter has a steady-state gain; add --filter kf")
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
