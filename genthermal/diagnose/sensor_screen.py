"""The sensor-fault side of a diagnosis: screen the record, compete with the physical effects, correct.

:class:`SensorScreen` runs, for :func:`genthermal.diagnose.discover.diagnose` with
``sensor_faults=True``: the model-free screens before the search; after the first round, the best
single-sensor or input-sensor fault against the best physical effect; on a record searched blind,
the onset signatures, the shared-air test and the calibrated screen. A claimed fault is corrected
and the round run again. Method: ``docs/guide/methods.md``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..machines.interface import Role
from .compare import MeasuredSeries, as_measurements
from .calibrated_screen import (CalibratedFrame, best_physical, calibration_sensitivities, input_hypotheses,
                                misfit_from_start, on_series_grid, sensor_hypotheses)
from .input_readings import screen_input_readings
from .sensor_plausibility import noise_refusal, refusal
from .input_sensors import corrected_inputs, input_sensors, input_step_response, screen_inputs
from .onset_signatures import inertial_outputs, screen_frozen, screen_input_jumps, screen_jumps
from .shared_air import minimal_detectable_error, screen_ambient_against_inlet
from .sensor_faults import (PREFERENCE_BIC, SensorHypothesis, corrected_readings, outputs_from,
                            screen_against_model, screen_noise, screen_redundant, sensor_columns,
                            sensor_groups)


def record_readings(data, series: MeasuredSeries, interface) -> dict:
    """Every sensor column of ``data`` (schema of the machine ``interface``) on the grid of
    ``series`` (linear interpolation over the finite samples; NaN outside them). A
    :class:`MeasuredSeries` gives its outputs as sensors."""
    if isinstance(data, MeasuredSeries):
        return {name: np.array(row, dtype=float) for name, row in zip(interface.output_names, data.outputs)}
    measurements = as_measurements(data, interface)
    time_s = measurements.time_s
    readings = {}
    for output, columns in sensor_columns(interface).items():
        for name in columns:
            if name not in measurements.frame:
                continue
            values = measurements.frame[name].to_numpy(dtype=float)
            ok = np.isfinite(values)
            if ok.sum() < 2:
                continue
            on_grid = np.interp(series.time_s, time_s[ok], values[ok], left=np.nan, right=np.nan)
            exact = np.searchsorted(time_s, series.time_s).clip(0, time_s.size - 1)
            matched = np.isclose(time_s[exact], series.time_s)
            on_grid[matched & ~np.isfinite(values[exact])] = np.nan
            readings[name] = on_grid
    return readings


def corrected_record(measurements, series: MeasuredSeries, hypotheses):
    """``measurements`` (MeasurementData) with the faults of ``hypotheses`` (fitted on the grid of
    ``series``) removed from their record columns: the fitted signal subtracted (interpolated to
    the record's times), or the column NaN from the onset for a stuck or noisy sensor of an
    output that has other sensors (:func:`~genthermal.diagnose.sensor_faults.corrected_readings`)."""
    frame = measurements.frame.copy()
    time_s = measurements.time_s
    for hypothesis in hypotheses:
        drop = hypothesis.drops_reading
        onset_s = float(series.time_s[0]) + hypothesis.fault.onset_s
        for column in (c for c in hypothesis.columns if c in frame):
            if drop:
                frame.loc[time_s >= onset_s, column] = np.nan
            elif hypothesis.fault.kind != "noise":
                frame[column] = frame[column].to_numpy(float) - np.interp(time_s, series.time_s, hypothesis.signal)
    return dataclasses.replace(measurements, frame=frame)


class SensorScreen:
    """Sensor faults of one record (module docstring).

    Parameters
    ----------
    data : MeasurementData, pandas.DataFrame, path or MeasuredSeries
        The record as given to diagnose.
    series : MeasuredSeries
        Its model outputs on the diagnosis grid.
    interface : MachineInterface
        The machine's interface (sensor schema, phase currents).
    prior : sequence of SensorHypothesis
        Faults claimed before (on the model's own sensors, before a sensor view split them:
        :func:`corrected_record`); ``data`` is already corrected for them.

    Attributes
    ----------
    found : list of SensorHypothesis
        Sensor faults claimed so far.
    alternative : SensorHypothesis or None
        The best single-sensor fault tried against the model, claimed or not.
    limits : dict
        Input sensor → the smallest error of it this record could tell from its physical
        look-alike, K (the ambient against a frame cooling change), when none was claimed.
    """

    def __init__(self, data, series: MeasuredSeries, interface, prior=()):
        self.output_names = list(interface.output_names)
        self.columns = sensor_columns(interface)
        self.series = series
        self.elapsed_s = series.time_s - series.time_s[0]
        self.readings = record_readings(data, series, interface)
        self.found: list[SensorHypothesis] = list(prior)
        self.prior = tuple(prior)
        self.alternative: SensorHypothesis | None = None
        #: Input → the smallest error of it the record could tell from its physical look-alike, K
        #: (:meth:`_ambient_limit`).
        self.limits: dict[str, float] = {}
        #: Input → what its limit was measured against (:meth:`limit_text`).
        self.limit_look_alikes: dict[str, str] = {}
        self._frame_for, self._frame = None, None  # the search the calibrated frame is of, and the frame
        self.model_round_done = False
        self.interface = interface
        #: Error model of the calibrated model and its criterion (:meth:`use_error_model`).
        self.error_model, self.criterion = None, None
        self._residuals = None  # output -> measured minus model of the search the faults are fitted on
        self._predicted = None  # output -> the model's prediction of that search
        #: (SensorHypothesis, reason) of the faults fitted but refused as implausible.
        self.refused: list = []
        phases = interface.generator.phase_inputs if interface.has_role(Role.GENERATOR) else ()
        self.found += screen_redundant(self.readings, series.inputs, self.elapsed_s, series.dt_s, self.columns, phases)
        corrected = corrected_readings(self.readings, self.found[len(self.prior):])
        groups = sensor_groups(corrected, self.columns)
        for noisy in screen_noise(corrected, self.elapsed_s, self.columns):
            if noisy.fault.sensor in {f.fault.sensor for f in self.found}:
                continue
            reason = noise_refusal(noisy, corrected, groups)
            if reason:
                self.refused.append((noisy, reason))
            else:
                self.found.append(noisy)
        self.found += screen_input_readings(series.inputs, input_sensors(interface), self.elapsed_s)

    def use_error_model(self, error_model, criterion) -> None:
        """Score the faults fitted against the model with ``criterion`` (a
        :class:`~genthermal.diagnose.error_model.WhitenedBIC`: effective samples) and refuse the
        implausible ones against the discrepancy floors of ``error_model``
        (:mod:`~genthermal.diagnose.sensor_plausibility`); None: white noise, bounds only."""
        self.error_model = error_model
        self.criterion = criterion if hasattr(criterion, "scale") else None

    def _rescaled(self, delta_white: float, n: int) -> float:
        """A white-noise ΔBIC of a two-parameter fault over ``n`` samples on effective samples."""
        return delta_white if self.criterion is None else self.criterion.scale(delta_white, n, 2)

    def _admit(self, hypothesis) -> bool:
        """True when ``hypothesis`` is a plausible claim; else it is kept in :attr:`refused`."""
        floors = {} if self.error_model is None else {s.sensor: s.level_K for s in self.error_model.sensors}
        pooled = None if self.error_model is None else self.error_model.floor_K
        readings = dict(self.readings)
        for name in self.series.inputs.columns:
            if name != "time_s":
                readings.setdefault(name, self.series.inputs[name].to_numpy(float))
        # the columns of an output read by several distinct sensors (the phase windings; copies of
        # one reading, as a flight's record logs the winding, are one sensor)
        phases = tuple(c for group in sensor_groups(self.readings, self.columns).values() if len(group) > 1
                       for c in group)
        reason = refusal(hypothesis, readings, self.elapsed_s, floors, pooled,
                         getattr(self.interface, "coolant_input", None), getattr(self.interface, "ambient_input", None),
                         "T_outlet", phases,
                         # other outputs leaving the model at the onset tell a machine change from one
                         # sensor only against the floors of an error model: without one, a plant's
                         # slowly moving misfit reads as such a change
                         self._residuals if self.error_model is not None else None,
                         self.interface.coolant_medium == "room_air", self._predicted)
        if reason:
            self.refused.append((hypothesis, reason))
        return reason is None

    def corrected_series(self) -> MeasuredSeries:
        """The series with the claimed sensor faults removed from its outputs."""
        new = self.found[len(self.prior):]  # the data are already corrected for the prior faults
        if not new:
            return self.series
        outputs = outputs_from(corrected_readings(self.readings, new), self.output_names, self.columns)
        return dataclasses.replace(self.series, outputs=outputs, inputs=corrected_inputs(self.series.inputs, new))

    def against_model(self, search, ranked, noise: float, outputs=None, onsets=None,
                      on_top: bool = False, inputs: bool = True) -> SensorHypothesis | None:
        """Claim the best single-sensor fault if it beats the physical effects (module docstring).

        Parameters
        ----------
        search : EffectSearch
            The first round's search (its ``predicted_before`` is the model fitted to the record).
        ranked : list of Candidate
            The physical effects of that round, best first.
        noise : float
            Estimated sensor noise, K.
        outputs, onsets : optional
            Restrict the faults tried to the sensors of these outputs and to these onset samples
            (:func:`~genthermal.diagnose.sensor_faults.screen_against_model`).
        on_top : bool
            Also claim a fault that, fitted on top of the best physical effect, passes the four
            tests against that effect alone. Only where a detector has already said which sensor
            moved and when (in flight): on a record searched blind, a second physical effect that
            moves one sensor most (an iron loss after a blockage) passes it too.
        inputs : bool
            Also fit the faults of the input sensors (coolant inlet, ambient:
            :mod:`~genthermal.diagnose.input_sensors`) when every output is looked at; the
            better of the two kinds is the candidate.
        """
        from .discover import passes_tests

        self.model_round_done = True
        self._residuals = dict(zip(search.output_names, search.series.outputs - search.predicted_before))
        self._predicted = dict(zip(search.output_names, search.predicted_before))
        exclude = {h.fault.sensor for h in self.found}
        candidate = screen_against_model(search.series.outputs, search.predicted_before, self.readings,
                                         self.elapsed_s, self.output_names, self.columns, exclude,
                                         outputs, onsets)
        if inputs and (outputs is None or set(outputs) >= set(self.output_names)):
            through_input = screen_inputs(search.viewed(search.model), search.series,
                                          search.series.outputs - search.predicted_before, self.output_names, onsets)
            if through_input is not None and (candidate is None or through_input.delta_bic < candidate.delta_bic):
                candidate = through_input
        self.alternative = candidate
        if candidate is None:
            return None
        candidate.delta_bic = self._rescaled(candidate.delta_bic, search.n_valid)
        best_physical = ranked[0] if ranked else None
        alone = passes_tests(candidate.rmse_before, candidate.rmse_after, candidate.delta_bic, noise)
        if best_physical is None:
            claimed = alone
        else:
            candidate.alternative = f"{best_physical.effect} ΔBIC {best_physical.delta_bic:.0f}"
            claimed = alone and candidate.delta_bic < best_physical.delta_bic - PREFERENCE_BIC
            # the record may hold a machine effect (or model error) and a sensor fault
            if not claimed and on_top and candidate.evidence != "input":
                on_top = screen_against_model(search.series.outputs, best_physical.predicted, self.readings,
                                              self.elapsed_s, self.output_names, self.columns, exclude,
                                              outputs, onsets)
                if on_top is not None:
                    on_top.delta_bic = self._rescaled(on_top.delta_bic, search.n_valid)
                if on_top is not None and on_top.fault.sensor == candidate.fault.sensor and passes_tests(
                        on_top.rmse_before, on_top.rmse_after, on_top.delta_bic, noise):
                    on_top.alternative = (f"on top of {best_physical.effect}: RMSE {on_top.rmse_before:.3f} → "
                                          f"{on_top.rmse_after:.3f} K, ΔBIC {on_top.delta_bic:.0f}")
                    candidate, claimed = on_top, True
        if claimed and not self._admit(candidate):
            claimed = False
        if not claimed:
            return self._onset_signatures(search, ranked, noise) if outputs is None and onsets is None else None
        self.found.append(candidate)
        return candidate

    def _onset_signatures(self, search, ranked, noise: float) -> SensorHypothesis | None:
        """Claim the sensor faults told by their onset alone (a reading that froze, a jump of a
        sensor with thermal inertia, an input's jump the machine did not follow:
        :mod:`~genthermal.diagnose.onset_signatures`), when the whole-record comparison did not
        claim one; the first claimed, or None."""
        model = search.viewed(search.model)
        inputs = search.series.inputs
        exclude = {h.fault.sensor for h in self.found}
        claimed = screen_frozen(self.readings, self.elapsed_s, self.columns, exclude)
        exclude |= {h.fault.sensor for h in claimed}
        measured, predicted = search.series.outputs, search.predicted_before
        responses = {name: input_step_response(model, inputs, name, self.output_names)
                     for name in input_sensors(model.spec.interface)}
        coolant = model.spec.interface.coolant_input
        inertial = inertial_outputs(responses[coolant], self.output_names) if coolant in responses else set()
        jump = screen_jumps(measured, predicted, self.readings, search.series.dt_s, self.elapsed_s,
                            self.output_names, self.columns, inertial, noise, exclude)
        claimed += [jump] if jump is not None else []
        through_input = screen_input_jumps(inputs, measured - predicted, responses, search.series.dt_s,
                                           self.elapsed_s, noise)
        claimed += [through_input] if through_input is not None else []
        interface = model.spec.interface
        ambient = getattr(interface, "ambient_input", None)
        # the inlet is the ambient's redundant reading only where both read the room's air
        if interface.coolant_medium == "room_air" and ambient in responses and coolant in responses and \
                ambient not in {h.fault.sensor for h in claimed}:
            left_inlet = screen_ambient_against_inlet(inputs, ambient, coolant, self.elapsed_s, search.series.dt_s,
                                                      lambda: self._calibrated_frame(search, ranked, responses)[0],
                                                      responses[ambient], noise)
            claimed += [left_inlet] if left_inlet is not None else []
        claimed = [h for h in claimed if self._admit(h)]
        if not claimed:
            calibrated = self._calibrated(search, ranked, noise, responses, exclude)
            claimed += [calibrated] if calibrated is not None and self._admit(calibrated) else []
        self.found += claimed
        return claimed[0] if claimed else None

    def _calibrated(self, search, ranked, noise: float, responses: dict, exclude) -> SensorHypothesis | None:
        """The best sensor or input fault fitted jointly with a calibration of the model, if it
        beats the physical effects fitted the same way
        (:mod:`~genthermal.diagnose.calibrated_screen`)."""
        from .discover import passes_tests

        model = search.viewed(search.model)
        frame, sensitivities, from_start = self._calibrated_frame(search, ranked, responses)
        hypotheses = sensor_hypotheses(frame, self.readings, self.elapsed_s, self.output_names, self.columns,
                                       exclude)
        hypotheses += input_hypotheses(frame, responses, self.elapsed_s, search.series.dt_s, search.series.inputs)
        if not hypotheses:
            return None
        best = min(hypotheses, key=lambda h: h.delta_bic)
        physical_bic, physical = best_physical(frame, ranked, search.coarse.time_s, search.series.time_s)
        best.delta_bic = self._rescaled(best.delta_bic, frame.n)
        physical_bic = self._rescaled(physical_bic, frame.n) if math.isfinite(physical_bic) else physical_bic
        best.alternative = f"calibrated: {physical or 'no physical effect'} ΔBIC {physical_bic:.0f}"
        claimed = passes_tests(best.rmse_before, best.rmse_after, best.delta_bic, noise) and \
            best.delta_bic < physical_bic - PREFERENCE_BIC
        ambient = getattr(model.spec.interface, "ambient_input", None)
        if ambient in responses and not (claimed and best.fault.sensor == ambient):
            self.limits[ambient] = self._ambient_limit(frame, sensitivities, from_start, responses[ambient], ranked,
                                                       search, noise)
        return best if claimed else None

    def _calibrated_frame(self, search, ranked, responses: dict):
        """The record's residual with the calibration nuisance projected off, and its terms:
        (CalibratedFrame, sensitivities, misfits from the start); computed once per search."""
        from .discover import DEFAULT_BASELINE_PARAMETERS

        if self._frame_for is not search:
            model = search.viewed(search.model)
            sensitivities = calibration_sensitivities(model, search.series.inputs, self.output_names,
                                                      DEFAULT_BASELINE_PARAMETERS)
            from_start = misfit_from_start(responses, ranked, search.coarse.time_s, search.series.time_s)
            frame = CalibratedFrame(search.series.outputs - search.predicted_before, [*sensitivities, *from_start])
            self._frame_for, self._frame = search, (frame, sensitivities, from_start)
        return self._frame

    def _ambient_limit(self, frame, sensitivities, from_start, step_response, ranked, search, noise) -> float:
        """The smallest ambient bias from mid-record the calibrated comparison could tell from a
        frame cooling change on this record, K (:func:`~genthermal.diagnose.shared_air.minimal_detectable_error`)."""
        n = self.elapsed_s.size
        onset = n // 2
        look_alike = None
        for candidate in ranked:
            responses = getattr(candidate, "onset_responses", None)
            if candidate.effect == "frame_cooling_change" and responses is not None and responses.onsets.size:
                coarse_onset = int(np.argmin(np.abs(search.coarse.time_s[responses.onsets] - search.series.time_s[onset])))
                look_alike = on_series_grid(responses.changes[coarse_onset], search.coarse.time_s, search.series.time_s)
        residual = search.series.outputs - search.predicted_before
        self.limit_look_alikes[search.viewed(search.model).spec.interface.ambient_input] = "a frame cooling change" if look_alike is not None else \
            "the calibration misfit alone (no frame cooling change was fitted to compare with)"
        return minimal_detectable_error(lambda extra: CalibratedFrame(residual, [*sensitivities, *from_start, *extra]),
                                        step_response, look_alike, onset, noise, frame.n)

    def text(self, machine_verdict: str) -> str:
        """Plain language: ``"the T_iron sensor drifts by +1.40 K/h from 1.60 h; the machine is healthy"``."""
        if not self.found:
            return ""
        faults = "; ".join(h.fault.describe() for h in self.found)
        machine = ("the machine is healthy" if machine_verdict == "none"
                   else f"on the corrected record the machine shows {machine_verdict}")
        return f"Sensor fault: {faults}; {machine}."

    def limit_text(self) -> str:
        """Plain language for :attr:`limits`: ``"an ambient error below 4.2 K cannot be told from
        frame cooling on this record"``."""
        claimed = {h.fault.sensor for h in self.found}
        against = {name: self.limit_look_alikes.get(name, "a frame cooling change") for name in self.limits}
        parts = [f"an error of the {name} sensor below {value:.1f} K cannot be told from {against[name]} on "
                 "this record" if math.isfinite(value) else
                 f"no error of the {name} sensor can be told from {against[name]} on this record"
                 for name, value in self.limits.items() if name not in claimed]
        return ("Limit: " + "; ".join(parts) + ".") if parts else ""

    def to_list(self) -> list:
        """JSON list of the claimed sensor faults."""
        return [h.to_dict() for h in self.found]

    def refused_list(self) -> list:
        """JSON list of the sensor faults fitted but refused, each with its reason."""
        return [{**h.to_dict(), "refused": reason} for h, reason in self.refused]
