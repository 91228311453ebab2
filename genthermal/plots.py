"""Matplotlib figures of simulations. Functions return the figure and save it when given a path."""

from __future__ import annotations

import matplotlib.pyplot as plt  # the backend is the user's (the command line picks Agg, genthermal.cli)
import pandas as pd

from .machines.interface import InputKind
from .outputs import replacing

#: Resolution of every PNG genthermal writes, dots per inch.
FIGURE_DPI = 110


def finish_figure(fig, path=None, close: bool = False):
    """Lay out ``fig``, save it to ``path`` (PNG, folders created) when given, and return it.

    The file is written whole or not at all (:func:`genthermal.outputs.replacing`).

    ``close`` releases the figure from pyplot after saving (for reports that draw many)."""
    fig.tight_layout()
    if path is not None:
        with replacing(path) as temporary:
            fig.savefig(temporary, dpi=FIGURE_DPI)
    if close:
        plt.close(fig)
    return fig


def plot_simulation(result: pd.DataFrame, interface, title: str = "", path=None, limit_C: float | None = None):
    """Load currents and node temperatures of a simulation result over time.

    Parameters
    ----------
    result : pandas.DataFrame
        Output of :func:`genthermal.simulate.simulate`.
    interface : MachineInterface
        The simulated machine's (``model.spec.interface``): which columns are currents, inputs,
        sensors and limits.
    title : str
        Figure title.
    path : path-like, optional
        Where to save the PNG.
    limit_C : float, optional
        Temperature limit drawn as a dashed line; default the machine's sensor limits.
    """
    hours = result["time_s"] / 3600.0
    fig, (ax_i, ax_t) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True,
                                     gridspec_kw={"height_ratios": [1, 2.4]})
    currents = interface.inputs_of_kind(InputKind.CURRENT)
    for name in currents:
        ax_i.plot(hours, result[name], label=name, lw=1.2)
    ax_i.set_ylabel("current [A]")
    ax_i.legend(loc="lower right", ncol=len(currents), fontsize=8)
    ax_i.grid(alpha=0.3)
    not_nodes = {*interface.input_names, *interface.output_names}
    sensor_columns = {f"T_{node}" for node in interface.sensor_nodes.values()}
    nodes = [c for c in result.columns if c.startswith("T_") and c not in not_nodes]
    for column in nodes:
        emphasis = column in sensor_columns
        ax_t.plot(hours, result[column], lw=2.0 if emphasis else 1.0, alpha=1.0 if emphasis else 0.7,
                  label=column[2:].replace("_", " "))
    ax_t.plot(hours, result[interface.coolant_input], "k:", lw=1, label="coolant")
    limits = sorted(set(interface.limits_C.values())) if limit_C is None else [limit_C]
    for limit in limits:
        ax_t.axhline(limit, color="red", ls="--", lw=1, label=f"limit {limit:g} °C")
    ax_t.set_xlabel("time [h]")
    ax_t.set_ylabel("temperature [°C]")
    ax_t.legend(loc="upper left", fontsize=7, ncol=3)
    ax_t.grid(alpha=0.3)
    if title:
        ax_i.set_title(title)
    return finish_figure(fig, path)


def plot_comparison(results: dict[str, pd.DataFrame], columns, title: str = "", path=None):
    """Overlay the sensor temperatures of several runs (e.g. nonlinear vs linear vs C).

    Parameters
    ----------
    results : dict
        Label → result frame with ``time_s`` and ``columns``.
    columns : sequence of str
        Columns to overlay, one panel each (a model's ``output_names``).
    """
    fig, axes = plt.subplots(len(columns), 1, figsize=(9, 3.2 * len(columns)), sharex=True, squeeze=False)
    for ax, column in zip(axes[:, 0], columns):
        for label, frame in results.items():
            ax.plot(frame["time_s"] / 3600.0, frame[column], label=label, lw=1.3)
        ax.set_ylabel(f"{column} [°C]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[-1, 0].set_xlabel("time [h]")
    if title:
        axes[0, 0].set_title(title)
    return finish_figure(fig, path)
