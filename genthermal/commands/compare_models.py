"""``genthermal compare-models TRAIN.csv VAL.csv``: the candidate design models on validation data
(thesis 5.4): nonlinear physics, linear physics and ARX (fitted on TRAIN)."""

from __future__ import annotations

from ..errors import InputError
from ._common import add_json_argument, add_model_arguments, model_from_args, positive_float


def register(subparsers) -> None:
    """Add the ``compare-models`` sub-command."""
    parser = subparsers.add_parser(
        "compare-models", help="compare the physics models and an ARX model on validation data (thesis 5.4)",
        description="Fit ARX models of the winding and iron temperatures to TRAIN, then simulate them and "
        "the nonlinear and linear physics models open loop on VAL; print R², RMSE and max error per sensor.")
    parser.add_argument("train", help="training data CSV (for the ARX models)")
    parser.add_argument("validation", help="validation data CSV (all models are scored on it)")
    add_json_argument(parser, "the table (R², RMSE and max error per model and sensor)")
    add_model_arguments(parser, what="the nonlinear physics model (its linear design model is derived from it)")
    parser.add_argument("--dt", default="10", help="sample time in s the data are resampled to (default 10)")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Compare the models, print the table and write the JSON."""
    from ..estimation.comparison import compare_design_models
    from ..measurements import load_measurements
    from ..outputs import report_json

    dt = positive_float("--dt", args.dt)
    train, validation = load_measurements(args.train), load_measurements(args.validation)
    plant = model_from_args(args)
    if plant.is_affine:
        raise InputError("--model", args.model, "give a nonlinear model; its linear design model is compared with it")
    table = compare_design_models(train, validation, plant=plant, dt_s=dt)
    print(f"design models on {args.validation} (ARX fitted on {args.train}), open loop:")
    print(table.to_string(index=False, float_format=lambda v: f"{v:.4f}"))
    if args.json:
        report_json(args.json, {"train": str(args.train), "validation": str(args.validation), "dt_s": dt,
                                "models": table.to_dict(orient="records")})
    return 0
