"""``genthermal fmu --model M --out m.fmu``: an FMI 2.0 FMU (model exchange and co-simulation).

``M`` is a built-in model (``genco_rf201a``, ``genco_rf201a:linear``) or a model file written by
``calibrate`` / ``diagnose`` (parameters and effects included). The FMU carries the generated C
library compiled for this machine and its sources; see :mod:`genthermal.fmu`.
"""

from __future__ import annotations

from ..fmu import export_fmu
from ..model_file import load_model


def register(subparsers) -> None:
    """Add the ``fmu`` sub-command."""
    parser = subparsers.add_parser(
        "fmu", help="export the model as an FMI 2.0 FMU (model exchange and co-simulation)",
        description="Write an FMI 2.0 FMU of the model for Modelica tools, Simulink or FMPy: inputs and "
        "sensor outputs named as in the model, parameters as tunable start values with units, directional "
        "derivatives from the exact Jacobians. Needs a C compiler.")
    parser.add_argument("--model", default="genco_rf201a",
                        help="built-in model (genco_rf201a, genco_rf201a:linear) or a model file (YAML)")
    parser.add_argument("--out", required=True, help="the .fmu file to write")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Export the FMU and say what it holds."""
    model = load_model(args.model)
    written = export_fmu(model, args.out)
    print(f"wrote {written.path}: {model.name} as FMI 2.0 model exchange + co-simulation, "
          f"model identifier {written.model_identifier}, {written.n_variables} variables "
          f"({model.n_states} states, {len(model.input_names)} inputs, {len(model.output_names)} outputs, "
          f"{len(model.parameter_names)} tunable parameters), binary for {written.platform}")
    return 0
