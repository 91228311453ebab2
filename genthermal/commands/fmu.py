"""``genthermal fmu --model NAME|FILE --out model.fmu``: an FMI 2.0 FMU (model exchange and
co-simulation) carrying the generated C library compiled for this machine and its sources.

Reference: docs/guide/embedded.md (the FMU itself: :mod:`genthermal.fmu`) and docs/guide/cli.md.
"""

from __future__ import annotations

from ._common import add_json_argument, add_model_arguments, add_out_argument, model_from_args


def register(subparsers) -> None:
    """Add the ``fmu`` sub-command."""
    parser = subparsers.add_parser(
        "fmu", help="export the model as an FMI 2.0 FMU (model exchange and co-simulation)",
        description="Write an FMI 2.0 FMU of the model for Modelica tools, Simulink or FMPy: inputs and "
        "sensor outputs named as in the model, parameters as tunable start values with units, directional "
        "derivatives from the exact Jacobians. Needs a C compiler.")
    add_model_arguments(parser, what="the model exported (parameters and effects of a model file included)")
    add_out_argument(parser, "fmu", "the model with its C library and sources", required=True)
    add_json_argument(parser, "what the FMU holds (identifier, variables, states, inputs, outputs, platform)")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Export the FMU and say what it holds."""
    from ..fmu import export_fmu

    model = model_from_args(args)
    written = export_fmu(model, args.out)
    print(f"wrote {written.path}: {model.name} as FMI 2.0 model exchange + co-simulation, "
          f"model identifier {written.model_identifier}, {written.n_variables} variables "
          f"({model.n_states} states, {len(model.input_names)} inputs, {len(model.output_names)} outputs, "
          f"{len(model.parameter_names)} tunable parameters), binary for {written.platform}")
    if args.json:
        from ..outputs import report_json

        report_json(args.json, {"model": model.name, "fmu": str(written.path),
                                "model_identifier": written.model_identifier, "variables": written.n_variables,
                                "states": model.n_states, "inputs": list(model.input_names),
                                "outputs": list(model.output_names), "parameters": len(model.parameter_names),
                                "platform": written.platform})
    return 0
