"""``genthermal diagnose DATA.csv [DATA2.csv ...] [--model NAME|FILE] [--baseline HEALTHY.csv ...] [--joint] [--json out.json]``:
which catalogue effect (or open-library term) the model lacks. Several baselines give one calibration
and one error model; several DATA records are each diagnosed against them, or with ``--joint`` one
effect is fitted over all of them at once. Reference: docs/guide/calibration-diagnosis.md."""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import InputError
from ..progress import say, working
from ._common import add_choice_argument, add_json_argument, add_out_argument, model_from_args
from ._vocabulary import PHASES
from ._common import DEFAULT_FIT_STEP_S, add_model_arguments, positive_float
from .compare import data_step, fitting_data

#: Fewest samples a diagnosed record (and its baseline) may have.
MIN_DIAGNOSIS_SAMPLES = 30


def register(subparsers) -> None:
    """Add the ``diagnose`` sub-command."""
    parser = subparsers.add_parser("diagnose", help="find the physical effect a model lacks",
                                   description="Fit every catalogue effect the model lacks (parameters and "
                                   "onset), rank by ΔBIC, and say which one explains the data, or 'none'.")
    add_model_arguments(parser)
    parser.add_argument("data", metavar="DATA", nargs="*",
                        help="measurements CSV to explain; several: each is diagnosed on its own against the same "
                        "baseline calibration and error model, and the effects named on every one are reported")
    parser.add_argument("--dt", help="resample the data to this period in s first (default: the data's own step); "
                        "for a logger file without a time column (read through a column map): its sample period")
    parser.add_argument("--columns", metavar="FILE", help="column map (YAML) of a logger's CSV (default: the "
                        "machine's own map, if it has one)")
    parser.add_argument("--fit-step", metavar="S", help="files read through a column map: average them to this "
                        f"step, s (default {DEFAULT_FIT_STEP_S:g} s)")
    parser.add_argument("--baseline", metavar="HEALTHY", nargs="+", action="extend",
                        help="healthy measurements: calibrate the uncertain parameters on them first and estimate "
                        "the model's error (the discrepancy floor) on them; several records: one calibration and "
                        "one error model over all, each record from its own initial state. It takes every file "
                        "after it: put DATA first, or end the list with --")
    add_json_argument(parser, "the diagnosis (ranked effects, verdict, residual, sensor faults)")
    parser.add_argument("--iterate", action="store_true", help="add the best effect and search again until "
                        "nothing is significant")
    parser.add_argument("--joint", action="store_true", help="several DATA records: fit each catalogue effect "
                        "over all of them at once (one set of its values from the start of every record, each "
                        "record from its measured initial state) and sum its evidence over the records: an "
                        "effect present in every profile. With --baseline: the baseline parameters calibrated "
                        "and the error model taken on the baselines first")
    parser.add_argument("--report", metavar="DIR", help="write report.md, diagnosis.json and plots into DIR")
    add_out_argument(parser, "model", "the model with the effects found")
    parser.add_argument("--workers", type=int, default=min(2, os.cpu_count() or 1),
                        help="processes fitting candidates side by side (default: up to 2 cores)")
    add_choice_argument(parser, "--phases", PHASES, default="auto",
                        help="fit one winding node per phase sensor: when they differ (auto), always, never")
    parser.add_argument("--no-open-search", action="store_true",
                        help="when the catalogue leaves the residual unexplained, do not search the open library "
                             "of heat flows and conductance changes")
    parser.set_defaults(func=run)


def _long_enough(data, step, option: str):
    """``data``, or InputError when it has fewer than :data:`MIN_DIAGNOSIS_SAMPLES` (on ``step``'s grid)."""
    time_s = data.time_s
    samples = time_s.size if step is None else int((time_s[-1] - time_s[0]) / step) + 1
    if samples < MIN_DIAGNOSIS_SAMPLES:
        raise InputError(option, data.source, f"{samples} sample(s): a diagnosis fits an effect's size and onset "
                         f"and needs at least {MIN_DIAGNOSIS_SAMPLES} samples (e.g. 5 min at 10 s)")
    return data


def read_records(model, args) -> tuple:
    """(DATA records, baseline records or None, the diagnosis' step ``dt_s``) of ``args``: through a
    column map (``--columns`` or the machine's own; ``--dt`` is then the file's sample period and
    the records are averaged to ``--fit-step``) or in the CSV schema; every file of the call must
    have the same columns."""
    from ..column_map import read_logged_set
    from ..diagnose.multi_record import decimated
    from ._records import _column_map

    if not args.data:
        raise InputError("DATA", "none", "no record to diagnose: --baseline takes every file after it; put DATA "
                         "first (diagnose DATA --baseline A B) or end the baselines with -- (--baseline A B -- DATA)")
    paths = list(args.data) + list(args.baseline or [])
    column_map = _column_map(args, model)
    interface, rated = model.spec.interface, model.spec.rated_current_A
    if column_map is not None:
        import numpy as np

        step = DEFAULT_FIT_STEP_S if args.fit_step is None else positive_float("--fit-step", args.fit_step)
        records = read_logged_set(paths, column_map, interface, data_step(args), rated)
        records = [decimated(r, step) if float(np.median(np.diff(r.time_s))) < step else r for r in records]
        dt_s = None
    else:
        records = [fitting_data(p, model, args) for p in paths]
        first = set(records[0].frame.columns)  # the baselines' sensors are checked by the diagnosis
        for path, record in zip(paths[1:len(args.data)], records[1:len(args.data)]):
            if set(record.frame.columns) != first:
                different = sorted(set(record.frame.columns) ^ first)[0]
                raise InputError(f"{path}: columns", different, "the records of one call must have the same columns")
        dt_s = data_step(args)
    data = [_long_enough(r, dt_s, "DATA") for r in records[:len(args.data)]]
    baselines = [_long_enough(r, dt_s, "--baseline") for r in records[len(args.data):]] or None
    return data, baselines, dt_s


def run(args) -> int:
    """Diagnose each DATA record and print the ranking and verdict."""
    from ..diagnose.discovery import Discovery
    from ..diagnose.fitter import OnsetFitter
    from ..outputs import report_json

    model = model_from_args(args)
    data, baselines, dt_s = read_records(model, args)
    if len(data) > 1:
        for option in ("report", "out"):
            if getattr(args, option):
                raise InputError(f"--{option}", getattr(args, option), "writes one diagnosis: give one DATA record")
    if args.joint:
        for option in ("report", "out", "iterate"):
            if getattr(args, option):
                raise InputError(f"--{option}", getattr(args, option), "not with --joint (one ranking over the records)")
        document = _diagnose_jointly(model, data, baselines, dt_s, args)
        if args.json:
            report_json(args.json, document)
        return 0
    discovery = Discovery(fitter=OnsetFitter(workers=args.workers), iterate=args.iterate, phases=args.phases,
                          progress=lambda line: say(f"  ... {line}"))
    documents = [_diagnose_one(discovery, model, record, baselines, dt_s, args) for record in data]
    if len(documents) > 1:
        named = [set(f["effect"] for f in d["found"]) for d in documents]
        common = sorted(set.intersection(*named))
        print(f"on {len(documents)} records: named on every one: {', '.join(common) or 'none'}; per record: "
              + "; ".join(f"{d['data']}: {', '.join(sorted(n)) or 'none'}" for d, n in zip(documents, named)))
        document = {"records": documents, "named_on_every_record": common}
    else:
        document = documents[0]
    if args.json:
        report_json(args.json, document)
    return 0


def _diagnose_jointly(model, data, baselines, dt_s, args) -> dict:
    """``--joint``: every applicable effect fitted over the DATA records at once
    (:func:`~genthermal.diagnose.over_records.diagnose_over_records`), printed; its JSON document."""
    import numpy as np

    from ..diagnose.baseline_set import calibrate_baselines
    from ..diagnose.catalogue import Catalogue
    from ..diagnose.discover import DEFAULT_BASELINE_PARAMETERS
    from ..diagnose.error_model import baseline_error_model
    from ..diagnose.multi_record import record_from_measurements
    from ..diagnose.over_records import diagnose_over_records

    if len(data) < 2:
        raise InputError("--joint", data[0].source, "fits one effect over several records: give two DATA files or more")
    # the fit's grid: --dt, else --fit-step (records read through a column map are on it already)
    step = dt_s if dt_s is not None else (DEFAULT_FIT_STEP_S if args.fit_step is None else
                                          positive_float("--fit-step", args.fit_step))
    error_model, calibration = None, None
    with working("diagnose over the records"):
        if baselines:
            names = [n for n in DEFAULT_BASELINE_PARAMETERS if n in model.parameters]
            if names:
                calibration = calibrate_baselines(model, baselines, names, step)
                model = calibration.model
            error_model = baseline_error_model(model, model, baselines, step, None, Catalogue.for_diagnosis())
            say(f"  ... {error_model.summary()}")
        records = [record_from_measurements(model, d, step if float(np.median(np.diff(d.time_s))) < step else None)
                   for d in data]  # a record already on the grid (read through a column map) is kept
        result = diagnose_over_records(model, records, error_model=error_model,
                                       progress=lambda line: say(f"  ... {line}"))
    document = {**result.to_dict(), "error_model": error_model.to_dict() if error_model else None,
                "baseline_calibration": calibration.to_dict() if calibration else None}
    print(f"{model.name} over {len(records)} records ({', '.join(r.name for r in records)}), "
          f"{document['criterion']}:")
    for entry in document["ranked"]:
        params = ", ".join(f"{k} = {v:.4g}" for k, v in entry["params"].items())
        print(f"  {entry['effect']:>32s}: {params:<34s} RMSE {entry['rmse_before']:.3f} -> {entry['rmse_after']:.3f} K"
              f"  ΔIC {entry['delta_ic']:9.1f}{'  *' if entry['significant'] else ''}"
              + (f"  (no finding: {entry['implausible']})" if entry["implausible"] else ""))
    alike = document["look_alikes"]
    print(f"verdict over the records: {document['verdict']}"
          + (f" (cannot be told from {', '.join(alike)} on these records)" if alike else ""))
    return document


def _diagnose_one(discovery, model, data, baselines, dt_s, args) -> dict:
    """Diagnose ``data``, print it (and write ``--report``, ``--out``); its JSON document."""
    from ..model_file import save_model
    from ..outputs import replacing_folder

    with working("diagnose"):
        result = discovery.fit(model, data, baseline=baselines, dt_s=dt_s)
    if result.unexplained and not args.no_open_search:
        from ..diagnose.open_followup import open_followup

        with working("open search"):
            say("  ... the catalogue leaves the residual unexplained: searching the open library of heat flows")
            result.open_search = open_followup(discovery, result, data, dt_s)
    document = result.to_dict()
    floor = document["residual"].get("floor_K")
    print(f"{model.name} on {document['data']}: noise ≈ {result.noise_std:.3f} K"
          + (f", discrepancy floor {floor:.3f} K (the calibrated model's error on the baseline)" if floor else ""))
    for c in document["ranked"]:
        params = ", ".join(f"{k} = {v:.4g}" for k, v in c["params"].items())
        print(f"  {c['effect']:>32s}: {params:<22s} onset {c['onset_s'] / 3600:5.2f} h  RMSE "
              f"{c['rmse_before']:.3f} -> {c['rmse_after']:.3f} K  ΔBIC {c['delta_ic']:9.1f}"
              f"{'  *' if c['significant'] else ''}")
    for p in document["pairs"][:3]:
        print(f"  {' + '.join(p['effects']):>66s}: RMSE {p['rmse_after']:.3f} K  ΔBIC {p['delta_ic']:9.1f}"
              f"{'  *' if p['significant'] else ''}")
    for k, iteration in enumerate(document["iterations"][1:], start=2):
        print(f"  round {k}: RMSE {iteration['rmse_before']:.3f} K, added {iteration['added'] or 'nothing'}")
    for fault in document["sensor_faults"]:
        print(f"  sensor fault: {fault['text']} (ΔBIC {fault['delta_ic']:.0f}, by {fault['evidence']})")
    for refused in document.get("refused_sensor_faults", []):
        print(f"  refused sensor fault: {refused['refused']}")
    print(f"verdict: {document['verdict']}" + (" (the nearest catalogue effect, not a confident verdict: it leaves "
                                               "the residual unexplained)" if document["nearest"] else ""))
    if document.get("open_search"):
        terms = document["open_search"]["terms"]
        lead = ("not explained by the catalogue" if not document["found"] else
                f"not explained by the catalogue: {' + '.join(f['effect'] for f in document['found'])} leaves the "
                "residual unexplained")
        on_top, in_place = document["open_search"]["on_top_of"], document["open_search"]["in_place_of"]
        print(f"{lead}; open search ({document['open_search']['library_size']} terms"
              + (f", in place of {in_place}" if in_place else "")
              + (f", on top of {' + '.join(on_top)}" if on_top else "") + "): "
              + ("; ".join(t["text"] for t in terms) if terms else "no term is significant either"))
        for term in terms:
            print(f"  to keep {term['term']} as an effect:\n" + "".join(f"    {line}\n" for line in
                                                                        term["code"].splitlines()))
    print(document["explanation"])
    print(document["residual"]["summary"])
    if args.report:
        from ..diagnose.report import write_diagnosis_report

        with replacing_folder(args.report) as folder:  # the report appears whole or not at all
            written = write_diagnosis_report(result, folder)
        print(f"wrote {Path(args.report) / written.name}")
    if args.out:
        print(f"wrote {save_model(result.improved_model(), args.out, {f.effect: f.onset_s for f in result.found})}")
    return document
