"""The onboard load manager: its rule in Python (the reference) and in C on the emulated target.

The rule is written in ``c/manager.h``; :func:`fly_reference` is the same rule, decision for
decision, on the same CasADi functions the C library is generated from (the design model's
discrete ``step`` and the filter's ``kalman_update``). :func:`fly_on_target` builds
``c/manager.c`` with ``c/flight_target.c`` for the Cortex-M4F and flies the same flight under QEMU:
the same true plants (the nonlinear model with the mission's mismatch, and the fault from its
onset), the same measurement noise.

The manager knows no fault model: it sees the fault only through its measurements and the
measured inlet temperature, which it holds over the prediction (thesis 7.3.6).
"""

from __future__ import annotations

import dataclasses
import struct
from pathlib import Path

import numpy as np

from ..codegen import generate_c
from ..design import linear_design_model
from ..errors import InputError
from ..estimation.kalman import KalmanFilter, output_matrices
from ..mission import input_columns
from ..exciter import exciter_line
from ..schedule.flight.manager_settings import DEFAULT_MARGIN_K
from ..schedule.power_system import PowerSystem
from . import toolchain


#: Peak of an empty prediction, °C (``NO_PEAK`` in ``c/manager.c``).
NO_PEAK = -1e300


@dataclasses.dataclass(frozen=True)
class ManagerSettings:
    """The settings of ``gtm_settings_t`` (``c/manager.h``).

    Attributes
    ----------
    profile_A : numpy.ndarray
        Nominal phase current per sample of the mission, A RMS.
    limit_C : float
        Planning limit of the winding, θmax − margin, °C.
    rest_current_A, current_limit_A : float
        Phase current while resting and the highest a generator may carry, A RMS.
    ambient_C : float
    winding_state : int
        State the winding sensor measures.
    cycle_steps, rest_quantum_steps, max_rest_steps : int
        Samples between decisions (default 30: the thesis's 5-minute management cycle, 7.2), samples
        of rest added at a time (default 6: 1 minute, assumed as the rule's "fine step") and most
        rest pending (default 360: 1 h, the ``max_rest_s`` of the closed loop's settings).
    dt_s : float
        Sample time, s.
    field_no_load_A, field_gain : float
        Exciter law ``I_exc = field_no_load_A + field_gain * I`` on the target: the least-squares
        line of the AVR law (:func:`genthermal.exciter.exciter_line`, power factor 0.8 lagging;
        defaults: the default law at its default rating; :func:`blockage_flight` passes the
        machine's generator law at its rated current) over 0 … rated current, so that the C code
        needs no square root per sample.
    """

    profile_A: np.ndarray
    limit_C: float
    rest_current_A: float
    current_limit_A: float
    ambient_C: float
    winding_state: int
    cycle_steps: int = 30
    rest_quantum_steps: int = 6
    max_rest_steps: int = 360
    dt_s: float = 10.0
    field_no_load_A: float = exciter_line()[0]
    field_gain: float = exciter_line()[1]


@dataclasses.dataclass(frozen=True)
class Flight:
    """A closed-loop flight: the plants, the fault and the noise.

    Attributes
    ----------
    healthy_plant, faulty_plant : ThermalModel
        True plant of both generators, and of generator 0 from ``onset_sample`` on.
    onset_sample : int
    inlet_C, inlet_rise_C : float
        Coolant inlet, °C, and the rise of generator 0's inlet from the onset, K.
    sensor_states : tuple of int
        Plant state each sensor (``T_winding``, ``T_iron``) reads.
    noise : numpy.ndarray
        (max_samples, 2 generators, 2 sensors) measurement noise, K.
    """

    healthy_plant: object
    faulty_plant: object
    onset_sample: int
    inlet_C: float
    inlet_rise_C: float
    sensor_states: tuple
    noise: np.ndarray


@dataclasses.dataclass
class FlightRecord:
    """Per sample: the manager's decisions and the temperatures (what ``flight_target.c`` prints).

    Attributes
    ----------
    flags : numpy.ndarray
        (n, 6) resting, decided, rest_remaining (samples), displaced, hot, infeasible.
    currents_A : numpy.ndarray
        (n, 2) phase currents applied over the sample, A RMS.
    plant_winding_C : numpy.ndarray
        (n, 2) true winding temperature at the sample, °C.
    filtered_winding_C : numpy.ndarray
        (n, 2) the filters' winding estimates, °C.
    predicted_peak_C : numpy.ndarray
        (n, 2) winding peaks of the last decision's last prediction, °C.
    instructions : dict
        On the target: ``manager_max`` (longest ``gtm_step``) and ``manager_total``, instructions.
    stack_bytes : int
        On the target: deepest stack used, bytes.
    """

    flags: np.ndarray
    currents_A: np.ndarray
    plant_winding_C: np.ndarray
    filtered_winding_C: np.ndarray
    predicted_peak_C: np.ndarray
    instructions: dict = dataclasses.field(default_factory=dict)
    stack_bytes: int = 0


def sensor_states(model) -> tuple:
    """States the sensors read; the C manager and plant need outputs that are plain node temperatures."""
    C, e = output_matrices(model)
    if np.any(e != 0) or not np.all((C == 0) | (C == 1)) or not np.all(C.sum(axis=1) == 1):
        raise InputError("model outputs", model.output_names, "the onboard manager needs sensors that read one "
                         "node temperature each")
    expected = input_columns(model.spec.interface.generator)[1:]
    if tuple(model.input_names) != expected:
        raise InputError("model inputs", model.input_names, f"the onboard manager expects {expected}")
    return tuple(int(np.argmax(row)) for row in C)


def blockage_flight(system: PowerSystem, rule_margin_K: float = DEFAULT_MARGIN_K, seed: int = 0,
                    spare_samples: int = 720, dt_s: float = 10.0) -> tuple:
    """The manager's model, settings and flight of a two-generator mission with one fault on the
    first generator.

    Parameters
    ----------
    system : PowerSystem
        E.g. ``PowerSystem.from_mission(load_mission("blockage_large"))``.
    rule_margin_K : float
        Back-off below θmax, K.
    seed : int
        Seed of the measurement noise (thesis eq. 6.10 variances).
    spare_samples : int
        Noise samples beyond the mission for the rests.

    Returns
    -------
    design_model : ThermalModel
        The linear design model of the nominal machine (no fault, no mismatch).
    settings : ManagerSettings
    flight : Flight

    Raises
    ------
    InputError
        Not two generators, or not exactly one fault, on the first generator, with an effect.
    """
    faults = system.faults
    if system.n_generators != 2 or len(faults) != 1 or faults[0].generator != 0 or not faults[0].effect:
        raise InputError("generators/faults", f"{system.n_generators} generators, {len(faults)} fault(s)",
                         "the onboard manager flight needs 2 generators and one fault with an effect on the first")
    design = linear_design_model(system.nominal_model)
    generator = system.nominal_model.spec.interface.generator
    profile = system.mission.to_inputs(dt_s, generator)[generator.phase_inputs[0]].to_numpy()[:-1]
    field_no_load_A, field_gain = exciter_line(rated_current_A=system.nominal_model.spec.rated_current_A,
                                               law=generator.exciter_law)
    settings = ManagerSettings(profile, system.limit_C - rule_margin_K, system.rest_current_A,
                               system.current_limit_A, system.mission.T_ambient_C, sensor_states(design)[0], dt_s=dt_s,
                               field_no_load_A=field_no_load_A, field_gain=field_gain)
    healthy, faulty = system.plant_model(0), system.plant_model(0, (0,))
    rng = np.random.default_rng(seed)
    variances = np.asarray(healthy.spec.interface.noise_variances_K2)
    noise = rng.normal(0.0, np.sqrt(variances), (len(profile) + spare_samples, 2, variances.size))
    flight = Flight(healthy, faulty, int(round(faults[0].onset_s / dt_s)), system.mission.T_inlet_C,
                    faults[0].inlet_rise_C, sensor_states(healthy), noise)
    return design, settings, flight


class _Rule:
    """The rule of ``c/manager.c`` on the design model's CasADi functions."""

    def __init__(self, design, settings: ManagerSettings):
        self.s = settings
        self.discrete = design.discretise(settings.dt_s)
        self.kalman = KalmanFilter(design, settings.dt_s).update_function()

    def input(self, current: float, inlet_C: float) -> np.ndarray:
        s = self.s
        return np.array([current, current, current, s.field_no_load_A + s.field_gain * current, inlet_C, s.ambient_C])

    def currents(self, index: int, displaced: bool, hot: int) -> list:
        s, nominal = self.s, float(self.s.profile_A[index])
        if not displaced:
            return [nominal, nominal]
        shift = max(0.0, min(s.current_limit_A - nominal, nominal - s.rest_current_A))
        return [nominal - shift if g == hot else nominal + shift for g in range(2)]

    def peak(self, x0, g, rest, index, displaced, hot, inlet_C, stop_above_C) -> float:
        """Winding peak of the prediction (states after each step), stopping at the first value
        above ``stop_above_C``; :data:`NO_PEAK` for an empty horizon."""
        s = self.s
        U = [self.input(s.rest_current_A, inlet_C)] * rest
        U += [self.input(self.currents(k, displaced, hot)[g], inlet_C) for k in range(index, len(s.profile_A))]
        if not U:
            return NO_PEAK
        trajectory = np.asarray(self.discrete.simulator(len(U))(x0, np.array(U).T))[s.winding_state]
        running = np.maximum.accumulate(trajectory)
        above = np.nonzero(running > stop_above_C)[0]
        return float(running[above[0]] if above.size else running[-1])


def fly_reference(design_model, settings: ManagerSettings, flight: Flight) -> FlightRecord:
    """Fly ``flight`` with the Python rule on ``design_model`` (the manager's model); the record
    ``flight_target.c`` prints, value for value."""
    s = settings
    rule = _Rule(design_model, s)
    steps = {"healthy": flight.healthy_plant.discretise(s.dt_s).step, "faulty": flight.faulty_plant.discretise(s.dt_s).step}
    x_plant = [np.full(flight.healthy_plant.n_states, s.ambient_C) for _ in range(2)]
    x_pred = [np.full(rule.discrete.model.n_states, s.ambient_C) for _ in range(2)]
    peaks = [s.ambient_C, s.ambient_C]
    state = {"index": 0, "rest": 0, "displaced": False, "hot": 0, "infeasible": False}
    rows = []
    for k in range(len(flight.noise)):
        if state["index"] >= len(s.profile_A) and state["rest"] == 0:
            break
        inlet = [flight.inlet_C + (flight.inlet_rise_C if g == 0 and k >= flight.onset_sample else 0.0) for g in range(2)]
        y = [np.array([x_plant[g][i] for i in flight.sensor_states]) + flight.noise[k, g] for g in range(2)]
        filtered = [np.asarray(rule.kalman(x_pred[g], rule.input(0.0, inlet[g]), y[g])[0]).ravel() for g in range(2)]
        decided = k % s.cycle_steps == 0
        if decided:
            peaks = _decide(rule, state, filtered, inlet)
        resting = state["rest"] > 0
        if resting:
            currents = [s.rest_current_A] * 2
            state["rest"] -= 1
        else:
            currents = rule.currents(state["index"], state["displaced"], state["hot"])
            state["index"] += 1
        rows.append(([int(resting), int(decided), state["rest"], int(state["displaced"]), state["hot"],
                      int(state["infeasible"])], currents, [x_plant[g][flight.sensor_states[0]] for g in range(2)],
                     [filtered[g][s.winding_state] for g in range(2)], list(peaks)))
        for g in range(2):
            x_pred[g] = np.asarray(rule.discrete.step(filtered[g], rule.input(currents[g], inlet[g]))).ravel()
            plant = steps["faulty" if g == 0 and k >= flight.onset_sample else "healthy"]
            x_plant[g] = np.asarray(plant(x_plant[g], rule.input(currents[g], inlet[g]))).ravel()
    else:
        raise InputError("flight.noise", len(flight.noise), "too few noise samples for the mission and its rests")
    return FlightRecord(*(np.array([row[i] for row in rows], dtype=float) for i in range(5)))


def _decide(rule: _Rule, state: dict, filtered, inlet) -> list:
    s = rule.s

    def predict(rest, displaced, hot, stop):
        peaks = [rule.peak(filtered[g], g, rest, state["index"], displaced, hot, inlet[g], stop) for g in range(2)]
        return peaks, any(p > s.limit_C for p in peaks)

    peaks, breach = predict(state["rest"], state["displaced"], state["hot"], np.inf)
    if not breach:
        return peaks
    if not state["displaced"]:
        state["displaced"], state["hot"] = True, 1 if peaks[1] > peaks[0] else 0
        peaks, breach = predict(state["rest"], True, state["hot"], np.inf)
        if not breach:
            return peaks
    for rest in range(state["rest"] + s.rest_quantum_steps, s.max_rest_steps + 1, s.rest_quantum_steps):
        peaks, breach = predict(rest, True, state["hot"], s.limit_C)
        if not breach:
            state["rest"] = rest
            return peaks
    state["rest"] = max(state["rest"], s.max_rest_steps)
    state["infeasible"] = True
    return peaks


def _c_array(values) -> str:
    return ",\n".join(", ".join(repr(float(v)) for v in chunk) for chunk in np.array_split(
        np.asarray(values, dtype=float).ravel(), max(1, np.asarray(values).size // 6)))


def flight_data_source(settings: ManagerSettings, flight: Flight) -> str:
    """``flight_data.c``: the manager's settings, the plants' constants, the profile and the noise."""
    s = settings
    sensors = ", ".join(str(i) for i in flight.sensor_states)
    return f"""/* flight_data.c -- written by genthermal.embedded.manager (do not edit) */
#include "flight.h"

const double flight_profile_A[] = {{
{_c_array(s.profile_A)}
}};
const double flight_noise[] = {{
{_c_array(flight.noise)}
}};
const gtm_settings_t flight_settings = {{
    flight_profile_A, {len(s.profile_A)}, {s.limit_C!r}, {s.rest_current_A!r}, {s.current_limit_A!r},
    {s.field_no_load_A!r}, {s.field_gain!r}, {s.ambient_C!r}, {s.winding_state}, {s.cycle_steps},
    {s.rest_quantum_steps}, {s.max_rest_steps}
}};
const flight_plant_t flight_plant = {{
    {flight.onset_sample}, {flight.inlet_C!r}, {flight.inlet_rise_C!r}, {{{sensors}}}, {len(flight.noise)}
}};
"""


def build_flight_program(design_model, settings: ManagerSettings, flight: Flight, out_dir) -> toolchain.TargetBuild:
    """Generate the three libraries (manager ``gt``, plants ``gtp`` and ``gtb``) and cross-compile
    ``manager.c`` + ``flight_target.c`` for the Cortex-M4F in double precision.

    Raises
    ------
    genthermal.embedded.toolchain.TargetToolchainError
        No cross toolchain.
    """
    toolchain.check_toolchain()
    out_dir = Path(out_dir)
    kalman = KalmanFilter(design_model, settings.dt_s).update_function()
    manager = generate_c(design_model, out_dir / "gt", settings.dt_s, "gt", {"kalman_update": kalman})
    plants = [generate_c(model, out_dir / prefix, settings.dt_s, prefix)
              for prefix, model in (("gtp", flight.healthy_plant), ("gtb", flight.faulty_plant))]
    data = out_dir / "flight_data.c"
    data.write_text(flight_data_source(settings, flight))
    hand_written = [toolchain.support_file("manager.c"), toolchain.support_file("flight_target.c"), data,
                    manager.abi_source]
    generated = [manager.directory / f"gt_casadi_{name}.c" for name in ("step", "kalman_update")]
    generated += [plant.directory / f"{plant.prefix}_casadi_step.c" for plant in plants]
    return toolchain.build(hand_written, [manager.directory, *(p.directory for p in plants)], out_dir / "build",
                           "flight", "double", generated)


def fly_on_target(build_result: toolchain.TargetBuild, timeout_s: float = 600.0) -> FlightRecord:
    """Run the flight program under QEMU and decode what it printed."""
    output = toolchain.run(build_result.elf, timeout_s)
    flags, values, costs = [], [], {}
    for line in output.splitlines():
        kind, *fields = line.split()
        if kind == "s":
            flags.append([int(f) for f in fields[:6]])
            values.append([struct.unpack(">d", bytes.fromhex(f))[0] for f in fields[6:]])
        elif kind == "cost":
            costs[fields[0]] = int(fields[1])
    values = np.array(values)
    instructions = {name: toolchain.instructions(costs[name]) for name in ("manager_max", "manager_total")}
    return FlightRecord(np.array(flags, dtype=float), values[:, 0:2], values[:, 2:4], values[:, 4:6], values[:, 6:8],
                        instructions, costs["stack"])
