"""The composed discovery: candidates, criterion and fitter behind ``fit``; nothing global changes."""

import math
import time

import numpy as np
import pytest

from genthermal.diagnose import AIC, BIC, Catalogue, Discovery, OnsetFitter
from genthermal.diagnose.compare import measured_series
from genthermal.diagnose.hidden import make_hidden_effect_case
from genthermal.diagnose.parallel import WORKER_CPU, can_fork, cpu_clock, map_in_workers
from genthermal.diagnose.search import EffectSearch
from genthermal.effects import CATALOGUE
from genthermal.errors import InputError


def test_defaults_are_the_registered_catalogue_bic_and_pairs():
    discovery = Discovery()
    assert list(discovery.candidates) == list(CATALOGUE)
    assert isinstance(discovery.criterion, BIC) and discovery.fitter == OnsetFitter()
    assert discovery.fitter.pairs and discovery.fitter.workers == 1


def test_a_catalogue_is_immutable_and_derived_catalogues_are_new():
    registered = Catalogue.registered()
    fewer = registered.without("frame_cooling_change")
    assert "frame_cooling_change" in registered and "frame_cooling_change" not in fewer
    assert list(registered.only(["phase_short_circuit"])) == ["phase_short_circuit"]
    with pytest.raises(TypeError):
        registered["x"] = CATALOGUE["phase_short_circuit"]
    with pytest.raises(InputError, match="not among the candidates"):
        fewer.without("frame_cooling_change")
    assert Catalogue.of(["phase_short_circuit"]) == {"phase_short_circuit": CATALOGUE["phase_short_circuit"]}


def test_criteria_score_a_change_of_fit():
    n, k = 1000, 2
    assert BIC().delta(50.0, 100.0, n, k) == pytest.approx(n * math.log(0.5) + k * math.log(n))
    assert AIC().delta(50.0, 100.0, n, k) == pytest.approx(n * math.log(0.5) + 2 * k)
    with pytest.raises(InputError, match="rss"):
        BIC().delta(0.0, 1.0, n, k)


@pytest.mark.parametrize("build, field", [
    (lambda: Discovery(criterion=object()), "criterion"),
    (lambda: Discovery(fitter="fast"), "fitter"),
    (lambda: Discovery(max_iterations=0), "max_iterations"),
    (lambda: Discovery(candidates="phase_short_circuit"), "candidates"),
    (lambda: Discovery(candidates=["no_such_effect"]), "no_such_effect"),
    (lambda: Discovery().with_settings(speed=2), "speed"),
    (lambda: OnsetFitter(workers=0), "workers"),
    (lambda: OnsetFitter(pair_pool=1), "pair_pool"),
])
def test_bad_settings_name_the_field(build, field):
    with pytest.raises(InputError, match=field):
        build()


def test_a_search_fits_nothing_until_asked(plant_model):
    case = make_hidden_effect_case(None, mission="thesis_fig_7_7", dt_s=600.0, seed=1, plant=plant_model)
    search = EffectSearch(plant_model, measured_series(case.data))
    assert not hasattr(search, "rss_before")
    with pytest.raises(InputError, match="fit_found"):
        search.rank()
    assert search.fit_found().rss_before > 0


def test_a_derived_discovery_shares_the_memo_and_changes_only_what_it_is_told():
    discovery = Discovery(iterate=True)
    narrower = discovery.with_settings(candidates=["phase_short_circuit"])
    assert narrower._memo is discovery._memo and narrower.iterate
    assert list(narrower.candidates) == ["phase_short_circuit"] and len(discovery.candidates) == len(CATALOGUE)


def test_workers_give_the_results_of_one_process():
    offset = np.arange(3.0)  # state the forked workers inherit

    def shifted(x):
        return offset + x

    seen = []
    serial = map_in_workers(shifted, [1.0, 2.0, 3.0], 1)
    parallel = map_in_workers(shifted, [1.0, 2.0, 3.0], 2, lambda done, total, item: seen.append(done))
    assert all(np.array_equal(a, b) for a, b in zip(serial, parallel))
    assert sorted(seen) == [1, 2, 3] and (can_fork() or seen == [1, 2, 3])
    with pytest.raises(InputError, match="workers"):
        map_in_workers(shifted, [1.0], 0)


@pytest.mark.skipif(not can_fork(), reason="no forked workers on this platform")
def test_workers_cpu_time_is_counted_and_the_busiest_worker_bounds_the_wall_time():
    def busy(seconds):
        started = time.process_time()
        while time.process_time() - started < seconds:
            pass
        return seconds

    before, maps = cpu_clock(), WORKER_CPU.maps
    assert map_in_workers(busy, [0.3, 0.1, 0.1], 2) == [0.3, 0.1, 0.1]
    spent = cpu_clock() - before
    assert WORKER_CPU.maps == maps + 1
    assert 0.5 <= spent.workers_s < 0.8  # every item's CPU time, in whichever worker it ran
    # the busiest worker ran the 0.3-s item, perhaps with one 0.1-s item: the other ran the rest
    assert 0.3 <= spent.critical_s - spent.own_s <= 0.45 and spent.critical_s < spent.total_s
