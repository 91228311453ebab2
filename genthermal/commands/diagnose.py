"""``genthermal diagnose DATA.csv [--model NAME|FILE] [--baseline HEALTHY.csv] [--json out.json]``: which
catalogue effect (or open-library term) the model lacks. Reference: docs/guide/calibration-diagnosis.md."""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import InputError
from ..progress import say, working
from ._common import add_choice_argument, add_json_argument, add_out_argument, model_from_args
from ._vocabulary import PHASES
from .compare import add_model_and_data_arguments, data_step, fitting_data

#: Fewest samples a diagnosed record (and its baseline) may have.
MIN_DIAGNOSIS_SAMPLES = 30


def register(subparsers) -> None:
    """Add the ``diagnose`` sub-command."""
    parser = subparsers.add_parser("diagnose", help="find the physical effect a model lacks",
                                   description="Fit every catalogue effect the model lacks (parameters and "
                                   "onset), rank by ΔBIC, and say which one explains the data, or 'none'.")
    add_model_and_data_arguments(parser)
    parser.add_argument("--baseline", metavar="HEALTHY", help="healthy measurements: calibrate the uncertain "
                        "parameters on them first")
    add_json_argument(parser, "the diagnosis (ranked effects, verdict, residual, sensor faults)")
    parser.add_argument("--iterate", action="store_true", help="add the best effect and search again until "
                        "nothing is significant")
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


def _long_enough(data, args, option: str):
    """``data``, or InputError when it has fewer than :data:`MIN_DIAGNOSIS_SAMPLES` (on ``--dt``'s grid)."""
    time_s, step = data.time_s, data_step(args)
    samples = time_s.size if step is None else int((time_s[-1] - time_s[0]) / step) + 1
    if samples < MIN_DIAGNOSIS_SAMPLES:
        raise InputError(option, data.source, f"{samples} sample(s): a diagnosis fits an effect's size and onset "
                         f"and needs at least {MIN_DIAGNOSIS_SAMPLES} samples (e.g. 5 min at 10 s)")
    return data


def run(args) -> int:
    """Diagnose and print the ranking and verdict."""
    from ..diagnose.discovery import Discovery
    from ..diagnose.fitter import OnsetFitter
    from ..model_file import save_model
    from ..outputs import replacing_folder, report_json

    model = model_from_args(args)
    data = _long_enough(fitting_data(args.data, model, args), args, "DATA")
    baseline = None if args.baseline is None else _long_enough(fitting_data(args.baseline, model, args), args,
                                                                "--baseline")
    with working("diagnose"):
        discovery = Discovery(fitter=OnsetFitter(workers=args.workers), iterate=args.iterate, phases=args.phases,
                              progress=lambda line: say(f"  ... {line}"))
        result = discovery.fit(model, data, baseline=baseline, dt_s=data_step(args))
    if result.unexplained and not args.no_open_search:
        from ..diagnose.open_followup import open_followup

        with working("open search"):
            say("  ... the catalogue leaves the residual unexplained: searching the open library of heat flows")
            result.open_search = open_followup(discovery, result, data, data_step(args))
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
    if args.json:
        report_json(args.json, document)
    if args.report:
        from ..diagnose.report import write_diagnosis_report

        with replacing_folder(args.report) as folder:  # the report appears whole or not at all
            written = write_diagnosis_report(result, folder)
        print(f"wrote {Path(args.report) / written.name}")
    if args.out:
        print(f"wrote {save_model(result.improved_model(), args.out, {f.effect: f.onset_s for f in result.found})}")
    return 0
