"""``genthermal compare DATA.csv [--model NAME|FILE] [--report DIR] [--json FILE] [--dt S]``."""

from __future__ import annotations

from pathlib import Path

from ._common import add_json_argument, add_model_arguments, add_record_set_arguments, model_from_args, positive_float


def add_model_and_data_arguments(parser, several: bool = False, fitting: bool = False) -> None:
    """``--model`` (built-in name or model file), ``DATA`` (CSV; several with ``several``, and then
    ``--columns`` and ``--fit-step`` too, and with ``fitting`` ``--weight`` and ``--prior-weight``) and ``--dt``."""
    add_model_arguments(parser)
    parser.add_argument("data", metavar="DATA", nargs="+" if several else None,
                        help="measurements CSV (time_s, I_u, I_v, I_w, I_exc, T_inlet, T_ambient, T_winding_u, "
                        "T_winding_v, T_winding_w, T_iron)" + ("; several records: each is simulated from its "
                                                              "own measured initial state" if several else ""))
    parser.add_argument("--dt", help="resample the data to this period in s first (default: the data's own step); "
                        "for a logger file without a time column (read through a column map): its sample period")
    if several:
        add_record_set_arguments(parser, fitting)


def data_step(args) -> float | None:
    """The ``--dt`` option as seconds, or None."""
    return None if args.dt is None else positive_float("--dt", args.dt)


def fitting_data(path: str, model, args):
    """Measurements of ``path`` in ``model``'s CSV schema checked against its rating, block-averaged
    when long and no ``--dt`` was given (:mod:`genthermal.long_records`; the note is printed)."""
    from ..long_records import decimate_for_fitting
    from ..measurements import load_measurements

    data = load_measurements(path, rated_current_A=model.spec.rated_current_A, interface=model.spec.interface)
    if args.dt is not None:
        return data
    data, note = decimate_for_fitting(data)
    if note:
        print(f"note: {note}")
    return data


def register(subparsers) -> None:
    """Add the ``compare`` sub-command."""
    parser = subparsers.add_parser("compare", help="compare a model with measurements",
                                   description="Simulate the model (--model) on the measured inputs of DATA from the measured "
                                   "initial temperatures; report RMSE, MAE, max error, bias and R² per sensor, "
                                   "split by load band, temperature band, heating/cooling and hour, with plots.")
    add_model_and_data_arguments(parser, several=True)
    parser.add_argument("--report", metavar="DIR", help="write report.md, metrics.json and plots into DIR")
    add_json_argument(parser, "the metrics (per sensor and band; per record and pooled for several records)")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Compare and print the per-sensor metrics."""
    from ..diagnose.compare import compare
    from ..outputs import replacing_folder, report_json

    from ._records import compare_record_set, uses_record_set

    model = model_from_args(args)
    if uses_record_set(args, model):
        return compare_record_set(model, args)
    args.data = args.data[0]
    comparison = compare(model, args.data, data_step(args))
    print(f"{model.name} on {comparison.source}: {comparison.metrics['samples']} samples")
    total = comparison.metrics["samples"]
    for name, m in comparison.metrics["overall"].items():
        if m["n"] == 0:
            print(f"  {name}: no sample with both a measurement and a finite model value; no metrics")
            continue
        r2 = "n/a" if m["r2"] is None else f"{m['r2']:.4f}"
        counted = "" if m["n"] == total else f" (on the {m['n']} of {total} samples measured)"
        print(f"  {name}: RMSE {m['rmse']:.3f} K, MAE {m['mae']:.3f} K, max {m['max_abs']:.3f} K, "
              f"bias {m['bias']:+.3f} K, R² {r2}, trend {comparison.metrics['trend_K_per_h'][name]:+.3f} K/h"
              f"{counted}")
    if args.json:
        report_json(args.json, comparison.metrics)
    if args.report:
        from ..diagnose.report import write_compare_report

        with replacing_folder(args.report) as folder:  # the report appears whole or not at all
            written = write_compare_report(comparison, folder)
        print(f"wrote {Path(args.report) / written.name}")
    return 0
