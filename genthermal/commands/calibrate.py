"""``genthermal calibrate DATA.csv [--model NAME|FILE] --params k_cr,h_end_air --out model.yaml``: a
least-squares fit with confidence intervals. Reference: docs/guide/calibration-diagnosis.md."""

from __future__ import annotations

from ..progress import working
from ._common import add_json_argument, add_out_argument, model_from_args
from .compare import add_model_and_data_arguments, data_step, fitting_data


def register(subparsers) -> None:
    """Add the ``calibrate`` sub-command."""
    parser = subparsers.add_parser("calibrate", help="fit model parameters to measurements",
                                   description="Least-squares fit of the named parameters (IPOPT, exact "
                                   "derivatives, bounds from the parameters' physical ranges) with 95 % "
                                   "confidence intervals and identifiability warnings.")
    add_model_and_data_arguments(parser, several=True, fitting=True)
    parser.add_argument("--params", required=True, metavar="NAMES",
                        help="comma-separated parameter names, e.g. k_cr,h_end_air,R0, or 'assumed': every "
                        "parameter whose provenance is assumed")
    add_out_argument(parser, "model", "the calibrated model")
    add_json_argument(parser, "the fit summary (values, confidence intervals, RMSE before and after, warnings)")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Calibrate, print the table and warnings, write the model file."""
    from ..diagnose.calibrate import calibrate, check_parameter_names
    from ..model_file import save_model
    from ..outputs import report_json

    from ._records import calibrate_record_set, uses_record_set

    model = model_from_args(args)
    if args.params.strip() == "assumed":  # every parameter whose value was assumed
        args.params = ",".join(n for n in model.parameter_names if model.parameters[n].provenance == "assumed")
    names = check_parameter_names(model, args.params.split(","), "--params")
    if uses_record_set(args, model) or args.weight or args.prior_weight:  # the single-record fit has neither
        return calibrate_record_set(model, names, args)
    args.data = args.data[0]
    data = fitting_data(args.data, model, args)
    with working("calibrate"):
        result = calibrate(model, data, names, data_step(args))
    summary = result.to_dict()
    print(f"{model.name}: {len(names)} parameter(s) fitted to {args.data} "
          f"({result.status})")
    for row in summary["parameters"]:
        low, high = row["ci95"]
        print(f"  {row['name']:>14s} = {row['value']:.6g} {row['unit']}  (start {row['start']:.6g}; "
              f"95 % CI {low:.6g} .. {high:.6g})")
    print(f"  RMSE {summary['rmse_before']:.3f} K -> {summary['rmse_after']:.3f} K; "
          f"condition number {summary['condition_number']:.3g}")
    for warning in result.warnings:
        print(f"  warning: {warning}")
    if args.out:
        model_out = result.model
        if result.model.spec.variant == "nonlinear":
            from ..estimation.disturbance_prior import learn_disturbance_prior

            from ..measurements import load_measurements

            record = load_measurements(args.data, rated_current_A=model.spec.rated_current_A,
                                       interface=model.spec.interface)  # every sample, not the fitting blocks
            with working("disturbance prior"):
                prior = learn_disturbance_prior(result.model, record)
            model_out = result.model.with_disturbance_prior(prior)
            print("  disturbance prior (what an EKF on the calibrated model starts from, W; dT_inlet K): "
                  + ", ".join(f"{n} {m:.1f}" for n, m in zip(prior.names, prior.mean)))
        print(f"wrote {save_model(model_out, args.out)}")
    if args.json:
        report_json(args.json, summary)
    return 0
