"""Tables and figures of a diagnosis and a calibration, from what the result objects hold.

:func:`claims_frame` and :func:`plot_residual_change` are :meth:`Diagnosis.to_pandas` and
:meth:`Diagnosis.plot`; :func:`parameters_frame` and :func:`plot_fit` are those of
:class:`~genthermal.diagnose.calibrate.CalibrationResult`. Matplotlib is imported only to draw.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..sensor_faults import fault_bounds

#: Columns of :func:`claims_frame`, in order.
CLAIM_COLUMNS = ("claim", "kind", "subject", "quantity", "size", "unit", "bound_low", "bound_high", "onset_s",
                 "evidence", "delta_ic", "confidence")
#: Columns of :func:`parameters_frame`, in order.
PARAMETER_COLUMNS = ("name", "value", "unit", "ci95_low", "ci95_high", "std", "start", "provenance", "source",
                     "start_provenance")


def _number(value) -> float:
    return float("nan") if value is None else float(value)


def claims_frame(diagnosis):
    """Every claim of a diagnosis as a tidy table, one row per claimed size.

    Parameters
    ----------
    diagnosis : Diagnosis

    Returns
    -------
    pandas.DataFrame
        Columns :data:`CLAIM_COLUMNS`. ``claim`` is the index of the claim in
        ``diagnosis.to_dict()["claims"]``; ``kind``, ``evidence``, ``delta_ic`` (the criterion's
        change) and ``confidence`` are the claim's. One row per fitted parameter of a machine effect
        (``subject`` the effect, ``quantity`` the parameter, ``size`` its value in ``unit``,
        ``bound_low``/``bound_high`` the range a real machine's effect can take); one per sensor
        fault (``subject`` the sensor column, ``quantity`` the fault kind, ``size`` its value, the
        bounds what a faulty but still reading sensor of that kind can show); one for an
        unexplained residual (``quantity`` ``rmse``, ``size`` the residual's RMSE in K,
        ``bound_high`` the error level it is compared with). NaN where a bound or an onset (s from
        the record's start) does not apply.
    """
    import pandas as pd

    faults = iter(diagnosis.sensor_faults)
    rows = []
    for index, claim in enumerate(diagnosis.claims()):
        common = {"claim": index, "kind": claim["kind"], "evidence": claim["evidence"],
                  "delta_ic": _number(claim.get("delta_ic")), "confidence": claim["confidence"]}
        if claim["kind"] == "machine_effect":
            parameters = {p.name: p for p in diagnosis.catalogue[claim["effect"]].parameters}
            for name, value in claim["params"].items():
                parameter = parameters[name]
                low, high = parameter.plausible if parameter.plausible is not None else (parameter.lower,
                                                                                          parameter.upper)
                rows.append({**common, "subject": claim["effect"], "quantity": name, "size": float(value),
                             "unit": parameter.unit, "bound_low": float(low), "bound_high": float(high),
                             "onset_s": float(claim["onset_s"])})
        elif claim["kind"] == "sensor_fault":
            fault = next(faults).fault
            low, high = fault_bounds(fault)
            rows.append({**common, "subject": fault.sensor, "quantity": fault.kind, "size": float(fault.value),
                         "unit": fault.unit, "bound_low": low, "bound_high": high, "onset_s": float(fault.onset_s)})
        else:
            rows.append({**common, "subject": "residual", "quantity": "rmse", "size": _number(claim.get("rmse_K")),
                         "unit": "K", "bound_low": math.nan, "bound_high": _number(claim.get("floor_K")),
                         "onset_s": math.nan})
    return pd.DataFrame(rows, columns=list(CLAIM_COLUMNS))


def parameters_frame(result):
    """The fitted parameters of a calibration as a table, one row per parameter.

    Parameters
    ----------
    result : CalibrationResult

    Returns
    -------
    pandas.DataFrame
        Columns :data:`PARAMETER_COLUMNS`: the fitted ``value`` in ``unit``, its 95 % interval
        (``ci95_low``, ``ci95_high``) and standard deviation, the ``start`` value, the fitted
        value's ``provenance`` and ``source`` (what it was fitted on) and the provenance the start
        value had (``thesis``, ``literature``, ``assumed``, ``fitted``; empty when not recorded).
    """
    import pandas as pd

    rows = []
    for i, name in enumerate(result.names):
        parameter = result.model.parameters[name]
        low, high = result.fisher["ci95"][i]
        rows.append({"name": name, "value": float(result.values[i]), "unit": parameter.unit,
                     "ci95_low": float(low), "ci95_high": float(high), "std": float(result.fisher["std"][i]),
                     "start": float(result.start[i]), "provenance": parameter.provenance, "source": parameter.source,
                     "start_provenance": result.start_provenance[i] if i < len(result.start_provenance) else ""})
    return pd.DataFrame(rows, columns=list(PARAMETER_COLUMNS))


def _panels(ax, n: int):
    """(figure, one Axes per sensor, whether the figure is ours): new panels, or the user's ``ax``
    (one Axes for every sensor, or a sequence of one per sensor)."""
    import matplotlib.pyplot as plt

    if ax is None:
        fig, axes = plt.subplots(n, 1, figsize=(9, 1.2 + 2.3 * n), sharex=True, squeeze=False)
        return fig, list(axes[:, 0]), True
    if hasattr(ax, "plot"):
        return ax.figure, [ax] * n, False
    axes = list(np.ravel(np.asarray(ax, dtype=object)))
    if len(axes) != n or not all(hasattr(a, "plot") for a in axes):
        raise InputError("ax", f"{len(axes)} objects", f"give one matplotlib Axes, or one per sensor ({n})")
    return axes[0].figure, axes, False


def _finish(fig, path, ours: bool):
    """Lay out a figure we made; write it to ``path`` (PNG) whole or not at all; return it."""
    from ..outputs import replacing
    from ..plots import FIGURE_DPI, finish_figure

    if ours:
        return finish_figure(fig, path)
    if path is not None:
        with replacing(path) as temporary:
            fig.savefig(temporary, dpi=FIGURE_DPI)
    return fig


def _rms(values: np.ndarray) -> float:
    finite = values[np.isfinite(values)]
    return float(np.sqrt(np.mean(finite ** 2))) if finite.size else math.nan


def plot_residual_change(diagnosis, path=None, ax=None):
    """Residual (model − measurement, K) per sensor before the diagnosis and with its found effects.

    Parameters
    ----------
    diagnosis : Diagnosis
    path : path-like, optional
        PNG file to write the figure to.
    ax : matplotlib.axes.Axes or sequence of Axes, optional
        Draw into this Axes (every sensor) or these (one per sensor) instead of a new figure.

    Returns
    -------
    matplotlib.figure.Figure
    """
    series, names = diagnosis.series, diagnosis.output_names
    before = diagnosis.iterations[0].predicted_before - series.outputs
    after = diagnosis.iterations[-1].predicted_after - series.outputs
    added = " + ".join(f.effect for f in diagnosis.found) or "nothing found"
    fig, axes, ours = _panels(ax, len(names))
    hours = series.time_s / 3600.0
    for k, (panel, name) in enumerate(zip(axes, names)):
        label = f"{name} " if not ours else ""
        line = panel.plot(hours, before[k], lw=0.9, alpha=0.6, ls="--",
                          label=f"{label}before, RMS {_rms(before[k]):.3f} K")[0]
        panel.plot(hours, after[k], lw=1.1, color=line.get_color() if not ours else None,
                   label=f"{label}with {added}, RMS {_rms(after[k]):.3f} K")
        panel.axhline(0.0, color="k", lw=0.6)
        panel.set_ylabel(f"{name} residual [K]" if ours else "residual [K]")
        panel.grid(alpha=0.3)
        panel.legend(loc="upper left", fontsize=8)
    axes[-1].set_xlabel("time [h]")
    axes[0].set_title(f"{diagnosis.model.name} on {Path(str(series.source)).name}: verdict {diagnosis.verdict}")
    return _finish(fig, path, ours)


def plot_fit(result, path=None, ax=None):
    """Measured temperatures per sensor against the model before and after a calibration.

    Parameters
    ----------
    result : CalibrationResult
    path : path-like, optional
        PNG file to write the figure to.
    ax : matplotlib.axes.Axes or sequence of Axes, optional
        Draw into this Axes (every sensor) or these (one per sensor) instead of a new figure.

    Returns
    -------
    matplotlib.figure.Figure

    Raises
    ------
    InputError
        When the result holds no trajectories (``trajectories`` is None).
    """
    frame = result.trajectories
    if frame is None:
        raise InputError("trajectories", "None", "this calibration result holds no trajectories to plot")
    names = [column[: -len("_measured")] for column in frame.columns if column.endswith("_measured")]
    fig, axes, ours = _panels(ax, len(names))
    hours = frame["time_s"].to_numpy() / 3600.0
    for panel, name in zip(axes, names):
        label = f"{name} " if not ours else ""
        measured = frame[f"{name}_measured"].to_numpy()
        panel.plot(hours, measured, ".", ms=2, color="k", label=f"{label}measured")
        for stage, style in (("before", "--"), ("after", "-")):
            model = frame[f"{name}_{stage}"].to_numpy()
            panel.plot(hours, model, ls=style, lw=1.2,
                       label=f"{label}model {stage} the fit, RMS {_rms(model - measured):.3f} K")
        panel.set_ylabel(f"{name} [°C]" if ours else "temperature [°C]")
        panel.grid(alpha=0.3)
        panel.legend(loc="upper left", fontsize=8)
    axes[-1].set_xlabel("time [h]")
    axes[0].set_title(f"{result.model.name}: {', '.join(result.names)} fitted ({result.status})")
    return _finish(fig, path, ours)
