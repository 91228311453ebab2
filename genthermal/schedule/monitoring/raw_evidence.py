"""What a claimed sensor fault must show in the raw record, where no heat flow can imitate it
(the check the sensor watch runs before it believes a sensor fault). Main objects:
:class:`RawEvidenceSettings`, :func:`unsupported`. Method: docs/guide/flight-methods.md.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ...diagnose.search import noise_std
from ...diagnose.sensor_faults import MIN_NOISE_FACTOR
from ...errors import InputError


@dataclasses.dataclass(frozen=True)
class RawEvidenceSettings:
    """What the raw record must show for a claimed sensor fault (module docstring).

    Attributes
    ----------
    step_window_s : float
        Half-width of the local fit around a candidate step, s. 60 s (six 10-s samples, one fit
        step): long enough to tell a step from noise (an injected 4-K bias gives z 29-47), short
        enough that a heat flow's curve is an offset, a slope and a slope change in it.
    onset_tolerance_s : float
        Steps are looked for this close to the fitted onset, s: one management cycle (300 s); the
        check's onsets lie on the 60-s fit grid (injected ±4 K biases were fitted 10 s after
        their step).
    step_min_sigma : float
        Smallest step in noise standard deviations (:math:`z`). 5: the largest :math:`z` of the
        iron readings (which no load step moves within a sample) over the whole records of the
        seven grid flights and the 13 ``bench_sensor_flights`` flights was 3.7; a 1-K iron bias at
        the thesis noise (0.11 K) gives about 6.
    step_min_share : float
        Smallest raw step, as a share of the claimed bias (or the gain times the reading), with the
        same sign. 0.5: midway between the false biases of the grid (at most 0.23) and the
        injected ones (at least 0.96).
    step_min_rate_factor : float
        ... and at least this many times the node's change in one sample from heat there (the
        larger local slope). 2: a unit switched on heats its winding by about 1 K a sample, which
        the local fit reads partly as a step (1.4 K at grid case 52's switch-on, 1.6 K on a
        45-K, 400-s first-order heating); a bias is a jump several samples' heat large.
    min_samples : int
        Raw samples needed on each side of the onset for the noise comparison (30: 5 min at the
        10-s step; the robust scale is then known to about 15 %); with fewer, no noise claim.
    noise_min_factor : float
        Smallest ratio of the raw noise after the onset to that before it: the factor a noise claim
        needs (:data:`~genthermal.diagnose.sensor_faults.MIN_NOISE_FACTOR`).
    stuck_max_spread : float
        Largest standard deviation of the raw reading after a claimed stuck onset, in units of its
        noise before (:func:`stuck_spread`). A held reading has none, or its noise alone (about 1
        with :attr:`min_samples` samples or more); 2 leaves room for a noise estimate off by half.
        Measured: the live winding reading of grid case 37's stray-loss unit, fitted stuck at
        67.64 °C from 0.74 h once the biases were refused, moved by 9.2.
    """

    step_window_s: float = 60.0
    onset_tolerance_s: float = 300.0
    step_min_sigma: float = 5.0
    step_min_share: float = 0.5
    step_min_rate_factor: float = 2.0
    min_samples: int = 30
    noise_min_factor: float = MIN_NOISE_FACTOR
    stuck_max_spread: float = 2.0

    def __post_init__(self):
        for name in ("step_window_s", "onset_tolerance_s", "step_min_sigma", "step_min_share", "step_min_rate_factor",
                     "noise_min_factor",
                     "stuck_max_spread"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not (math.isfinite(value)
                                                                                      and value > 0):
                raise InputError(f"sensor_watch.raw_evidence.{name}", value, "must be a finite number > 0")
        if self.noise_min_factor <= 1.0:
            raise InputError("sensor_watch.raw_evidence.noise_min_factor", self.noise_min_factor,
                             "must be > 1 (a ratio of noise standard deviations that grew)")
        if isinstance(self.min_samples, bool) or not isinstance(self.min_samples, int) or self.min_samples < 3:
            raise InputError("sensor_watch.raw_evidence.min_samples", self.min_samples, "must be a whole number >= 3")


@dataclasses.dataclass(frozen=True)
class RawStep:
    """The largest step of a raw reading near an onset.

    Attributes
    ----------
    value_K : float
        Its size, K (0 when none could be fitted).
    at_s : float
        Time of the first sample after it, s (NaN when none).
    z : float
        Its size in noise standard deviations.
    fastest_K : float
        The larger of the local slopes before and after it, K per sample: how far heat moved the
        node in one sample there.
    """

    value_K: float
    at_s: float
    z: float
    fastest_K: float = 0.0


def step_near(times_s, reading, onset_s: float, settings: RawEvidenceSettings = RawEvidenceSettings()) -> RawStep:
    """The largest step of ``reading`` (°C at ``times_s``, s, a uniform step) at a sample within
    ``settings.onset_tolerance_s`` of ``onset_s`` (s), over a local offset, slope and slope change
    (module docstring); the noise is estimated on the reading before that stretch (the whole
    reading when that is too short)."""
    times, values = np.asarray(times_s, dtype=float), np.asarray(reading, dtype=float)
    none = RawStep(0.0, math.nan, 0.0)
    if times.size < 3:
        return none
    step_s = float(np.median(np.diff(times)))
    width = max(2, int(round(settings.step_window_s / step_s)))
    before = values[times < onset_s - settings.onset_tolerance_s - settings.step_window_s]
    noise = noise_std(before) if np.isfinite(before).sum() >= settings.min_samples + 2 else noise_std(values)
    if not (noise > 0):
        return none
    local = np.arange(-width, width) / width
    after = (local >= 0).astype(float)
    heat = np.column_stack([np.ones(2 * width), local, local * after])
    with_step = np.column_stack([heat, after])
    best = none
    for j in np.flatnonzero(np.abs(times - onset_s) <= settings.onset_tolerance_s):
        if j < width or j + width > values.size:
            continue
        segment = values[j - width:j + width]
        ok = np.isfinite(segment)
        if ok.sum() < with_step.shape[1] + 3 or not ok[:width].any() or not ok[width:].any():
            continue
        rss = []
        for design in (heat, with_step):
            fitted, *_ = np.linalg.lstsq(design[ok], segment[ok], rcond=None)
            rss.append(float(np.sum((segment[ok] - design[ok] @ fitted) ** 2)))
        z = math.sqrt(max(rss[0] - rss[1], 0.0)) / noise
        if z > best.z:  # slopes per unit of local time (width samples) → per sample
            fastest = max(abs(fitted[1]), abs(fitted[1] + fitted[2])) / width
            best = RawStep(float(fitted[-1]), float(times[j]), z, float(fastest))
    return best


def noise_factor(times_s, reading, onset_s: float, settings: RawEvidenceSettings = RawEvidenceSettings()) -> float:
    """Raw noise after ``onset_s`` (s) over raw noise before it
    (:func:`~genthermal.diagnose.search.noise_std`); NaN when a
    side has fewer than ``settings.min_samples`` finite samples."""
    times, values = np.asarray(times_s, dtype=float), np.asarray(reading, dtype=float)
    sides = [values[times < onset_s], values[times >= onset_s]]
    if any(np.isfinite(side).sum() < settings.min_samples for side in sides):
        return math.nan
    before, after = (noise_std(side) for side in sides)
    return after / before if before > 0 else math.nan


def stuck_spread(times_s, reading, onset_s: float, settings: RawEvidenceSettings = RawEvidenceSettings()) -> float:
    """Standard deviation of the raw reading from ``onset_s`` (s) on, over its noise before
    (:func:`~genthermal.diagnose.search.noise_std`): about 1 for a held reading with noise, 0
    without; NaN when a side has fewer than ``settings.min_samples`` finite samples."""
    times, values = np.asarray(times_s, dtype=float), np.asarray(reading, dtype=float)
    before, after = values[times < onset_s], values[times >= onset_s]
    before, after = before[np.isfinite(before)], after[np.isfinite(after)]
    if before.size < settings.min_samples or after.size < settings.min_samples:
        return math.nan
    noise = noise_std(before)
    return float(np.std(after)) / noise if noise > 0 else math.nan


def unsupported(fault, times_s, reading, settings: RawEvidenceSettings = RawEvidenceSettings()) -> str | None:
    """Why the raw reading of ``fault``'s sensor (°C at ``times_s``, s since the mission start, as
    the fault's onset) does not show ``fault`` (a :class:`~genthermal.sensor_faults.SensorFault`),
    or None when it does or the kind has no raw signature here (drift: module docstring)."""
    if fault.kind in ("bias", "gain"):
        times, values = np.asarray(times_s, dtype=float), np.asarray(reading, dtype=float)
        if fault.kind == "bias":
            expected, what = fault.value, f"a {fault.value:+.2f} K bias"
        else:
            level = values[(times < fault.onset_s) & np.isfinite(values)]
            expected = fault.value * (float(level[-1]) if level.size else math.nan)
            what = f"a gain error of {fault.value:+.3f} ({expected:+.2f} K)"
        step = step_near(times, values, fault.onset_s, settings)
        if step.z >= settings.step_min_sigma and step.value_K * expected > 0 \
                and abs(step.value_K) >= settings.step_min_share * abs(expected) \
                and abs(step.value_K) >= settings.step_min_rate_factor * step.fastest_K:
            return None
        return (f"{fault.sensor} {fault.kind} refused: {what} from {fault.onset_s / 3600.0:.2f} h, but the raw "
                f"record's largest step within {settings.onset_tolerance_s:g} s of it is {step.value_K:+.2f} K "
                f"(z {step.z:.1f}) where heat moved it {step.fastest_K:.2f} K a sample: a sensor steps at its "
                "onset, heat moves a node at a finite rate")
    if fault.kind == "stuck":
        spread = stuck_spread(times_s, reading, fault.onset_s, settings)
        if spread <= settings.stuck_max_spread:
            return None
        return (f"{fault.sensor} stuck refused: stuck at {fault.value:.2f} °C from {fault.onset_s / 3600.0:.2f} h "
                f"on the fit grid, but the raw reading since moves by {spread:.1f} noise standard deviations (a "
                f"held reading, even with its noise, by at most {settings.stuck_max_spread:g})")
    if fault.kind == "noise":
        factor = noise_factor(times_s, reading, fault.onset_s, settings)
        if factor >= settings.noise_min_factor:
            return None
        if not math.isfinite(factor):
            return (f"{fault.sensor} noise refused: fewer than {settings.min_samples} raw samples on a side of "
                    f"its onset at {fault.onset_s / 3600.0:.2f} h to compare the noise on")
        return (f"{fault.sensor} noise refused: {fault.value:.1f}× noisier on the fit grid from "
                f"{fault.onset_s / 3600.0:.2f} h, but the raw sample-to-sample noise changed by "
                f"{factor:.2f}× (a noisier sensor needs {settings.noise_min_factor:g}×): the grid's was a heat "
                "flow's curve")
    return None
