"""Several records in one ``compare`` or ``calibrate`` call, read as CSV schema or through a column map.

Each record is simulated from its own measured initial state
(:mod:`genthermal.diagnose.multi_record`); metrics are given per record, pooled, and by speed band,
load-current band and sensor.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError
from ..outputs import report_json
from ..progress import working
from ._common import DEFAULT_FIT_STEP_S

#: Speed bands of the comparison, rpm (upper edges; the last is open).
SPEED_BANDS_RPM = (100.0, 1000.0, 2000.0, 3000.0)
#: Load-current bands, as a share of the machine's rated current (upper edges; the last is open).
CURRENT_BANDS = (0.1, 0.4, 0.8)


def _machine(model):
    from ..machines import resolve_machine

    try:
        return resolve_machine(model.spec.machine_source or model.name)
    except InputError:
        return None


def _column_map(args, model):
    from ..column_map import ColumnMap

    if getattr(args, "columns", None):
        return ColumnMap.from_yaml(args.columns, model.spec.interface)
    machine = _machine(model)
    if machine is not None and machine.column_map is not None:
        return ColumnMap.from_dict(machine.column_map, model.spec.interface, f"column map of {machine.name}")
    return None


def uses_record_set(args, model) -> bool:
    """True when the call reads several records or goes through a column map."""
    return len(args.data) > 1 or _column_map(args, model) is not None


def load_record_set(args, model) -> list:
    """The records of ``args.data`` as :class:`~genthermal.diagnose.multi_record.Record` objects."""
    from ..column_map import read_logged_set
    from ..diagnose.multi_record import record_from_measurements
    from ..measurements import load_measurements
    from ._common import positive_float

    column_map = _column_map(args, model)
    dt = None if args.dt is None else positive_float("--dt", args.dt)
    step = DEFAULT_FIT_STEP_S if args.fit_step is None else positive_float("--fit-step", args.fit_step)
    if column_map is not None:
        data = read_logged_set(args.data, column_map, model.spec.interface, dt, model.spec.rated_current_A)
    else:
        if dt is not None:
            raise InputError("--dt", args.dt, "records in the CSV schema have a time column and keep their own step "
                             "here; --fit-step sets the step they are averaged to")
        data = [load_measurements(p, rated_current_A=model.spec.rated_current_A, interface=model.spec.interface)
                for p in args.data]
        first = set(data[0].frame.columns)
        for path, record in zip(args.data[1:], data[1:]):
            if set(record.frame.columns) != first:
                different = sorted(set(record.frame.columns) ^ first)[0]
                raise InputError(f"{path}: columns", different, "the records of one call must have the same columns")
    records = []
    for record in data:
        own = float(np.median(np.diff(record.time_s)))
        records.append(record_from_measurements(model, record, step if own < step else None))
    return records


def _bands(model, record) -> dict:
    from ..machines.interface import InputKind

    interface = model.spec.interface
    labels = {}
    speeds = interface.inputs_of_kind(InputKind.SPEED)
    if speeds:
        n = record.inputs[model.input_names.index(speeds[0])]
        edges = (0.0, *SPEED_BANDS_RPM, np.inf)
        labels["speed"] = [f"{lo:g}-{hi:g} rpm" for lo, hi in zip(edges[:-1], edges[1:])], np.digitize(n, SPEED_BANDS_RPM)
    currents = interface.inputs_of_kind(InputKind.CURRENT)
    if currents:
        amplitude = np.sqrt(sum(record.inputs[model.input_names.index(c)] ** 2 for c in currents))
        share = amplitude / interface.rated_current_A
        edges = (0.0, *CURRENT_BANDS, np.inf)
        labels["current"] = ([f"{lo:g}-{hi:g} x rated" for lo, hi in zip(edges[:-1], edges[1:])],
                             np.digitize(share, CURRENT_BANDS))
    return labels


def score_records(model, records) -> dict:
    """Per record and pooled RMSE / max |error| of every output, and pooled by band."""
    from ..diagnose.multi_record import simulate_record

    per_record, errors, band_errors = {}, [], {}
    for record in records:
        predicted = simulate_record(model, record)
        error = predicted - record.outputs
        errors.append(error)
        per_record[record.name] = {name: error_metrics(error[i]) for i, name in enumerate(model.output_names)}
        for band, (names, index) in _bands(model, record).items():
            for b, label in enumerate(names):
                chosen = error[:, index == b]
                band_errors.setdefault(band, {}).setdefault(label, []).append(chosen)
    pooled = np.hstack(errors)
    by_band = {band: {label: {name: error_metrics(np.hstack(parts)[i]) for i, name in enumerate(model.output_names)}
                      for label, parts in labels.items() if np.hstack(parts).shape[1]}
               for band, labels in band_errors.items()}
    return {"records": per_record, "pooled": {name: error_metrics(pooled[i]) for i, name in enumerate(model.output_names)},
            "by_band": by_band}


def error_metrics(error) -> dict:
    valid = np.isfinite(error)
    if not valid.any():
        return {"n": 0, "rmse": None, "max_abs": None, "bias": None}
    e = error[valid]
    return {"n": int(e.size), "rmse": float(np.sqrt(np.mean(e ** 2))), "max_abs": float(np.max(np.abs(e))),
            "bias": float(np.mean(e))}


def _print_scores(model, scores) -> None:
    names = list(model.output_names)
    print("  RMSE / max |error|, K       " + "".join(f"{n[2:]:>16s}" for n in names))
    rows = [(name.rsplit("/", 1)[-1], m) for name, m in scores["records"].items()] + [("all records", scores["pooled"])]
    for label, metrics in rows:
        print(f"  {label[:28]:28s}" + "".join(f"{_cell(metrics[n]):>16s}" for n in names))
    for band, labels in scores["by_band"].items():
        print(f"  by {band} band:")
        for label, metrics in labels.items():
            print(f"    {label[:26]:26s}" + "".join(f"{_cell(metrics[n]):>16s}" for n in names))


def _cell(m) -> str:
    return "-" if m["rmse"] is None else f"{m['rmse']:.2f}/{m['max_abs']:.1f}"


def compare_record_set(model, args) -> int:
    """``compare`` over several records (or one read through a column map)."""
    if getattr(args, "report", None):
        raise InputError("--report", args.report, "reports are written for one record in the CSV schema; use "
                         "--json for several records")
    records = load_record_set(args, model)
    with working("compare"):
        scores = score_records(model, records)
    print(f"{model.name} on {len(records)} record(s), each from its own measured initial state "
          f"({records[0].dt_s:g} s steps):")
    _print_scores(model, scores)
    if args.json:
        report_json(args.json, scores)
    return 0


def calibrate_record_set(model, names, args) -> int:
    """``calibrate`` over several records: one parameter set, per-record initial states."""
    from ..diagnose.multi_record import fit_records
    from ..model_file import save_model

    from ._common import parse_assignments
    from ._prior import prior_weights

    weights = parse_assignments(args.weight, "--weight")
    for name, value in weights.items():
        if name not in model.output_names:
            raise InputError(f"--weight {name}", name, f"not a sensor of {model.name} ({', '.join(model.output_names)})")
        if not (np.isfinite(value) and value >= 0):
            raise InputError(f"--weight {name}", value, "a weight must be a number >= 0")
    prior = prior_weights(args.prior_weight, model, names)
    records = load_record_set(args, model)
    before = score_records(model, records)
    with working("calibrate"):
        fit = fit_records(model, records, names, output_weights=[weights.get(n, 1.0) for n in model.output_names],
                          prior_weight=prior)
    fisher = fit.fisher
    after = score_records(fit.model, records)
    print(f"{model.name}: {len(names)} parameter(s) fitted to {len(records)} record(s) in {fit.fit_time_s:.0f} s "
          f"({'converged' if fit.converged else 'NOT converged'}); RMSE {_pooled_rmse(before):.3f} K -> "
          f"{fit.rmse:.3f} K over every sensor")
    for i, name in enumerate(names):
        low, high = fisher["ci95"][i]
        unit = model.parameters[name].unit
        held = f"; prior weight {prior[name]:g}" if prior[name] else ""
        print(f"  {name:>20s} = {fit.values[i]:.6g} {unit}  (start {fit.start[i]:.6g}; 95 % CI {low:.6g} .. {high:.6g}"
              f"{held})")
    for warning in fisher["warnings"]:
        print(f"  warning: {warning}")
    _print_scores(fit.model, after)
    if args.out:
        print(f"wrote {save_model(fit.model, args.out)}")
    if args.json:
        report_json(args.json, {"model": model.name, "records": [r.name for r in records], "converged": fit.converged,
                                "fit_time_s": fit.fit_time_s, "rmse_after_K": fit.rmse,
                                "parameters": [{"name": n, "unit": model.parameters[n].unit, "start": float(fit.start[i]),
                                                "value": float(fit.values[i]), "std": fisher["std"][i],
                                                "ci95": list(fisher["ci95"][i]), "prior_weight": prior[n]}
                                               for i, n in enumerate(names)],
                                "condition_number": fisher["condition_number"], "warnings": fisher["warnings"],
                                "before": before, "after": after})
    return 0


def _pooled_rmse(scores) -> float:
    values = [(m["rmse"] ** 2, m["n"]) for m in scores["pooled"].values() if m["n"]]
    return float(np.sqrt(sum(v * n for v, n in values) / sum(n for _, n in values)))
