"""The ambient PT100 against the coolant-inlet PT100: two readings of the same air.

On a rig whose cooling air is drawn from the room, the inlet and ambient PT100s read the same air,
so an ambient reading that leaves the inlet reading, and that the machine does not contradict, is
a sensor fault. :func:`screen_ambient_against_inlet` applies the four tests;
:func:`minimal_detectable_error` gives the smallest ambient bias the outputs alone could tell from
a frame cooling change. Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import math

import numpy as np

from ..sensor_faults import SensorFault
from .sensor_faults import PREFERENCE_BIC, SensorHypothesis

#: Two PT100s in the same air read within this, K: class B is ±(0.30 + 0.005·|T|) K (IEC 60751),
#: ±0.40 K at 20 °C each; two independent errors of that tolerance differ by at most
#: √2 · 0.40 = 0.57 K in root-sum-square, rounded to 0.6 K.
SHARED_AIR_TOLERANCE_K = 0.6
#: A disagreement of the two readings that counts, K (as the flight's input watch,
#: :attr:`~genthermal.schedule.monitoring.input_watch.InputWatchSettings.disagreement_K`: a 1-K input error is
#: what the plan's margin can take).
MIN_CHANGE_K = 1.0
#: The two readings must agree over at least this share of the record before the onset.
MIN_BEFORE_FRACTION = 0.1
#: The shape fitted to the ambient reading alone must be within this share of the difference's
#: fitted size, and the inlet's below it.
OWN_AGREEMENT = 0.5
#: Onset grid of the difference's fit, samples (then every sample near the best).
ONSET_STEP = 5


def noise_allowance(difference: np.ndarray) -> float:
    r"""What the readings' own noise adds to the largest excursion of their difference, K: the
    largest of :math:`N` independent normal values of standard deviation :math:`\sigma` is about
    :math:`\sigma\sqrt{2\ln N}`, with :math:`\sigma` the difference's noise from its second
    differences (:func:`~genthermal.diagnose.search.noise_std`; 0 for readings logged without noise)."""
    from .search import noise_std

    sigma = noise_std(np.asarray(difference, float)[None, :])
    if not np.isfinite(sigma):
        return 0.0
    return float(sigma * math.sqrt(2.0 * math.log(max(difference.size, 2))))


def _shape(kind: str, onset: int, elapsed_s: np.ndarray) -> np.ndarray:
    after = np.arange(elapsed_s.size) >= onset
    if kind == "bias":
        return after.astype(float)
    return after * (elapsed_s - elapsed_s[onset]) / 3600.0


def _fit_on(signal: np.ndarray, shape: np.ndarray) -> tuple[float, float, np.ndarray]:
    """Least squares of ``signal`` on an offset and ``shape``: (size, offset, what is left)."""
    design = np.column_stack([np.ones_like(shape), shape])
    coefficients, *_ = np.linalg.lstsq(design, signal, rcond=None)
    return float(coefficients[1]), float(coefficients[0]), signal - design @ coefficients


def fit_difference(difference, elapsed_s) -> tuple[str, int, float, float, np.ndarray]:
    """The bias or drift from an onset that best fits ``difference`` (K, (N,)) over an offset.

    Returns
    -------
    (kind, onset_index, value, offset_K, left_K)
        ``value`` in K (bias) or K/h (drift); ``left_K`` what the fit leaves, (N,).
    """
    difference, elapsed_s = np.asarray(difference, float), np.asarray(elapsed_s, float)
    n = difference.size
    first = max(1, int(MIN_BEFORE_FRACTION * n))

    def rss(kind, onset):
        _, _, left = _fit_on(difference, _shape(kind, onset, elapsed_s))
        return float(left @ left)

    best = None
    for kind in ("bias", "drift"):
        coarse = {o: rss(kind, o) for o in range(first, n - 2, ONSET_STEP)}
        if not coarse:
            continue
        centre = min(coarse, key=coarse.get)
        near = {o: rss(kind, o) for o in range(max(first, centre - ONSET_STEP), min(n - 2, centre + ONSET_STEP + 1))}
        results = {**coarse, **near}
        onset = min(results, key=results.get)
        if best is None or results[onset] < best[0]:
            best = (results[onset], kind, onset)
    if best is None:
        return "bias", n, 0.0, 0.0, np.zeros(n)
    _, kind, onset = best
    value, offset, left = _fit_on(difference, _shape(kind, onset, elapsed_s))
    return kind, onset, value, offset, left


def machine_follows(frame, response: np.ndarray, value: float, onset: int, noise: float) -> float:
    r"""How much better the outputs fit "the input really changed" than "the reading is wrong".

    Parameters
    ----------
    frame : CalibratedFrame
        The record's residual (measured minus the model driven by the logged input) with the
        calibration nuisance projected off (:class:`~genthermal.diagnose.calibrated_screen.CalibratedFrame`).
    response : numpy.ndarray
        (n_outputs, N) the outputs' response to a unit error of the input from the first sample
        (K per K for a bias, per K/h for a drift).
    value : float
        The error's size (K or K/h).
    onset : int
    noise : float
        Sensor noise standard deviation, K.

    Returns
    -------
    float
        :math:`(RSS_{sensor} - RSS_{real})/\sigma^2 = \lVert P_\perp s\rVert^2 (v^2 - 2 v \hat v)/\sigma^2`
        with :math:`s` the shape the error leaves (the response from the onset, negated) and
        :math:`\hat v` its least-squares size: positive when the outputs followed the logged reading.
    """
    shape = np.zeros_like(response)
    shape[:, onset:] = -response[:, :response.shape[1] - onset]
    projected = float(np.linalg.norm(frame.project(shape)))
    if not projected > 0.0:
        return 0.0
    _, sizes = frame.fit([shape])
    return projected ** 2 * (value * value - 2.0 * value * float(sizes[0])) / noise ** 2


def screen_ambient_against_inlet(inputs, ambient: str, inlet: str, elapsed_s, dt_s: float, frame_factory,
                                 step_response: np.ndarray, noise: float) -> SensorHypothesis | None:
    """The ambient sensor whose reading left the inlet reading of the same air (module docstring).

    Parameters
    ----------
    inputs : pandas.DataFrame
        The record's inputs on the diagnosis grid (logged readings).
    ambient, inlet : str
        Input columns of the ambient and the coolant inlet.
    elapsed_s : numpy.ndarray
        Time from the start, s.
    dt_s : float
    frame_factory : callable
        ``frame_factory()`` → the record's :class:`~genthermal.diagnose.calibrated_screen.CalibratedFrame`
        (called only when tests 1-3 pass: it costs a calibration's sensitivities).
    step_response : numpy.ndarray
        (n_outputs, N) response of the outputs to a 1-K step of the ambient at the first sample
        (:func:`~genthermal.diagnose.input_sensors.input_step_response`).
    noise : float
        Sensor noise, K.

    Returns
    -------
    SensorHypothesis or None
        ``evidence`` ``"input"``, ``signal`` the fitted error of the ambient reading, K.
    """
    if ambient not in inputs or inlet not in inputs or not (noise > 0):
        return None
    read_ambient, read_inlet = inputs[ambient].to_numpy(float), inputs[inlet].to_numpy(float)
    elapsed_s = np.asarray(elapsed_s, float)
    if not (np.isfinite(read_ambient).all() and np.isfinite(read_inlet).all()) or read_ambient.size < 20:
        return None
    difference = read_ambient - read_inlet
    kind, onset, value, _, left = fit_difference(difference, elapsed_s)
    if onset >= difference.size:
        return None
    before = difference[:onset]
    tolerance = SHARED_AIR_TOLERANCE_K + noise_allowance(difference)
    same_air = before.size >= MIN_BEFORE_FRACTION * difference.size and \
        abs(float(np.mean(before))) <= SHARED_AIR_TOLERANCE_K and \
        float(np.max(np.abs(before - np.mean(before)))) <= tolerance
    change = abs(value) * (1.0 if kind == "bias" else (elapsed_s[-1] - elapsed_s[onset]) / 3600.0)
    explained = float(np.max(np.abs(left))) <= tolerance
    if not (same_air and change >= MIN_CHANGE_K and explained):
        return None
    shape = _shape(kind, onset, elapsed_s)
    own, _, _ = _fit_on(read_ambient, shape)
    other, _, _ = _fit_on(read_inlet, shape)
    if abs(own - value) > OWN_AGREEMENT * abs(value) or abs(other) >= OWN_AGREEMENT * abs(value):
        return None
    response = step_response if kind == "bias" else np.cumsum(step_response, axis=1) * dt_s / 3600.0
    followed = machine_follows(frame_factory(), response, value, onset, noise)
    if followed > PREFERENCE_BIC:
        return None
    fault = SensorFault(ambient, kind, float(value), float(elapsed_s[onset]))
    unit = "K" if kind == "bias" else "K/h"
    return SensorHypothesis(fault, int(onset), float("nan"), float("nan"), -change * change / noise ** 2, "input",
                            value * shape,
                            f"the {ambient} reading left the {inlet} reading of the same air by {value:+.2f} {unit} "
                            f"(they agreed within {SHARED_AIR_TOLERANCE_K} K before; the {inlet} reading moved "
                            f"{other:+.2f} {unit}); the outputs favour the real change by {followed:.1f} σ² "
                            f"(a claim needs below {PREFERENCE_BIC:.0f})",
                            columns=(ambient,), output="")


def minimal_detectable_error(frame_factory, step_response: np.ndarray, look_alike: np.ndarray | None, onset: int,
                             noise: float, n_samples: int) -> float:
    r"""The smallest ambient bias from ``onset`` the outputs could tell from a frame cooling change.

    Parameters
    ----------
    frame_factory : callable
        ``frame_factory(extra_terms)`` → :class:`~genthermal.diagnose.calibrated_screen.CalibratedFrame`
        with the calibration nuisance and ``extra_terms`` (list of (n_outputs, N)) projected off.
    step_response : numpy.ndarray
        (n_outputs, N) response to a 1-K ambient step at the first sample.
    look_alike : numpy.ndarray or None
        (n_outputs, N) the frame cooling change's response from the same onset (None: none in the
        search).
    onset : int
    noise : float
        Sensor noise, K.
    n_samples : int
        Samples of the stacked record (the BIC's :math:`N`).

    Returns
    -------
    float
        :math:`\sigma\sqrt{\Delta_{min}}/\lVert P_\perp s\rVert`, K, with :math:`\Delta_{min} =`
        :data:`PREFERENCE_BIC` :math:`+ 2\ln N` (beat the look-alike by the preference after
        paying for size and onset) and :math:`P_\perp` the projection off the nuisance and the
        look-alike; inf when the shape lies in their span.
    """
    shape = np.zeros_like(step_response)
    shape[:, onset:] = -step_response[:, :step_response.shape[1] - onset]
    frame = frame_factory([] if look_alike is None else [look_alike])
    projected = float(np.linalg.norm(frame.project(shape)))
    if not projected > 1e-12 or not (noise > 0):
        return math.inf
    return noise * math.sqrt(PREFERENCE_BIC + 2 * math.log(max(n_samples, 2))) / projected
