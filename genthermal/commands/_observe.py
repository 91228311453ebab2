"""``estimate --sensors``: every node of the model from a chosen subset of its sensors.

The filter is :class:`~genthermal.estimation.node_observer.NodeObserver`: each sensor it reads
has an offset state with a random-walk step (``--offset-step``). Records are read as ``compare``
reads them (several at once, a logger's column map, ``--fit-step`` blocks). The report gives each
output's error filtered and open loop (from the measured initial state), per record and pooled,
and the error of predictions from the filtered state by horizon. Reference: docs/guide/cli.md.
"""

from __future__ import annotations

import difflib

import numpy as np

from ..errors import InputError
from ..outputs import report_json
from ..progress import working
from ._common import non_negative_float, positive_float

#: Options of the disturbance-state filters (``--filter``) that the node observer does not take.
FILTER_ONLY_OPTIONS = {"predict_from": "--predict-from", "min_improvement": "--min-improvement",
                       "plot": "--plot", "steady_state": "--steady-state", "estimate_noise": "--estimate-noise"}


def sensors_read(text: str | None, model) -> list[str]:
    """The outputs named by ``--sensors`` (comma-separated; None: every sensor)."""
    if text is None:
        return list(model.output_names)
    names = [n.strip() for n in str(text).split(",") if n.strip()]
    for name in names:
        if name not in model.output_names:
            close = difflib.get_close_matches(name, model.output_names, n=3)
            hint = f"did you mean {', '.join(close)}? " if close else ""
            raise InputError("--sensors", name, f"not a sensor of {model.name}; {hint}its sensors: "
                             f"{', '.join(model.output_names)}")
    if len(set(names)) != len(names):
        raise InputError("--sensors", text, "a sensor is named twice")
    return names


def offset_steps(items: list[str], model, read: list[str]) -> tuple[dict[str, float], float]:
    """Per-sensor offset steps and the default step, K per filter step, from ``--offset-step`` items
    (``K`` for every sensor read, ``SENSOR=K`` for one; a later item naming a sensor again wins)."""
    from ..estimation.node_observer import DEFAULT_OFFSET_STEP_K

    defaults = [item for item in items if "=" not in item]
    if len(defaults) > 1:
        raise InputError("--offset-step", defaults[1], f"one step for every sensor is given already "
                         f"({defaults[0]}); name the others as SENSOR=K")
    default = non_negative_float("--offset-step", defaults[0]) if defaults else DEFAULT_OFFSET_STEP_K
    steps = {}
    for item in items:
        name, sep, text = item.partition("=")
        if not sep:
            continue
        name = name.strip()
        if name not in read:
            where = "not a sensor the filter reads (--sensors)" if name in model.output_names else \
                f"not a sensor of {model.name}"
            raise InputError(f"--offset-step {name}", name, f"{where}; it reads {', '.join(read)}")
        steps[name] = non_negative_float(f"--offset-step {name}", text)
    return steps, default


def check_options(args) -> None:
    """Refuse the options of the disturbance-state filters, which the node observer does not take."""
    if args.filter != "ekf":
        raise InputError("--filter", args.filter, "--sensors runs its own extended Kalman filter of every node; "
                         "the linear filter reads every sensor (leave out --sensors, --offset-step, --process-std)")
    for attribute, option in FILTER_ONLY_OPTIONS.items():
        if getattr(args, attribute):
            raise InputError(option, getattr(args, attribute), "an option of the filter with disturbance states; "
                             "the node observer (--sensors, --offset-step, --process-std, several records or "
                             "a column map) does not take it")


def estimate_nodes(model, args) -> int:
    """Filter each record with the node observer; print and write (``--json``) the errors."""
    from ..diagnose.multi_record import simulate_record
    from ..estimation.node_observer import DEFAULT_PROCESS_STD_K, NodeObserver
    from ..estimation.prediction import DEFAULT_HORIZONS_MIN

    from ._records import error_metrics, load_record_set

    check_options(args)
    read = sensors_read(args.sensors, model)
    steps, default = offset_steps(args.offset_step, model, read)
    process = DEFAULT_PROCESS_STD_K if args.process_std is None else non_negative_float("--process-std",
                                                                                         args.process_std)
    every_min = positive_float("--every", args.every)
    horizons_s = [60.0 * h for h in DEFAULT_HORIZONS_MIN]
    records = load_record_set(args, model)
    names = list(model.output_names)
    observers, filtered, open_loop = {}, {}, {}
    ahead = {h: {n: [] for n in names} for h in horizons_s}
    with working("estimate"):
        for record in records:
            if record.dt_s not in observers:
                observers[record.dt_s] = NodeObserver(model, record.dt_s, read, process_std_K=process,
                                                      bias_std_K=steps, default_bias_std_K=default)
            observer = observers[record.dt_s]
            states, outputs = observer.run(record)
            filtered[record.name] = outputs - record.outputs
            open_loop[record.name] = simulate_record(model, record) - record.outputs
            for name, by_h in observer.horizon_errors(record, states, horizons_s, names, 60.0 * every_min).items():
                for h, errors in by_h.items():
                    ahead[h][name].append(errors)
    report = {"model": model.name, "records": [r.name for r in records], "dt_s": records[0].dt_s,
              "sensors_read": read, "offset_step_K": {n: steps.get(n, default) for n in read},
              "process_std_K": process, "prediction_starts_every_min": every_min,
              "filter": _scores(names, filtered), "open_loop": _scores(names, open_loop),
              "prediction_by_horizon": {f"{h / 60.0:g} min": {n: error_metrics(np.concatenate(parts))
                                                                for n, parts in by_name.items()}
                                        for h, by_name in ahead.items()}}
    _print(report, names)
    if args.json:
        report_json(args.json, report)
    return 0


def _scores(names, errors: dict) -> dict:
    """Per record and pooled metrics of each output from {record: (n_outputs, N) errors}."""
    from ._records import error_metrics

    pooled = np.hstack(list(errors.values()))
    return {"records": {r: {n: error_metrics(e[i]) for i, n in enumerate(names)} for r, e in errors.items()},
            "pooled": {n: error_metrics(pooled[i]) for i, n in enumerate(names)}}


def _cell(m) -> str:
    return "-" if m["rmse"] is None else f"{m['rmse']:.2f}/{m['max_abs']:.1f}"


def _print(report: dict, names: list[str]) -> None:
    steps = ", ".join(f"{n} {s:g}" for n, s in report["offset_step_K"].items())
    print(f"{report['model']} on {len(report['records'])} record(s) ({report['dt_s']:g} s steps): every node "
          f"estimated from {', '.join(report['sensors_read']) or 'no sensor (open loop)'}; offset steps, K per step: "
          f"{steps or '-'}; process noise {report['process_std_K']:g} K per step; the filter starts as in service "
          f"(unread nodes from the mean of the first readings), the open loop from the measured initial state")
    horizons = list(report["prediction_by_horizon"])
    print(f"  RMSE / max |error|, K, pooled {'':14s}{'filtered':>14s}{'open loop':>14s}"
          + "".join(f"{h + ' ahead':>16s}" for h in horizons))
    for name in names:
        role = "read" if name in report["sensors_read"] else "estimated"
        cells = [_cell(report["filter"]["pooled"][name]), _cell(report["open_loop"]["pooled"][name])]
        cells += [_cell(report["prediction_by_horizon"][h][name]) for h in horizons]
        print(f"  {name:>20s} {'(' + role + ')':12s}  " + "".join(f"{c:>14s}" for c in cells[:2])
              + "".join(f"{c:>16s}" for c in cells[2:]))
    print(f"  predictions start every {report['prediction_starts_every_min']:g} min from the filtered state, "
          "with the measured inputs")
