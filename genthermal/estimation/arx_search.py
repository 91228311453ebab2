"""Choosing ARX structures and inputs from rig data (thesis 5.3.1-5.3.2, Tables 5.1/5.2).

The thesis fits each output (stator winding, stator iron) from one input at a time, tries every
candidate structure (na, nb, nk), ranks the candidates by the R² of the simulated output and weighs
the AIC against the model size. :func:`arx_search` produces that table for one output and input;
:func:`select_input` repeats it for each input signal and reports the best.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import product

import numpy as np
import pandas as pd

from ..errors import InputError
from ..machines.interface import InputKind, MachineInterface
from ..measurements import DEFAULT_INTERFACE, MeasurementData
from .arx import arx_fit, r_squared

#: Name of the derived input: the mean of the squared load currents (A²), proportional to the
#: copper losses.
MEAN_SQUARED_CURRENT = "I_sq"


def input_signals(interface: MachineInterface) -> tuple:
    """Input signals an ARX model of the machine ``interface`` can use: its current and speed
    inputs (A, rpm) and :data:`MEAN_SQUARED_CURRENT` (A²) when it has load currents. For the thesis
    generator: the phase currents, the exciter current and ``I_sq``."""
    signals = (*interface.inputs_of_kind(InputKind.CURRENT), *interface.inputs_of_kind(InputKind.SPEED))
    return (*signals, MEAN_SQUARED_CURRENT) if interface.load_currents else signals


#: Input signals of the default machine (the thesis generator).
INPUT_SIGNALS = input_signals(DEFAULT_INTERFACE)
#: Outputs modelled, named as :attr:`MeasurementData.winding` / :attr:`MeasurementData.iron`.
OUTPUTS = ("winding", "iron")
CANDIDATE_COLUMNS = ["na", "nb", "nk", "R2", "AIC"]


@dataclass
class InputSelection:
    """Result of :func:`select_input`.

    Attributes
    ----------
    input_name : str
        The input whose best candidate has the highest R².
    candidates : pandas.DataFrame
        Every candidate structure for that input (columns na, nb, nk, R2, AIC), best R² first.
    per_input : pandas.DataFrame
        The best candidate of each input tried (columns input, na, nb, nk, R2, AIC), best first.
    """

    input_name: str
    candidates: pd.DataFrame
    per_input: pd.DataFrame


def input_signal(data: MeasurementData, name: str) -> np.ndarray:
    """The input signal ``name`` (one of :func:`input_signals` of the data's machine) of ``data``.

    ``I_sq`` is the mean of the squared load currents (for the thesis generator
    :math:`(I_u^2 + I_v^2 + I_w^2) / 3`), A²; the others are the columns, in their units.
    """
    signals = input_signals(data.interface)
    if name not in signals:
        raise InputError("input", name, f"unknown input signal; choose one of {', '.join(signals)}")
    if name == MEAN_SQUARED_CURRENT:
        return (data.frame[list(data.interface.load_currents)].to_numpy(dtype=float) ** 2).mean(axis=1)
    return data.frame[name].to_numpy(dtype=float)


def output_signal(data: MeasurementData, output: str) -> np.ndarray:
    """The measured output ``output`` ("winding" or "iron"), °C, NaN where not measured."""
    if output not in OUTPUTS:
        raise InputError("output", output, f"unknown output; choose one of {', '.join(OUTPUTS)}")
    return getattr(data, output)


def training_record(data: MeasurementData, output: str, input_name: str,
                    discard_before_s: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """``(y, u)`` from ``data`` (uniformly sampled), without the samples before ``discard_before_s``.

    The thesis discarded the first 30 min of the winding record so that the fit favours the high
    temperatures that matter for overheating (thesis 5.3.2, stator winding model).
    """
    time_s = data.time_s
    keep = time_s - time_s[0] >= discard_before_s
    if np.count_nonzero(keep) < 10:
        raise InputError("discard_before_s", discard_before_s,
                         f"leaves {np.count_nonzero(keep)} samples of {data.source}; need at least 10")
    return output_signal(data, output)[keep], input_signal(data, input_name)[keep]


def arx_search(y, u, na_range=range(1, 4), nb_range=range(1, 4), nk_range=range(0, 5),
               integrate_input: bool = False, remove_offset: bool = True, ts_s: float = 10.0,
               constant_term: bool = False) -> pd.DataFrame:
    """Fit every structure of the ranges and score it (thesis Tables 5.1/5.2).

    Parameters
    ----------
    y, u : array_like
        Output (°C, NaN where not measured) and input on one uniform grid.
    na_range, nb_range, nk_range : iterable of int
        Numbers of A and B parameters and delays to try.
    integrate_input, remove_offset, ts_s, constant_term
        As :func:`~genthermal.estimation.arx.arx_fit`.

    Returns
    -------
    pandas.DataFrame
        Columns na, nb, nk, R2 (simulated output, see :func:`~genthermal.estimation.arx.r_squared`),
        AIC (:math:`\\ln V + 2 (n_a + n_b) / N`), sorted by R² (best first; AIC breaks ties).
    """
    rows = []
    structures = list(product(na_range, nb_range, nk_range))
    if not structures:
        raise InputError("structure ranges", [list(na_range), list(nb_range), list(nk_range)],
                         "every range must hold at least one value")
    for na, nb, nk in structures:
        model = arx_fit(y, u, na, nb, nk, integrate_input=integrate_input, remove_offset=remove_offset,
                        ts_s=ts_s, constant_term=constant_term)
        rows.append((na, nb, nk, r_squared(y, model.simulate(u)), model.aic))
    table = pd.DataFrame(rows, columns=CANDIDATE_COLUMNS)
    return table.sort_values(["R2", "AIC"], ascending=[False, True], kind="stable").reset_index(drop=True)


def select_input(data: MeasurementData, output: str, inputs=None, discard_before_s: float = 0.0,
                 **search_options) -> InputSelection:
    """Search every structure for each input of ``inputs`` and pick the input with the best R².

    Parameters
    ----------
    data : MeasurementData
        Uniformly sampled training data (see :func:`genthermal.measurements.resample`).
    output : str
        "winding" or "iron".
    inputs : iterable of str
        Input signals to try (default all of :func:`input_signals` of the data's machine).
    discard_before_s : float
        Leave out the start of the record, s (see :func:`training_record`).
    **search_options
        Passed to :func:`arx_search` (ranges, ``integrate_input``, ``remove_offset``, ``ts_s``,
        ``constant_term``).
    """
    tables, best_rows = {}, []
    inputs = input_signals(data.interface) if inputs is None else inputs
    for name in inputs:
        y, u = training_record(data, output, name, discard_before_s)
        tables[name] = arx_search(y, u, **search_options)
        best_rows.append({"input": name, **tables[name].iloc[0].to_dict()})
    if not best_rows:
        raise InputError("inputs", list(inputs), "need at least one input signal to try")
    per_input = pd.DataFrame(best_rows).sort_values(["R2", "AIC"], ascending=[False, True], kind="stable")
    per_input = per_input.reset_index(drop=True).astype({"na": int, "nb": int, "nk": int})
    best = str(per_input.loc[0, "input"])
    return InputSelection(best, tables[best], per_input)
