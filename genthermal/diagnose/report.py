"""Reports of comparisons and diagnoses: Markdown with plots, JSON, and the discovery demo."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..outputs import write_json
from ..plots import finish_figure, plt
from ..resources import DEMO_DATA_DIR
from .compare import Comparison, compare
from .discover import Diagnosis

#: The shipped demo dataset (which effect is hidden is said in its README, not in the CSV).
DEMO_DATA = DEMO_DATA_DIR / "hidden_effect_demo.csv"


def _save(fig, path: Path) -> str:
    finish_figure(fig, path, close=True)
    return path.name


def plot_overlay(time_s, measured, predictions: dict, names, path: Path, title: str = "") -> str:
    """Measured sensor temperatures against one or more model runs (one panel per sensor)."""
    hours = (np.asarray(time_s) - time_s[0]) / 3600.0
    fig, axes = plt.subplots(len(names), 1, figsize=(9, 3.0 * len(names)), sharex=True, squeeze=False)
    for i, (ax, name) in enumerate(zip(axes[:, 0], names)):
        ax.plot(hours, measured[i], ".", ms=2, color="0.35", label="measured")
        for label, predicted in predictions.items():
            ax.plot(hours, predicted[i], lw=1.4, label=label)
        ax.set_ylabel(f"{name} [°C]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[-1, 0].set_xlabel("time [h]")
    if title:
        axes[0, 0].set_title(title)
    return _save(fig, path)


def plot_residuals(time_s, residuals: dict, names, path: Path, title: str = "") -> str:
    """Model − measurement over time for one or more models."""
    hours = (np.asarray(time_s) - time_s[0]) / 3600.0
    fig, axes = plt.subplots(len(names), 1, figsize=(9, 2.6 * len(names)), sharex=True, squeeze=False)
    for i, (ax, name) in enumerate(zip(axes[:, 0], names)):
        for label, residual in residuals.items():
            ax.plot(hours, residual[i], lw=0.9, label=label)
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set_ylabel(f"{name} error [K]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[-1, 0].set_xlabel("time [h]")
    if title:
        axes[0, 0].set_title(title)
    return _save(fig, path)


def plot_regressors(comparison: Comparison, path: Path) -> str:
    """Residual of each sensor against the candidate regressors (I², θ, I_exc, T_inlet, dθ/dt for the
    thesis generator: ``comparison.regressor_labels``)."""
    frame, names, labels = comparison.frame, comparison.output_names, comparison.regressor_labels
    fig, axes = plt.subplots(len(names), len(labels), figsize=(3.0 * len(labels), 2.7 * len(names)),
                             squeeze=False)
    for i, name in enumerate(names):
        for j, (column, label) in enumerate(labels.items()):
            ax = axes[i, j]
            ax.plot(frame[column], frame[f"{name}_residual"], ".", ms=2, alpha=0.5)
            ax.axhline(0.0, color="k", lw=0.6)
            ax.set_xlabel(label, fontsize=8)
            if j == 0:
                ax.set_ylabel(f"{name} error [K]", fontsize=8)
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
    return _save(fig, path)


def _metrics_table(split: dict, names) -> list[str]:
    lines = ["| band | " + " | ".join(f"{n} RMSE [K] | {n} bias [K]" for n in names) + " |",
             "|---|" + "---|---|" * len(names)]
    for band, per_sensor in split.items():
        cells = []
        for n in names:
            m = per_sensor[n]
            cells += ["–", "–"] if m["rmse"] is None else [f"{m['rmse']:.3f}", f"{m['bias']:+.3f}"]
        lines.append(f"| {band} | " + " | ".join(cells) + " |")
    return lines


def write_compare_report(comparison: Comparison, out_dir) -> Path:
    """Write ``report.md``, ``metrics.json`` and the plots of a comparison into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    frame, names, metrics = comparison.frame, comparison.output_names, comparison.metrics
    measured = frame[[f"{n}_measured" for n in names]].to_numpy().T
    predicted = frame[[f"{n}_model" for n in names]].to_numpy().T
    overlay = plot_overlay(frame["time_s"].to_numpy(), measured, {comparison.model_name: predicted}, names,
                           out / "model_vs_measurement.png", f"{comparison.model_name} on {comparison.source}")
    residual = plot_residuals(frame["time_s"].to_numpy(), {"model − measured": predicted - measured}, names,
                              out / "residual_vs_time.png")
    regressors = plot_regressors(comparison, out / "residual_vs_regressors.png")
    write_json(out / "metrics.json", metrics)
    lines = [f"# {comparison.model_name} against {comparison.source}", "",
             f"{metrics['samples']} samples every {metrics['dt_s']:g} s; error = model − measurement "
             f"(positive: the model runs hot). RMSE over both sensors: {metrics['rmse_all_sensors']:.3f} K.", "",
             "| sensor | RMSE [K] | MAE [K] | max abs [K] | bias [K] | R² | trend [K/h] |", "|---|---|---|---|---|---|---|"]
    for n in names:
        m = metrics["overall"][n]
        r2 = "–" if m["r2"] is None else f"{m['r2']:.4f}"
        lines.append(f"| {n} | {m['rmse']:.3f} | {m['mae']:.3f} | {m['max_abs']:.3f} | {m['bias']:+.3f} | {r2} | "
                     f"{metrics['trend_K_per_h'][n]:+.3f} |")
    for title, key in (("Load band", "by_load_band"), ("Temperature band", "by_temperature_band"),
                       ("Heating or cooling", "by_heating"), ("Hour", "by_hour")):
        lines += ["", f"## Where it fails: {title.lower()}", "", *_metrics_table(metrics[key], names)]
    lines += ["", "## Plots", "", f"![model vs measurement]({overlay})", "", f"![residual]({residual})", "",
              f"![residual vs regressors]({regressors})", "",
              f"Initial state: {metrics['initial_state']['method']} (a = {metrics['initial_state']['a']:.3f}, "
              f"c = {metrics['initial_state']['c_C']:.2f} °C)."]
    (out / "report.md").write_text("\n".join(lines) + "\n")
    return out / "report.md"


def write_diagnosis_report(diagnosis: Diagnosis, out_dir) -> Path:
    """Write ``report.md``, ``diagnosis.json`` and the before/after overlays into ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    series, names = diagnosis.series, diagnosis.output_names
    document = diagnosis.to_dict()
    write_json(out / "diagnosis.json", document)
    lines = [f"# Diagnosis of {document['model']} on {document['data']}", "",
             f"Verdict: **{document['verdict']}**. Estimated sensor noise {diagnosis.noise_std:.3f} K.", "",
             document["explanation"], "", "| round | RMSE before [K] | added | RMSE after [K] |", "|---|---|---|---|"]
    for k, iteration in enumerate(diagnosis.iterations, start=1):
        lines.append(f"| {k} | {iteration.rmse_before:.3f} | {' + '.join(iteration.added_effects) or '–'} | "
                     f"{iteration.rmse_after:.3f} |")
    lines += ["", "## Is something still missing?", "", diagnosis.residual["summary"]]
    if diagnosis.experiment:
        scenario = diagnosis.experiment.write(out / "separating_test.yaml")
        experiment = diagnosis.experiment
        lines += ["", "## A test that tells the look-alikes apart", "",
                  f"{experiment.candidates[0]} and {experiment.candidates[1]} explain these data about equally well. "
                  f"The {experiment.mission.duration_s / 60:.0f}-min test [{scenario.name}]({scenario.name}) (within "
                  f"the ratings, winding at most {experiment.peak_winding_C:.1f} °C) separates their predicted "
                  f"{experiment.sensor} by {experiment.separation_sigma:.0f} × the noise at "
                  f"{experiment.at_time_min:.0f} min: run it on the rig and diagnose the record."]
    lines += ["", "## Ranking (first round)", "", "| effect | parameters | onset [h] | RMSE after [K] | ΔBIC | significant |",
              "|---|---|---|---|---|---|"]
    for c in diagnosis.iterations[0].ranked:
        params = ", ".join(f"{k} = {v:.4g}" for k, v in c.values.items())
        lines.append(f"| {c.effect} | {params} | {c.onset_s / 3600:.2f} | {c.rmse_after:.3f} | {c.delta_bic:.0f} | "
                     f"{'yes' if c.significant else 'no'} |")
    for k, iteration in enumerate(diagnosis.iterations, start=1):
        if not iteration.added_effects:
            continue
        added = " + ".join(iteration.added_effects)
        predictions = {"before": iteration.predicted_before, f"with {added}": iteration.predicted_after}
        overlay = plot_overlay(series.time_s, series.outputs, predictions, names, out / f"round_{k}_overlay.png",
                               f"round {k}: adding {added}")
        residual = plot_residuals(series.time_s, {n: p - series.outputs for n, p in predictions.items()}, names,
                                  out / f"round_{k}_residual.png")
        lines += ["", f"## Round {k}: {added}", "", iteration.explanation, "",
                  f"![overlay]({overlay})", "", f"![residual]({residual})"]
    (out / "report.md").write_text("\n".join(lines) + "\n")
    return out / "report.md"


def run_discovery_demo(out_dir, data=None, model=None) -> dict:
    """Compare → diagnose → add the effect → the error falls, on the shipped demo dataset.

    Parameters
    ----------
    out_dir : path-like
        Where the compare and diagnose reports and plots go (``compare/``, ``diagnose/``,
        ``improved_model.yaml``, ``summary.json``).
    data : path-like, optional
        Measurements; default ``scenarios/data/hidden_effect_demo.csv``.
    model : ThermalModel, optional
        Default: the nonlinear model of the thesis generator.

    Returns
    -------
    dict
        ``rmse_before``, ``rmse_after`` (K), ``verdict``, ``params``, ``onset_s``, ``noise_std_K``
        and the paths written.
    """
    from ..machines import build_model
    from ..model_file import save_model
    from .discover import diagnose

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    data = DEMO_DATA if data is None else Path(data)
    model = build_model() if model is None else model
    before = compare(model, data)
    write_compare_report(before, out / "compare")
    diagnosis = diagnose(model, data)
    write_diagnosis_report(diagnosis, out / "diagnose")
    improved = diagnosis.improved_model()
    save_model(improved, out / "improved_model.yaml", {f.effect: f.onset_s for f in diagnosis.found})
    added = diagnosis.iterations[0].added
    summary = {"data": str(data), "verdict": diagnosis.verdict, "noise_std_K": diagnosis.noise_std,
               # before and after on the same sensors: the diagnosis's (compare's report has its own)
               "rmse_before": diagnosis.iterations[0].rmse_before,
               "rmse_after": added.rmse_after if added else diagnosis.iterations[0].rmse_before,
               "params": added.values if added else {}, "onset_s": added.onset_s if added else None,
               "explanation": diagnosis.iterations[0].explanation,
               "reports": [str(out / "compare" / "report.md"), str(out / "diagnose" / "report.md")],
               "model_file": str(out / "improved_model.yaml")}
    write_json(out / "summary.json", summary)
    return summary
