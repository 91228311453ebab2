"""The chapter-7 calibration: selectable by name, fitted values with provenance and physical bounds,
and its proxies of the thesis's chapter-7 outcomes (fast checks; the flights are in
benchmarks/reproduce_thesis.py)."""

import numpy as np
import pytest

from genthermal.errors import InputError
from genthermal.machines import build_model
from genthermal.coolant import inlet_rise
from genthermal.machines.chapter7 import (BLOCKAGE_MINUTES, FIT_BOUNDS, ONSET_S, PLANNING_LIMIT_C, PLANT_MISMATCH,
                                          PREDICTION_LAG_K, PROXIES, ProxySimulator, no_action_blockage_minutes)
from genthermal.mission import load_mission
from genthermal.model_file import load_model
from genthermal.schedule.power_system import PowerSystem
from genthermal.simulate import simulate

FITTED_MACHINE_PARAMETERS = ("h_top_air", "h_end_air", "R0", "P_iron", "h_ambient", "m_dot_fan")


@pytest.fixture(scope="module")
def chapter7():
    return load_model("genco_rf201a:chapter7")


@pytest.fixture(scope="module")
def plant(chapter7):
    """The true plant of the chapter-7 scenarios: the calibration with their mismatch."""
    return chapter7.with_parameters("assumed", "scenario mismatch",
                                    **{k: chapter7.parameters.value(k) * f for k, f in PLANT_MISMATCH.items()})


@pytest.fixture(scope="module")
def blockage():
    return PowerSystem.from_mission(load_mission("chapter7_blockage_large")).faults[0]


def part_peak(plant, rise_K: float, part: tuple) -> float:
    """Open-loop winding peak (°C) of ``plant`` in a part (start, end, min) of the Fig 7.7 mission with
    the inlet ``rise_K`` higher from the fault on."""
    inputs = load_mission("thesis_fig_7_7").to_inputs(60.0)
    t = inputs["time_s"].to_numpy()
    inputs["T_inlet"] = inputs["T_inlet"] + inlet_rise(t, ONSET_S, rise_K)
    winding = simulate(plant, inputs)["T_winding"].to_numpy()
    return float(winding[(t >= 60 * part[0]) & (t < 60 * part[1])].max())


def threshold_rise(plant, part: tuple, level_C: float) -> float:
    """Smallest inlet rise (K, to 0.05 K) at which the open-loop peak in ``part`` reaches ``level_C``."""
    low, high = 0.0, 30.0
    while high - low > 0.05:
        middle = 0.5 * (low + high)
        low, high = (middle, high) if part_peak(plant, middle, part) < level_C else (low, middle)
    return high


def test_chapter7_is_a_named_parameter_set_with_fitted_provenance(chapter7):
    default = build_model()
    assert chapter7.spec.name == default.spec.name and chapter7.n_states == default.n_states
    for name in FITTED_MACHINE_PARAMETERS:
        parameter = chapter7.parameters[name]
        assert parameter.provenance == "fitted" and "thesis ch. 7 outcomes" in parameter.source
        assert parameter.value != default.parameters.value(name)
    unchanged = [n for n in default.parameter_names if n not in FITTED_MACHINE_PARAMETERS]
    assert all(chapter7.parameters.value(n) == default.parameters.value(n) for n in unchanged)


def test_fitted_values_lie_within_their_physical_bounds(chapter7):
    # the plant the fit ran on is the model with the scenarios' mismatch: both must be physical
    for name in FITTED_MACHINE_PARAMETERS:
        low, high = FIT_BOUNDS[name][:2]
        value = chapter7.parameters.value(name)
        assert low / 1.2 <= value <= high * 1.2, name


def test_default_calibration_is_unchanged_and_cooler(chapter7):
    inputs = load_mission("thesis_fig_7_7").to_inputs(60.0)
    default_peak = simulate(build_model(), inputs)["T_winding"].max()
    chapter7_peak = simulate(chapter7, inputs)["T_winding"].max()
    assert default_peak < 90.0 < chapter7_peak < 110.0   # ch. 5 level vs ch. 7 level, both healthy


def test_every_proxy_is_met_by_the_plant(plant, blockage):
    import dataclasses

    proxies = [dataclasses.replace(p, inlet_rise_tau_s=blockage.inlet_rise_tau_s) if p.blockage_outlet_mm else p
               for p in PROXIES]
    simulator = ProxySimulator(plant, ["k_flow", "n_flow"], proxies)
    peaks = [float(p) for p in simulator.peaks(np.array([blockage.values["k_flow"], blockage.values["n_flow"]]))]
    for proxy, peak in zip(proxies, peaks):
        assert peak == pytest.approx(proxy.target_C, abs=1.0), proxy.name


def test_no_action_blockage_reaches_109_C_44_min_after_the_fault(plant, blockage):
    """Thesis Fig 7.5: 109 °C 44 min after the fault (111 min into the flight); ± 10 min."""
    minutes = no_action_blockage_minutes(plant, blockage.values["k_flow"], blockage.values["n_flow"],
                                         blockage.inlet_rise_tau_s)
    assert abs(minutes - BLOCKAGE_MINUTES) <= 10.0
    # the inlet's time constant matters: with a step rise the limit comes much sooner
    assert no_action_blockage_minutes(plant, blockage.values["k_flow"], blockage.values["n_flow"], 0.0) < minutes - 10


def test_inlet_thresholds_open_loop(plant):
    """Fast stand-ins for the closed-loop flights (benchmarks/reproduce_thesis.py). The manager acts
    when its prediction passes the planning limit, which lags the true plant by about
    PREDICTION_LAG_K, so it acts where the plant's peak passes the limit plus the lag. Thesis: < 4 K
    nothing, 4 K a rest before landing; 16 K the smallest rise that needs displacement in
    cruise/combat. The calibration's thresholds must lie within the thesis's 1-K steps of those."""
    act = PLANNING_LIMIT_C + PREDICTION_LAG_K
    landing = threshold_rise(plant, (220, 241), act)
    assert 2.5 <= landing <= 4.0
    assert part_peak(plant, landing, (66, 220)) < PLANNING_LIMIT_C  # landing is the first part to need action
    combat = threshold_rise(plant, (120, 180), act + PREDICTION_LAG_K)
    assert 14.0 <= combat <= 16.0
    assert part_peak(plant, combat, (66, 120)) < PLANNING_LIMIT_C  # the cruise before it needs none


def test_chapter7_scenarios_fly_the_chapter7_machine():
    system = PowerSystem.from_mission(load_mission("chapter7_blockage_large"))
    assert system.machine == "genco_rf201a:chapter7"
    assert system.nominal_model.parameters["R0"].provenance == "fitted"
    assert system.faults[0].values == {"k_flow": 0.6, "n_flow": 0.5}
    assert system.faults[0].inlet_rise_tau_s == pytest.approx(43.6 * 60)


def test_unknown_parameter_set_is_refused():
    with pytest.raises(InputError, match="model"):
        load_model("genco_rf201a:chapter9")
    mission = load_mission("chapter7_inlet_4C")
    document = mission.to_dict()
    document["generators"]["machine"] = "genco_rf201a:chapter9"
    from genthermal.mission import Mission
    with pytest.raises(InputError) as error:
        PowerSystem.from_mission(Mission.from_dict(document))
    assert error.value.field == "generators.machine"
