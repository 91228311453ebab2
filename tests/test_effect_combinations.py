"""Two forms of one loss exclude each other: the pair search never fits them together (it raised
on the bench IPMSM, where both speed-dependent iron losses rank among the best single effects)."""

from __future__ import annotations

import pytest

from genthermal.effects import combination_reason, get_effect
from genthermal.machines import build_model
from genthermal.resources import BENCH_MOTOR_DIR


@pytest.fixture(scope="module")
def plain():
    return build_model(f"{BENCH_MOTOR_DIR / 'ipmsm_machine.py'}:MACHINE_PLAIN")


def test_two_iron_loss_forms_cannot_be_combined(plain):
    reason = combination_reason(plain, (get_effect("speed_iron_loss"), get_effect("iron_loss_hysteresis_eddy")))
    assert reason is not None and reason.startswith("iron_loss_hysteresis_eddy after speed_iron_loss"), reason
    assert "iron loss" in reason
    reason = combination_reason(plain, (get_effect("iron_loss_hysteresis_eddy"), get_effect("speed_iron_loss")))
    assert reason is not None and reason.startswith("speed_iron_loss after iron_loss_hysteresis_eddy"), reason


def test_different_losses_combine(plain):
    assert combination_reason(plain, (get_effect("magnet_eddy_loss"), get_effect("speed_iron_loss"))) is None
    assert combination_reason(plain, (get_effect("speed_iron_loss"), get_effect("bearing_friction"))) is None


def test_an_effect_the_model_cannot_take_is_named_first(plain):
    once = plain.with_effect(get_effect("magnet_eddy_loss"))
    reason = combination_reason(once, (get_effect("magnet_eddy_loss"), get_effect("speed_iron_loss")))
    assert reason == "magnet_eddy_loss after nothing: already applied"


def test_the_pair_search_drops_the_pairs_that_cannot_be_combined(plain):
    """The pool of pairs is filtered before any fit (a search stand-in: only its model and its
    effects are read)."""
    from types import SimpleNamespace

    from genthermal.diagnose.joint import PairSearch

    search = SimpleNamespace(model=plain, effect=get_effect)
    single = {name: SimpleNamespace(effect=name) for name in
              ("magnet_eddy_loss", "speed_iron_loss", "iron_loss_hysteresis_eddy")}
    pairs = [(single["magnet_eddy_loss"], single["speed_iron_loss"]),
             (single["speed_iron_loss"], single["iron_loss_hysteresis_eddy"]),
             (single["magnet_eddy_loss"], single["iron_loss_hysteresis_eddy"])]
    kept = PairSearch._combinable(SimpleNamespace(search=search), pairs)
    assert [(a.effect, b.effect) for a, b in kept] == [("magnet_eddy_loss", "speed_iron_loss"),
                                                       ("magnet_eddy_loss", "iron_loss_hysteresis_eddy")]
