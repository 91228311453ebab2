"""``genthermal describe``: the model's nodes, element formulas (plain or LaTeX) and parameters
with their provenance."""

from __future__ import annotations

from ._common import add_json_argument, add_model_arguments, model_from_args


def register(subparsers) -> None:
    """Add the ``describe`` sub-command."""
    parser = subparsers.add_parser("describe", help="list nodes, element formulas and parameters with provenance")
    parser.add_argument("--latex", action="store_true", help="print the element formulas as LaTeX")
    add_model_arguments(parser)
    add_json_argument(parser, "the model's states, inputs, sensors and parameters (value, unit, provenance, source)")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Print the description (and write the JSON)."""
    import sympy

    model = model_from_args(args)
    net = model.network
    show = sympy.latex if args.latex else sympy.sstr
    stages = net.reduction_stages()
    print(f"{model!r}\nnodes: {stages['all_nodes']} -> {stages['without_intermediate']} without intermediate "
          f"nodes -> {stages['states']} states")
    interface = model.spec.interface
    print(f"\ninputs: {', '.join(f'{i.name} [{i.unit}]' for i in interface.inputs)}; rated current "
          f"{interface.rated_current_A:g} A")
    print("sensors: " + "; ".join(f"{s.output} = node {s.node} (columns {', '.join(s.columns)}, noise "
                                  f"{s.noise_variance_K2:g} K^2" + (f", limit {s.limit_C:g} °C)" if s.limit_C else ")")
                                  for s in interface.sensors))
    print(f"roles: {', '.join(role.value for role in interface.roles) or 'none'}")
    print("\nstates (capacitive nodes) and heat capacities [J/K]:")
    for name in model.state_names:
        print(f"  {name:22s} C = {show(net.node(name).capacitance)}")
    print("\nlinks, resistance [K/W]:")
    for link in net.links:
        print(f"  {link.a} -- {link.b}  [{link.label}]\n      R = {show(link.resistance)}")
    print("\nair streams, resistance 1/(c_air m_dot) [K/W]:")
    for stream in net.air_streams:
        print(f"  {stream.upstream} -> {stream.downstream}: R = {show(stream.resistance)}")
    print("\nheat sources [W]:")
    for source in net.heat_sources:
        print(f"  {source.node} ({source.label}): {show(source.power)}")
    print("\nparameters:")
    for row in model.parameters.table():
        print(f"  {row['name']:20s} {row['value']:<12.6g} {row['unit']:12s} {row['provenance']:10s} {row['source']}")
    if args.json:
        from ..outputs import report_json

        report_json(args.json, {"model": model.name, "nodes": stages, "states": list(model.state_names),
                                "inputs": [{"name": i.name, "unit": i.unit} for i in interface.inputs],
                                "outputs": list(model.output_names),
                                "parameters": [{key: (float(value) if key == "value" else value)
                                                for key, value in row.items()} for row in model.parameters.table()]})
    return 0
