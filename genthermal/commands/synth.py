"""``genthermal synth SCENARIO --out data.csv``: synthetic rig data from a (possibly mismatched) plant."""

from __future__ import annotations

from ..errors import InputError
from ._common import (add_json_argument, add_model_arguments, add_out_argument, model_from_args, non_negative_float,
                      parse_assignments, positive_float)
from ._vocabulary import DEFAULT_CURRENT_NOISE, THESIS_NOISE_VARIANCE_K2


#: Largest sensor noise variance accepted, K² (a 10 K standard deviation: no PT100 is that bad).
MAX_NOISE_VARIANCE_K2 = 100.0
#: Largest relative current noise accepted (50 %).
MAX_CURRENT_NOISE = 0.5


def _at_most(option: str, value: float, limit: float, unit: str) -> float:
    if value > limit:
        raise InputError(option, value, f"at most {limit:g} {unit}: larger noise hides the machine entirely")
    return value


def register(subparsers) -> None:
    """Add the ``synth`` sub-command."""
    parser = subparsers.add_parser(
        "synth", help="write synthetic rig data (measurement CSV schema) for a mission",
        description="Simulate the nonlinear model on a mission and write what the rig would log: three "
        "winding PT100s and the iron and outlet PT100s with Gaussian noise (thesis eq. 6.10 variances), "
        "currents with relative noise. --param changes the plant's parameters to make it differ from "
        "the design model.")
    parser.add_argument("scenario", help="scenario name (see scenarios/) or path to a YAML file")
    add_out_argument(parser, "csv", "the record in the measurement CSV schema (genthermal.measurements)",
                     required=True)
    parser.add_argument("--seed", default="0", help="random seed (integer, default 0)")
    parser.add_argument("--dt", default="10", help="sample period in s (default 10)")
    parser.add_argument("--noise-winding", default=str(THESIS_NOISE_VARIANCE_K2[0]), metavar="K2",
                        help="noise variance of each winding sensor, K² (default 0.0082)")
    parser.add_argument("--noise-iron", default=str(THESIS_NOISE_VARIANCE_K2[1]), metavar="K2",
                        help="noise variance of the iron and outlet sensors, K² (default 0.013)")
    parser.add_argument("--current-noise", default=str(DEFAULT_CURRENT_NOISE), metavar="REL",
                        help="relative standard deviation of the measured currents (default 0.01)")
    add_model_arguments(parser, what="the plant")
    parser.add_argument("--generator", type=int, default=1,
                        help="which generator of a fault scenario to record (1-based, default 1)")
    add_json_argument(parser, "the record's summary (samples, step, seed, plant, overrides, noise, faults)")
    parser.set_defaults(func=run)


def run(args) -> int:
    """Simulate the plant and write the CSV."""
    from ..mission import load_mission
    from ..outputs import report_json, write_csv
    from ..synth import synthesize

    dt = positive_float("--dt", args.dt)
    try:
        seed = int(args.seed)
    except ValueError:
        raise InputError("--seed", args.seed, "must be a whole number") from None
    if seed < 0:
        raise InputError("--seed", args.seed, "must be a whole number >= 0")
    noise = tuple(_at_most(option, non_negative_float(option, text), MAX_NOISE_VARIANCE_K2, "K²")
                  for option, text in (("--noise-winding", args.noise_winding), ("--noise-iron", args.noise_iron)))
    current_noise = _at_most("--current-noise", non_negative_float("--current-noise", args.current_noise),
                             MAX_CURRENT_NOISE, "(relative)")
    overrides = parse_assignments(args.param)
    mission = load_mission(args.scenario)
    plant = model_from_args(args, source="synthetic plant, set on the command line")
    inputs, switches, fault_text = apply_scenario_faults(plant, mission, dt, args.generator)
    winding, iron = noise  # the outlet PT100 shares the iron's variance (--noise-iron)
    frame = synthesize(plant, inputs, dt_s=dt, seed=seed, noise_var=(winding, iron, iron), current_noise=current_noise,
                       switches=switches)
    out = write_csv(frame, args.out, float_format="%.5f")
    changed = "".join(f", {name}={value:g}" for name, value in overrides.items())
    print(f"{mission.name}: {len(frame)} samples every {dt:g} s from {plant.name} (--model {args.model}{changed}), "
          f"seed {seed}")
    if fault_text:
        print(f"faults of generator {args.generator}: {fault_text}")
    print(f"noise variances: winding {noise[0]:g} K² per sensor, iron {noise[1]:g} K², currents "
          f"{100 * current_noise:g} %")
    print(f"wrote {out}")
    if args.json:
        report_json(args.json, {"mission": mission.name, "samples": len(frame), "dt_s": dt, "seed": seed,
                                "plant": plant.name, "model": str(args.model), "param": overrides,
                                "noise_variance_K2": {"winding": noise[0], "iron": noise[1]},
                                "current_noise": current_noise, "generator": args.generator,
                                "faults": fault_text or None, "out": str(out)})
    return 0


def apply_scenario_faults(plant, mission, dt_s: float, generator: int):
    """The inputs and plant switches of one generator of a scenario with ``faults``.

    Each fault of that generator raises its coolant inlet temperature and switches the plant to
    the fault's catalogue effect from its onset (the schema is that of
    :mod:`genthermal.schedule.power_system`). Returns ``(inputs, switches, description)``.
    """
    inputs = mission.to_inputs(dt_s)
    if not mission.extras.get("faults"):
        return inputs, [], ""
    from ..schedule.power_system import PowerSystem

    system = PowerSystem.from_mission(mission)
    if not 1 <= generator <= system.n_generators:
        raise InputError("--generator", generator, f"the scenario has generators 1..{system.n_generators}")
    index = generator - 1
    inputs[plant.spec.interface.generator.coolant_input] = system.inlet_C(index, inputs["time_s"].to_numpy())
    faults = sorted((f for f in system.faults if f.generator == index), key=lambda f: f.onset_s)
    switches, model = [], plant
    for fault in faults:
        if fault.effect:
            model = model.with_effect(fault.effect, **fault.values)
            switches.append((fault.onset_s, model))
    text = "; ".join(f"{f.kind} at {f.onset_s / 60:g} min (inlet +{f.inlet_rise_C:g} K"
                     + (f", {f.effect} {dict(f.values)})" if f.effect else ")") for f in faults)
    return inputs, switches, text or "none"

