"""The chapter-7 verdicts of benchmarks/reproduce_thesis.py check what the thesis states: +4 K is
reproduced only with both a rest before landing and load displaced in it ("a short rest and load
adjust before landing"), +16 K only with displacement in cruise/combat, none in the cruise after and
"a short rest with some load displacement" for landing. Flight outcomes are built by hand (no flight)."""

import pytest

ACTIONS = ("loading_preparation", "start_warm_up", "taxi", "take_off_climb", "cruise", "cruise_combat", "cruise",
           "landing")


@pytest.fixture(scope="module")
def reproduce(benchmark_script):
    return benchmark_script("reproduce_thesis")


def _outcome(shed=None, rest_before_landing=0.0, peak=107.0):
    """A flight outcome with ``shed`` (action index → A) and a rest of ``rest_before_landing`` min before landing."""
    shed = shed or {}
    actions = [{"action": name, "shed_A": shed.get(i, 0.0), "rest_min": rest_before_landing if i == 7 else 0.0,
                "rest_before_min": rest_before_landing if i == 7 else 0.0} for i, name in enumerate(ACTIONS)]
    return {"actions": actions, "peak_C": peak, "peak_gen1_C": peak, "peak_gen2_C": peak - 4.0}


@pytest.mark.parametrize("shed, rest, verdict, missing", [
    ({7: 0.3}, 5.0, "reproduced", ""),
    ({}, 5.0, "qualitative", "displaces no load in landing"),        # the rated-current reading's flight
    ({7: 0.05}, 0.0, "qualitative", "does not rest before landing"),  # the θmax reading's flight
    ({5: 0.2, 7: 0.3}, 5.0, "contradicted", "acts earlier too"),
])
def test_inlet_4K_needs_both_the_rest_and_the_load_adjust(reproduce, shed, rest, verdict, missing):
    row = reproduce.inlet_4K_row(_outcome(shed, rest))
    assert row["verdict"] == verdict
    assert missing in row["reason"]


def test_inlet_4K_reason_reports_the_rated_reading(reproduce):
    """The reason names what the flight held to 7 A did and the rated-current study's least violation."""
    study = {"worst_violation_K": 3.21, "sharp_worst_violation_K": 3.25, "active": ["landing_4K", "managed_gen1_landing"]}
    row = reproduce.inlet_4K_row(_outcome({7: 0.05}, 0.0), _outcome({}, 5.0, 97.2), study)
    assert "5-min rest before landing, 0.00 A displaced in it" in row["reason"] and "without the load adjust" in row["reason"]
    assert "+3.21 K (+3.25 K on the samples' sharp peaks): no calibration meets them all" in row["reason"]
    assert "landing_4K, managed_gen1_landing" in row["reason"]


@pytest.mark.parametrize("shed, rest, verdict", [
    ({5: 0.04, 7: 0.45}, 5.0, "reproduced"),
    ({5: 0.04}, 20.0, "qualitative"),            # no displacement in landing (the rated-current flight)
    ({5: 0.04, 6: 0.2, 7: 0.45}, 5.0, "qualitative"),  # displacement in the cruise after
    ({4: 0.1, 5: 0.04, 7: 0.45}, 5.0, "qualitative"),  # displacement before cruise/combat
    ({}, 0.0, "contradicted"),
])
def test_inlet_16K_checks_every_part_of_the_thesis_outcome(reproduce, shed, rest, verdict):
    row = reproduce.inlet_16K_row(_outcome(shed, rest))
    assert row["verdict"] == verdict
    assert (row["reason"] == "") == (verdict == "reproduced")


def test_inlet_16K_reason_adds_the_rated_flight_as_one_clause(reproduce):
    row = reproduce.inlet_16K_row(_outcome({5: 0.04, 7: 0.45}, 5.0), _outcome({5: 0.04}, 20.0))
    assert row["verdict"] == "reproduced"
    assert row["reason"].startswith("held to the rated 7 A instead:") and "20-min rest before landing" in row["reason"]


def _flown_blockage(rests_before, gen1_starts):
    """The blockage flown on the simulation model: rests (min) before and gen1's temperature (°C) at
    the start of each action from cruise on."""
    outcome = _outcome({4: 0.04, 5: 0.56, 6: 0.49, 7: 0.93}, peak=110.1)
    for i, (rest, start) in enumerate(zip(rests_before, gen1_starts), start=4):
        outcome["actions"][i].update(rest_min=rest, rest_before_min=rest, gen1_start_C=start)
    return {**outcome, "breach_s": 40.0}


def test_simulation_model_reading_ties_the_rests_within_the_conditions_to_gen1s_temperature(reproduce):
    """Rests before cruise/combat and the cruise after, with gen1 1.7 K below θmax at the latest
    start, are where the thesis breached; the study under that manager names its verdict."""
    study = {"worst_violation_K": 0.46, "sharp_worst_violation_K": 0.48}
    text = reproduce._simulation_model_text(_flown_blockage((0, 5, 5, 20), (95.0, 110.1, 108.3, 106.3)), study)
    assert "rests before cruise_combat 5 min (gen1 at 110.1 °C when it began); cruise 5 min" in text
    assert "within 1.7 K of θmax" in text and "the thesis breached instead" in text
    assert "+0.46 K (+0.48 K on the sharp peaks): no calibration meets them all" in text
    calm = reproduce._simulation_model_text(_flown_blockage((0, 0, 0, 10), (95.0, 104.0, 105.0, 106.0)), None)
    assert "landing 10 min" in calm and "breached instead" not in calm and "least worst violation" not in calm
