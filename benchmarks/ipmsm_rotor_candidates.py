"""Rotor candidates for the bench IPMSM, each one small transformation of ``MACHINE`` (a study).

Round 4 of ``docs/results/ipmsm.md``: the rotor reading as a mix of the rotor and a neighbour
(the end-space air, the teeth, the end winding; also with a magnet-layer node), a fast
over-temperature of the sensor spot, a rotor-loss term in current times speed, a magnet loss
falling with magnet temperature, and the EKF's process noise on the rotor. ``pilot`` fits on the
2-fold pilot of the results page, ``folds`` on the benchmark's four folds (the same fit, sensor
weights and rotor-side prior as ``bench_ipmsm.py``), ``ekf`` takes the rotor's process noise from
a grid by the training profiles' rotor error. None of these terms is in the machine file.

Run: ``python3 benchmarks/ipmsm_rotor_candidates.py pilot VARIANT ...`` (``folds VARIANT``, ``ekf``).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import time
from pathlib import Path

import numpy as np
import sympy

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_ipmsm as bench  # noqa: E402

from genthermal import speed_losses  # noqa: E402
from genthermal.diagnose.multi_record import fit_records, simulate_record  # noqa: E402
from genthermal.estimation.node_observer import NodeObserver  # noqa: E402
from genthermal.losses import input_symbol  # noqa: E402
from genthermal.machines import build_model  # noqa: E402
from genthermal.machines.registry import resolve_machine  # noqa: E402
from genthermal.network import HeatSource, Link, Node  # noqa: E402
from genthermal.parameters import Parameter, ParameterSet  # noqa: E402

#: Training profiles of the pilot's first fold (the second trains on the other six).
PILOT_TRAIN = ("id_1", "id_3", "id_7", "id_9", "id_12", "id_14")
#: Total conductance of a massless probe node, W/K: the heat through it is negligible, so that it
#: changes the reading only.
PROBE_G = 1e-3
#: Process-noise steps of the rotor node tried in the EKF, K per step (None: the observer's own).
ROTOR_STD_GRID_K = (None, 0.01, 0.03, 0.1, 0.3)
EKF_SENSORS = bench.SENSOR_SETS["stator sensors without end cap and bearing"]


def _with(machine, extra, build, sensor_node=None):
    """``machine`` with parameters ``extra`` added and its network passed through ``build``."""
    base_params, base_build = machine.default_parameters, machine.build_network
    interface = machine.interface
    if sensor_node is not None:
        interface = dataclasses.replace(interface, sensors=tuple(
            dataclasses.replace(s, node=sensor_node) if s.output == "T_rotor" else s for s in interface.sensors))
    return dataclasses.replace(machine, interface=interface, default_parameters=lambda: extra(base_params()),
                               build_network=lambda p: build(base_build(p), p.symbols()))


def mixed_reading(machine, neighbour="end_space_air", on="rotor"):
    """The rotor reading = T_on + w (T_neighbour - T_on), w in [0.001, 0.5] (a massless probe)."""
    def extra(p):
        return p.with_parameters(Parameter("w_probe", 0.1, "1", "assumed", f"share of {neighbour} in the reading",
                                           lower=1e-3, upper=0.5, lower_inclusive=True))

    def build(net, S):
        w = S["w_probe"]
        return net.replace(nodes=net.nodes + (Node("rotor_probe", "massless", None, "solid"),),
                           links=net.links + (Link(on, "rotor_probe", 1 / (PROBE_G * (1 - w)), "probe"),
                                              Link("rotor_probe", neighbour, 1 / (PROBE_G * w), "probe")))
    return _with(machine, extra, build, "rotor_probe")


def spot_over_temperature(machine, with_load=False):
    """The rotor reading = T_rotor + b n/n_ref (+ d (I/I_ref)^2), K: a fast local over-temperature."""
    roles = machine.interface.roles

    def extra(p):
        new = [Parameter("dT_spot_speed", 1.0, "K", "assumed", "spot over-temperature at n_ref", lower=0.0,
                         upper=15.0, lower_inclusive=True)]
        if with_load:
            new.append(Parameter("dT_spot_load", 0.5, "K", "assumed", "spot over-temperature at I_ref",
                                 lower=0.0, upper=15.0, lower_inclusive=True))
        return p.with_parameters(*new)

    def build(net, S):
        rise = S["dT_spot_speed"] * speed_losses.speed_ratio(roles)
        if with_load:
            rise = rise + S["dT_spot_load"] * speed_losses.load_squared(roles)
        net = net.replace(nodes=net.nodes + (Node("rotor_probe", "massless", None, "solid"),),
                          links=net.links + (Link("rotor", "rotor_probe", 1 / PROBE_G, "probe"),))
        return net.with_heat_sources([HeatSource("rotor_probe", PROBE_G * rise, "spot")])
    return _with(machine, extra, build, "rotor_probe")


def magnet_loss_temperature(machine):
    """The magnet loss times (1 - a (T_rotor - 20 °C)), a in [0, 0.005] 1/K (NdFeB's resistivity)."""
    def extra(p):
        return p.with_parameters(Parameter("a_pm_theta", 0.002, "1/K", "assumed", "fall of the magnet eddy loss "
                                           "per K (NdFeB resistivity rising 0.1-0.3 %/K)", lower=0.0, upper=0.005,
                                           lower_inclusive=True))

    def build(net, S):
        factor = 1 - S["a_pm_theta"] * (net.temperature_symbol("rotor") - 20)
        return net.replace(heat_sources=tuple(
            dataclasses.replace(s, power=s.power * factor) if s.label == speed_losses.LABELS["magnet"] else s
            for s in net.heat_sources))
    return _with(machine, extra, build)


def current_speed_loss(machine):
    """A rotor loss P_pm (n/n_ref)^c k (I/I_ref)^2 n/n_ref beside the magnet loss (a loss map term)."""
    roles = machine.interface.roles

    def extra(p):
        return p.with_parameters(Parameter("k_pm_current_speed", 0.1, "1", "assumed", "rise of the rotor loss's "
                                           "current part with speed", lower=0.0, upper=20.0, lower_inclusive=True))

    def build(net, S):
        power = (S["P_pm_ref"] * speed_losses.speed_power(roles, S["pm_speed_exponent"]) * S["k_pm_current_speed"]
                 * speed_losses.load_squared(roles) * speed_losses.speed_ratio(roles))
        return net.with_heat_sources([HeatSource("rotor", power, speed_losses.LABELS["magnet"])])
    return _with(machine, extra, build)


def magnet_layer(machine, c_magnet=2500.0, c_core=5100.0, g_core=40.0):
    """Two rotor nodes: the magnet layer (sensor, magnet loss, air gap) and the core ("rotor")."""
    def extra(p):
        return ParameterSet([p[n] for n in p if n != "C_rotor"] + [
            Parameter("C_rotor", c_core, "J/K", "assumed", "rotor core lamination", lower=c_core / 3,
                      upper=c_core * 3, lower_inclusive=True),
            Parameter("C_magnet", c_magnet, "J/K", "assumed", "magnets and the lamination around them",
                      lower=c_magnet / 3, upper=c_magnet * 3, lower_inclusive=True),
            Parameter("G_magnet_core", g_core, "W/K", "assumed", "magnet pockets and bridges to the core")])

    def build(net, S):
        core, tooth = net.temperature_symbol("rotor"), net.temperature_symbol("tooth")
        layer = sympy.Symbol("theta_magnet", real=True)
        links = tuple(Link("tooth", "magnet", l.resistance, l.label) if {l.a, l.b} == {"tooth", "rotor"} else l
                      for l in net.links) + (Link("magnet", "rotor", 1 / S["G_magnet_core"], "pockets"),)
        sources = []
        for s in net.heat_sources:
            if s.label == speed_losses.LABELS["magnet"]:
                s = dataclasses.replace(s, node="magnet")
            elif {tooth, core} <= s.power.free_symbols and s.node in ("tooth", "rotor"):  # the air-gap rise
                s = dataclasses.replace(s, node="magnet" if s.node == "rotor" else s.node,
                                        power=s.power.subs(core, layer))
            sources.append(s)
        return net.replace(nodes=net.nodes + (Node("magnet", "capacitive", S["C_magnet"], "solid"),), links=links,
                           heat_sources=tuple(sources))
    return _with(machine, extra, build, "magnet")


LAYER_PRIOR = {"C_magnet": bench.ROTOR_PRIOR_WEIGHT, "G_magnet_core": bench.ROTOR_PRIOR_WEIGHT}
#: name -> (transformation of the machine, extra prior weights, machine whose sensors set the initial states)
VARIANTS = {
    "base": (lambda m: m, {}, None),
    "mix_air": (mixed_reading, {}, None),
    "mix_air_prior": (mixed_reading, {"w_probe": bench.ROTOR_PRIOR_WEIGHT}, None),
    "mix_tooth": (lambda m: mixed_reading(m, "tooth"), {}, None),
    "mix_end_winding": (lambda m: mixed_reading(m, "end_winding"), {}, None),
    "magnet_layer": (magnet_layer, LAYER_PRIOR, magnet_layer),
    "magnet_layer_mix_air": (lambda m: mixed_reading(magnet_layer(m), on="magnet"),
                             {**LAYER_PRIOR, "w_probe": bench.ROTOR_PRIOR_WEIGHT}, magnet_layer),
    "spot": (spot_over_temperature, {}, None),
    "spot_load": (lambda m: spot_over_temperature(m, True), {}, None),
    "pm_theta": (magnet_loss_temperature, {"a_pm_theta": bench.ROTOR_PRIOR_WEIGHT}, None),
    "pm_theta_free": (magnet_loss_temperature, {}, None),
    "current_speed": (current_speed_loss, {"k_pm_current_speed": bench.ROTOR_PRIOR_WEIGHT}, None),
    "current_speed_free": (current_speed_loss, {}, None),
}


def _setup(variant):
    make, extra_prior, starts = VARIANTS[variant]
    machine = resolve_machine(str(bench.MACHINE_FILE))
    model = build_model(make(machine))
    # the probe's reading is the rotor's at the start: initial states from the sensor on a state node
    start_model, names, data, to_record = bench.load(bench.SCORE_STEP_S)
    if starts is not None:
        start_model = build_model(starts(machine))
    fit_recs = [to_record(start_model, d, bench.FIT_STEP_S) for d in data]
    score_recs = [to_record(start_model, d, bench.SCORE_STEP_S) for d in data]
    fitted = [n for n in model.parameter_names if model.parameters[n].provenance == "assumed"]
    return model, names, fit_recs, score_recs, fitted, {**bench.prior_weights(fitted), **extra_prior}


def _rmse(errors):
    e = errors[np.isfinite(errors)]
    return float(np.sqrt(np.mean(e ** 2)))


def _stats(parts):
    e = np.concatenate(parts)
    e = e[np.isfinite(e)]
    return [round(float(np.sqrt(np.mean(e ** 2))), 3), round(float(np.max(np.abs(e))), 2)]


def cross_validate(variant, train_sets, ekf=False):
    """Fit ``variant`` on each training set, score open loop (and the EKF) on the other profiles."""
    model, names, fit_recs, score_recs, fitted, prior = _setup(variant)
    weights = [bench.OUTPUT_WEIGHTS.get(o, 1.0) for o in model.output_names]
    errors = {g: [] for g in bench.AUTHORS_LPTN_RMSE_K}
    ekf_errors = {"winding": [], "rotor": []}
    report = {"variant": variant, "n_fitted": len(fitted), "folds": []}
    for train_set in train_sets:
        train = [fit_recs[i] for i, n in enumerate(names) if n in train_set]
        started = time.perf_counter()
        fit = fit_records(model, train, fitted, factor=30.0, output_weights=weights, prior_weight=prior)
        report["folds"].append({"train": list(train_set), "time_s": round(time.perf_counter() - started, 1),
                                "converged": fit.converged,
                                "values": {n: float(fit.model.parameters[n].value) for n in fitted}})
        held = [i for i, n in enumerate(names) if n not in train_set]
        bias = bench.tuned_bias_std(fit.model, [score_recs[i] for i in range(len(names)) if i not in held]) \
            if ekf else None
        for i in held:
            record = score_recs[i]
            measured = bench.groups(model, record.outputs)
            predicted = bench.groups(model, simulate_record(fit.model, record))
            for g in errors:
                errors[g].append(predicted[g] - measured[g])
            rotor = errors["rotor"][-1][np.isfinite(errors["rotor"][-1])]
            report.setdefault("rotor_mean_rmse_by_profile_K", {})[names[i]] = [round(float(rotor.mean()), 2),
                                                                               round(_rmse(rotor), 2)]
            if ekf:
                _, y = NodeObserver(fit.model, record.dt_s, EKF_SENSORS, bias_std_K=bias).run(record)
                for g in ekf_errors:
                    ekf_errors[g].append(bench.groups(model, y)[g] - measured[g])
    report.update({g: _stats(parts) for g, parts in errors.items()})
    if ekf:
        report.update({f"ekf_{g}": _stats(parts) for g, parts in ekf_errors.items()})
    return report


def _rotor_noise_errors(model, records, bias, rotor_std):
    rotor, out = model.state_names.index("rotor"), model.output_names.index("T_rotor")
    errors = []
    for record in records:
        observer = NodeObserver(model, record.dt_s, EKF_SENSORS, bias_std_K=bias)
        if rotor_std is not None:
            observer.Q[rotor, rotor] = rotor_std ** 2
        errors.append(observer.run(record)[1][out] - record.outputs[out])
    return np.concatenate(errors)


def ekf_rotor_noise(pilot_report):
    """EKF on the stator sensors with the rotor's process noise of :data:`ROTOR_STD_GRID_K`, on the
    pilot's fitted base models; each fold takes the step with the smallest training rotor error."""
    model, names, _, score_recs, _, _ = _setup("base")
    held = {q: [] for q in ROTOR_STD_GRID_K}
    chosen = []
    for fold in pilot_report["folds"]:
        fitted = model.with_parameters(provenance="fitted", source="pilot", **fold["values"])
        train = [score_recs[i] for i, n in enumerate(names) if n in fold["train"]]
        test = [score_recs[i] for i, n in enumerate(names) if n not in fold["train"]]
        bias = bench.tuned_bias_std(fitted, train)
        scores = {q: _rmse(_rotor_noise_errors(fitted, train, bias, q)) for q in ROTOR_STD_GRID_K}
        for q in ROTOR_STD_GRID_K:
            held[q].append(_rotor_noise_errors(fitted, test, bias, q))
        best = min(scores, key=scores.get)
        chosen.append(held[best][-1])
        print(json.dumps({"train": fold["train"], "bias_std_K": bias, "training_rotor_rmse_K": scores,
                          "chosen_rotor_std_K": best}), flush=True)
    for q in ROTOR_STD_GRID_K:
        print(json.dumps({"rotor_std_K": q, "rotor_rmse_max_K": _stats(held[q])}))
    print(json.dumps({"rotor_std_K": "chosen on the training profiles", "rotor_rmse_max_K": _stats(chosen)}))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("what", choices=("pilot", "folds", "ekf"))
    parser.add_argument("variants", nargs="*", default=["base"], help=", ".join(VARIANTS))
    args = parser.parse_args()
    if not bench.DATA.is_dir():
        print(json.dumps({"skipped": f"no data at {bench.DATA}"}))
        return 0
    names = sorted((p.stem for p in bench.DATA.glob("id_*.csv")), key=lambda stem: int(stem.split("_")[1]))
    if args.what == "ekf":
        ekf_rotor_noise(cross_validate("base", (PILOT_TRAIN, tuple(n for n in names if n not in PILOT_TRAIN))))
        return 0
    for variant in args.variants:
        if args.what == "pilot":
            report = cross_validate(variant, (PILOT_TRAIN, tuple(n for n in names if n not in PILOT_TRAIN)))
        else:
            held = [names[i::4] for i in range(4)]
            report = cross_validate(variant, [tuple(n for n in names if n not in h) for h in held], ekf=True)
        shown = {k: v for k, v in report.items() if k != "folds"}
        shown["fits"] = [[f["time_s"], f["converged"]] for f in report["folds"]]
        print(json.dumps(shown), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
