"""``genthermal simulate SCENARIO --out sim.csv``: one healthy generator on a mission's profile."""

from __future__ import annotations

from ._common import add_json_argument, add_model_arguments, add_out_argument, model_from_args, positive_float


def register(subparsers) -> None:
    """Add the ``simulate`` sub-command."""
    parser = subparsers.add_parser("simulate", help="simulate a mission scenario",
                                   description="Simulate a mission (YAML scenario or shipped name) and "
                                   "write time_s, the inputs, T_<node> per state and the sensor outputs (°C).")
    parser.add_argument("scenario", help="scenario name (see scenarios/) or path to a YAML file")
    add_out_argument(parser, "csv", "time_s, the inputs, T_<node> per state and the sensor outputs, °C",
                     required=True)
    parser.add_argument("--plot", metavar="FILE.png", help="write a plot of the run")
    parser.add_argument("--dt", default="10", help="model step and output interval in s (default 10)")
    add_model_arguments(parser)
    add_json_argument(parser, "the run's summary (model, mission, step, rows, peak of each sensor)")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Run the simulation and write the CSV (and plot, and JSON)."""
    from ..mission import load_mission
    from ..outputs import report_json, write_csv
    from ..simulate import simulate

    dt = positive_float("--dt", args.dt)
    mission = load_mission(args.scenario)
    model = model_from_args(args)
    result = simulate(model, mission.to_inputs(dt))
    out = write_csv(result, args.out, float_format="%.6f")
    peak = result[model.output_names].max()
    print(f"{mission.name}: {mission.duration_s / 3600:.2f} h on {model.name}, dt = {dt:g} s")
    if mission.extras.get("faults"):
        print("note: this scenario's faults and generators are not simulated here (one healthy generator "
              "on the nominal profile); `genthermal plan` and `genthermal fly` run them")
    for name, value in peak.items():
        print(f"  peak {name}: {value:.2f} °C")
    print(f"wrote {out} ({len(result)} rows)")
    if args.plot:
        from ..plots import plot_simulation

        plot_simulation(result, model.spec.interface, title=f"{mission.name} — {model.name}", path=args.plot)
        print(f"wrote {args.plot}")
    if args.json:
        report_json(args.json, {"model": model.name, "mission": mission.name, "dt_s": dt, "rows": len(result),
                                "out": str(out), "peak_C": {name: float(value) for name, value in peak.items()}})
    return 0
