"""``genthermal sysid TRAIN.csv VAL.csv [--json out.json]``: ARX models of the winding and iron
temperatures from rig data (thesis 5.3: structure search, selection, validation on a second record,
the two models stacked into one state space).

Reference: docs/guide/estimation.md and docs/guide/cli.md.
"""

from __future__ import annotations

from ..errors import InputError
from ._common import add_choice_argument, add_json_argument, non_negative_float, positive_float
from ._vocabulary import ARX_INPUTS

#: Largest order or delay accepted on the command line (the search grows as the product of ranges).
MAX_STRUCTURE_VALUE = 20
TABLE_ROWS = 10


def register(subparsers) -> None:
    """Add the ``sysid`` sub-command."""
    parser = subparsers.add_parser(
        "sysid", help="identify ARX models of the winding and iron temperatures (thesis 5.3)",
        description="Fit ARX models of T_winding and T_iron to rig data (genthermal.measurements CSV "
        "schema), list the best candidate structures, validate the best on a second record and write "
        "JSON. Every model has a constant (offset) term, so a training record that starts warm (after "
        "a discard) gives a consistent model; the validation simulation starts from the first measured "
        "temperature of that record (initialisation from the data).")
    parser.add_argument("train", help="training data CSV")
    parser.add_argument("validation", help="validation data CSV (the selected models are scored on it)")
    add_json_argument(parser, "the candidates, the selected models, their scores and the stacked state space")
    add_choice_argument(parser, "--input", ARX_INPUTS, default="auto",
                        help="input signal, a current column of the CSV, or auto: try each (default)")
    parser.add_argument("--integrate", action="store_true",
                        help="fit on the integrated input and multiply the integrator back (thesis eq 5.9)")
    parser.add_argument("--discard-before-min", default="0", metavar="MIN",
                        help="leave out the first MIN minutes of the training record for both outputs "
                        "(the thesis left out 30 min for the winding)")
    parser.add_argument("--na", default="1-3", help="numbers of A parameters to try, e.g. 1-3 (default)")
    parser.add_argument("--nb", default="1-3", help="numbers of B parameters to try, e.g. 1-3 (default)")
    parser.add_argument("--nk", default="0-4", help="input delays in samples to try, e.g. 0-4 (default)")
    parser.add_argument("--dt", default="10", help="sample time in s the data are resampled to (default 10)")
    parser.set_defaults(func=run)


def parse_range(option: str, text: str, smallest: int) -> range:
    """Parse ``"LOW-HIGH"`` or ``"N"`` into an inclusive range of integers >= ``smallest``."""
    low_text, sep, high_text = str(text).partition("-")
    try:
        low = int(low_text)
        high = int(high_text) if sep else low
    except ValueError:
        raise InputError(option, text, "expected an integer or a range LOW-HIGH, e.g. 1-3") from None
    if low < smallest or high < low or high > MAX_STRUCTURE_VALUE:
        raise InputError(option, text, f"need {smallest} <= LOW <= HIGH <= {MAX_STRUCTURE_VALUE}")
    return range(low, high + 1)


def run(args) -> int:
    """Search, select and validate a model per output; print the tables and write the JSON."""
    from ..estimation.arx import block_diagonal_state_space
    from ..estimation.arx_search import OUTPUTS
    from ..measurements import load_measurements, resample
    from ..outputs import report_json

    ts_s = positive_float("--dt", args.dt)
    search_options = {"na_range": parse_range("--na", args.na, 1), "nb_range": parse_range("--nb", args.nb, 1),
                      "nk_range": parse_range("--nk", args.nk, 0), "integrate_input": args.integrate,
                      "ts_s": ts_s, "constant_term": True}
    discard_before_s = 60.0 * non_negative_float("--discard-before-min", args.discard_before_min)
    train = resample(load_measurements(args.train), ts_s)
    validation = resample(load_measurements(args.validation), ts_s)
    report = {"ts_s": ts_s, "train": str(args.train), "validation": str(args.validation),
              "integrate_input": bool(args.integrate), "discard_before_s": discard_before_s}
    models = {}
    for output in OUTPUTS:
        report[output], models[output] = identify_output(train, validation, output, args.input,
                                                         discard_before_s, search_options)
    A, B, C, D = block_diagonal_state_space([models[output] for output in OUTPUTS])
    report["state_space"] = {"outputs": [f"T_{output} - y_offset" for output in OUTPUTS],
                             "inputs": [report[output]["input"] for output in OUTPUTS],
                             "A": A.tolist(), "B": B.tolist(), "C": C.tolist(), "D": D.tolist()}
    if args.json:
        print()
        report_json(args.json, report)
    return 0


def identify_output(train, validation, output: str, input_choice: str, discard_before_s: float,
                    search_options: dict):
    """Search, print and select the model of one output; return its JSON section and the model."""
    import numpy as np

    from ..estimation.arx import arx_fit, simulation_scores
    from ..estimation.arx_search import arx_search, input_signal, output_signal, select_input, training_record

    if input_choice == "auto":
        selection = select_input(train, output, discard_before_s=discard_before_s, **search_options)
        input_name, candidates = selection.input_name, selection.candidates
        print(f"\nT_{output}: best candidate per input signal")
        print(selection.per_input.to_string(index=False, float_format=lambda v: f"{v:.4f}"))
        y, u = training_record(train, output, input_name, discard_before_s)
    else:
        input_name = input_choice
        y, u = training_record(train, output, input_name, discard_before_s)
        candidates = arx_search(y, u, **search_options)
    print(f"\nT_{output} from {input_name}: {min(TABLE_ROWS, len(candidates))} best of {len(candidates)} "
          "candidates (sorted by R² of the simulated output)")
    print(f"{'na':>4} {'nb':>4} {'nk':>4} {'R^2':>9} {'AIC':>9}")
    for row in candidates.head(TABLE_ROWS).itertuples():
        print(f"{row.na:>4d} {row.nb:>4d} {row.nk:>4d} {row.R2:>9.4f} {row.AIC:>9.4f}")
    best = candidates.iloc[0]
    model = arx_fit(y, u, int(best.na), int(best.nb), int(best.nk), integrate_input=search_options["integrate_input"],
                    ts_s=search_options["ts_s"], constant_term=search_options["constant_term"])
    measured = output_signal(validation, output)
    start = measured[np.isfinite(measured)]
    if start.size == 0:
        raise InputError(f"{validation.source}: T_{output}", "all NaN", "the validation record has no measurement")
    scores = simulation_scores(model, measured, input_signal(validation, input_name), initial_output=float(start[0]))
    print(f"selected na={int(best.na)} nb={int(best.nb)} nk={int(best.nk)}: validation R² {scores['R2']:.4f}, "
          f"RMSE {scores['rmse_K']:.2f} K, max |error| {scores['max_abs_error_K']:.2f} K")
    section = {
        "input": input_name,
        "candidates": [_candidate(row) for row in candidates.itertuples()],
        "selected": {**_candidate(best), "a": model.a.tolist(), "b": model.b.tolist(),
                     "y_offset_C": model.y_offset, "constant_K": model.constant,
                     "loss_function_K2": model.loss_function},
        "validation": scores,
    }
    return section, model


def _candidate(row) -> dict:
    return {"na": int(row.na), "nb": int(row.nb), "nk": int(row.nk), "R2": float(row.R2), "AIC": float(row.AIC)}
