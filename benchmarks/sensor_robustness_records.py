"""Records for the sensor-fault robustness bench: conditions the sensor screen was not built on.

``bench_sensor_faults.py`` diagnoses 4-h records of one mission at 10 s with the thesis noise and
constant, noise-free inlet and ambient readings. An implementation we did not write would record
differently; each case here draws its conditions from a seeded generator:

* plant: ``scenarios/data/rig_plant.yaml`` or ``rig_plant_b.yaml`` (parameters 15-30 % off in
  opposite directions, a different effect the built-in model lacks); every case is diagnosed on the
  built-in model, as a record of a real machine would be;
* sampling period: 1, 10 or 60 s (:data:`SAMPLE_PERIODS_S`);
* duration: 2-6 h (:data:`DURATION_H`), a load profile of its own: balanced phase currents held
  for 15-45 min at 27.3-100 % of the rated 7 A (the lowest and highest levels of thesis
  Table 3.2, as the shipped ``varying_load`` mission);
* sensor noise: one standard deviation 0.05-0.3 K for every temperature sensor (a class-A PT100
  with a good logger to a class-B one with a noisy channel; the thesis rig's are 0.09 and 0.11 K);
* inlet and ambient air: the rig draws its air from the room, so both read one air temperature
  that wanders by 0.5-3 K over 2-5 h about 20 °C; with ``input_noise`` the two input PT100s are
  as noisy as the others (``bench_sensor_faults`` logs them without noise).

Faults (:data:`FAULT_SIZES`) have a random sign and onset in 25-65 % of the record: bias 1-8 K,
drift 0.5-5 K/h, stuck (the reading at the onset held), gain 0.95-1.10 (relative error -5 % to
+10 %, a wrong transmitter span), noise ×2-×5.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pandas as pd

from genthermal.diagnose.hidden import inject, random_injection
from genthermal.effects import CATALOGUE
from genthermal.mission import Mission
from genthermal.model_file import load_model
from genthermal.sensor_faults import SensorFault, inject_sensor_faults

DATA = Path(__file__).resolve().parent.parent / "scenarios" / "data"
#: Plants the records come from (every case is diagnosed on the built-in model).
PLANTS = {"rig": DATA / "rig_plant.yaml", "rig_b": DATA / "rig_plant_b.yaml"}
SAMPLE_PERIODS_S = (1.0, 10.0, 60.0)
DURATION_H = (2.0, 6.0)
NOISE_STD_K = (0.05, 0.3)
#: Load levels, % of the rated phase current (thesis Table 3.2, lowest and highest), and how
#: long each is held, min.
LOAD_PERCENT = (27.3, 100.0)
HOLD_MIN = (15, 45)
RATED_CURRENT_A = 7.0
#: Air temperature about which inlet and ambient wander, °C, the wander's amplitude, K, and period, h.
AIR_C, AIR_AMPLITUDE_K, AIR_PERIOD_H = 20.0, (0.5, 3.0), (2.0, 5.0)
#: The fault kinds tried on each sensor.
KINDS = ("bias", "drift", "stuck", "gain", "noise")
#: Fault sizes (magnitude ranges; bias K, drift K/h, gain relative, noise factor).
FAULT_SIZES = {"bias": (1.0, 8.0), "drift": (0.5, 5.0), "gain": (0.05, 0.10), "noise": (2.0, 5.0)}
ONSET_SHARE = (0.25, 0.65)


@dataclasses.dataclass(frozen=True)
class Conditions:
    """How one record was made (module docstring)."""

    plant: str
    dt_s: float
    duration_h: float
    noise_std_K: float
    input_noise: bool
    seed: int

    def to_dict(self) -> dict:
        """JSON entry."""
        return dataclasses.asdict(self)


def draw_conditions(rng: np.random.Generator, seed: int) -> Conditions:
    """Seeded draw of a record's conditions (module docstring)."""
    return Conditions(plant=str(rng.choice(list(PLANTS))), dt_s=float(rng.choice(SAMPLE_PERIODS_S)),
                      duration_h=float(np.round(rng.uniform(*DURATION_H), 2)),
                      noise_std_K=float(np.round(rng.uniform(*NOISE_STD_K), 3)),
                      input_noise=bool(rng.random() < 0.5), seed=int(seed))


def load_profile(conditions: Conditions, rng: np.random.Generator) -> Mission:
    """Balanced load held for 15-45 min at random levels, ``conditions.duration_h`` long."""
    actions, left_min = [], conditions.duration_h * 60.0
    while left_min > 1e-9:
        hold = min(float(rng.integers(HOLD_MIN[0], HOLD_MIN[1] + 1)), left_min)
        actions.append({"load_percent": float(np.round(rng.uniform(*LOAD_PERCENT), 1)), "duration_min": hold})
        left_min -= hold
    return Mission.from_dict({"name": f"robustness_{conditions.seed}", "rated_current_A": RATED_CURRENT_A,
                              "T_inlet_C": AIR_C, "T_ambient_C": AIR_C, "actions": actions})


def record_inputs(conditions: Conditions, rng: np.random.Generator) -> pd.DataFrame:
    """The model inputs of a record: the load profile and the wandering room air."""
    inputs = load_profile(conditions, rng).to_inputs(conditions.dt_s)
    elapsed_h = inputs["time_s"].to_numpy(float) / 3600.0
    air = AIR_C + rng.uniform(*AIR_AMPLITUDE_K) * np.sin(2 * math.pi * elapsed_h / rng.uniform(*AIR_PERIOD_H)
                                                         + rng.uniform(0, 2 * math.pi))
    inputs["T_inlet"] = air
    inputs["T_ambient"] = air
    return inputs


def make_record(conditions: Conditions, effect: str | None = None):
    """A record of ``conditions.plant``, healthy or with a catalogue ``effect`` at a random onset.

    Returns
    -------
    (pandas.DataFrame, dict)
        The record (measurement CSV schema) and what was injected.
    """
    rng = np.random.default_rng((conditions.seed, 1))  # a stream apart from the conditions' draw
    plant = load_model(PLANTS[conditions.plant])
    inputs = record_inputs(conditions, rng)
    variance = conditions.noise_std_K ** 2
    injections = []
    if effect is not None:
        injections = [random_injection(effect, float(inputs["time_s"].iloc[-1]), rng)]
    record = inject(plant, injections, inputs, conditions.seed, noise_var=(variance, variance))
    if conditions.input_noise:
        for column in ("T_inlet", "T_ambient"):
            record[column] = record[column] + conditions.noise_std_K * rng.standard_normal(len(record))
    truth = {"effects": [dataclasses.asdict(i) for i in injections]}
    return record, truth


def effects_for(plant_name: str) -> list:
    """Catalogue effects the plant can take (the two of the linear design model are left out)."""
    plant = load_model(PLANTS[plant_name])
    return [name for name, effect in CATALOGUE.items() if effect.unavailable_reason(plant) is None]


def draw_fault(sensor: str, kind: str, duration_s: float, rng: np.random.Generator) -> SensorFault:
    """A fault of ``kind`` on ``sensor`` with a seeded size and onset (module docstring)."""
    if kind == "stuck":
        value = 0.0
    elif kind == "noise":
        value = float(rng.uniform(*FAULT_SIZES["noise"]))
    elif kind == "gain":
        value = float(rng.choice((-FAULT_SIZES["gain"][0], FAULT_SIZES["gain"][1])) * rng.uniform(0.2, 1.0))
    else:
        value = float(rng.choice((-1.0, 1.0)) * rng.uniform(*FAULT_SIZES[kind]))
    return SensorFault(sensor, kind, value, float(np.round(rng.uniform(*ONSET_SHARE) * duration_s, 0)))


def faulty_record(conditions: Conditions, sensor: str, kind: str):
    """A healthy record of ``conditions`` with one drawn sensor fault: (record, fault)."""
    record, _ = make_record(conditions)
    rng = np.random.default_rng((conditions.seed, 2))
    fault = draw_fault(sensor, kind, float(record["time_s"].iloc[-1] - record["time_s"].iloc[0]), rng)
    return inject_sensor_faults(record, [fault], noise_std_K=conditions.noise_std_K, seed=conditions.seed), fault
