"""The optimal scheduler on the flown (nonlinear) model: its plans, its back-off and its option."""

import dataclasses

import numpy as np
import pytest

from genthermal.cli import main
from genthermal.errors import InputError
from genthermal.estimation.ekf import ExtendedKalmanFilter
from genthermal.schedule.flight.manager_settings import ManagerSettings
from genthermal.schedule.flight.replanning import plan_with
from genthermal.schedule.planning.flown import FlownPlanning, update_steps
from genthermal.schedule.planning.optimal import OptimalSettings, optimal_plan
from genthermal.schedule.planning.optimal_nlp import FlownTranscription, NonlinearSettings, flown_optimal_plan
from genthermal.schedule.planning.plan import PlanningProblem, Schedule, Segment, build_timeline, predict, split_segments
from genthermal.schedule.power_system import AffineGenerator

BLOCKAGE = {"k_flow": 0.2, "n_flow": 0.0}
INLETS_C = np.array([51.0, 20.0])  # the faulty generator's inlet after the large blockage (thesis 7.3.3)


def _problem(generators, x0, segments, limit_C, flown=None, max_rest_s=1800.0, rest_current_A=1.911):
    return PlanningProblem(tuple(segments), generators, np.asarray(x0), INLETS_C, 20.0, rest_current_A, 7.0,
                           limit_C=limit_C, max_rest_s=max_rest_s, dt_s=10.0, window_s=300.0, flown=flown)


#: A filter that has converged: a tenth of the initial covariance (node standard deviation ~1 K).
CONVERGED = 0.1


def _flown(filters, x0, P0=None):
    nd = len(filters[0].disturbance_names)
    z0 = [np.concatenate([x, np.zeros(nd)]) for x in x0]
    return FlownPlanning(list(filters), z0, [f.P0 if P0 is None else P0 for f in filters])


@pytest.fixture(scope="module")
def believed(plant_model):
    """The nonlinear models the manager believes in: gen1 blocked, gen2 healthy, and their filters."""
    models = [plant_model.with_effect("coolant_flow_reduction", **BLOCKAGE), plant_model]
    return models, [ExtendedKalmanFilter(m, 10.0) for m in models]


def test_agrees_with_the_affine_transcription_when_no_nonlinearity_is_active(design_model):
    """The flown model is the design model itself, the filters have no noise: both transcriptions
    solve the same problem and must find the same schedule. The rest current is 2.2 A: at the
    thesis's 1.911 A the design model's loss floor is active in the end winding (its step heats
    that node by up to 0.02 K per 10 s more than the affine branch the affine planner uses)."""
    faulty = design_model.with_effect("coolant_flow_reduction", **BLOCKAGE)
    generators = [AffineGenerator(faulty), AffineGenerator(design_model)]
    quiet = dict(node_heat_noise_W=0.0, disturbance_drift_W=0.0, load_scaled_drift_W=0.0, coolant_drift_W=0.0,
                 inlet_drift_K=0.0, initial_disturbance_W=0.0)
    filters = [ExtendedKalmanFilter(m, 10.0, **quiet) for m in (faulty, design_model)]
    x0 = [g.steady_state(g.input(4.5, t, 20.0)) for g, t in zip(generators, INLETS_C)]
    segments = split_segments([Segment(0, "a", 900.0, ((0.0, 5.5),)), Segment(1, "b", 1200.0, ((0.0, 6.5),))], 300.0, 10.0)
    affine = optimal_plan(_problem(generators, x0, segments, 108.0, rest_current_A=2.2), OptimalSettings(check_s=10.0))
    nz = len(filters[0].state_names)
    flown_problem = _problem(generators, x0, segments, 108.0, _flown(filters, x0, np.zeros((nz, nz))),
                             rest_current_A=2.2)
    flown = flown_optimal_plan(flown_problem)
    assert affine.schedule.added_rest_s > 60.0  # the case needs rest: the agreement is not trivial
    assert flown.method == "optimal" and flown.feasible
    assert flown.details["backoff_K"] < 1e-6
    assert flown.schedule.added_rest_s == pytest.approx(affine.schedule.added_rest_s, abs=5.0)
    assert np.max(np.abs(flown.schedule.displaced_A - affine.schedule.displaced_A)) < 0.1


def test_plan_flown_open_loop_keeps_every_generator_below_thetamax_minus_its_back_off(believed, design_model):
    models, filters = believed
    generators = [AffineGenerator(design_model.with_effect("coolant_flow_reduction", **BLOCKAGE)),
                  AffineGenerator(design_model)]
    x0 = [np.full(models[0].n_states, 85.0), np.full(models[1].n_states, 60.0)]
    segments = split_segments([Segment(4, "5 cruise", 1800.0, ((0.0, 4.9),)),
                               Segment(7, "7 landing", 1200.0, ((0.0, 5.0),))], 300.0, 10.0)
    problem = _problem(generators, x0, segments, 110.0, _flown(filters, x0, CONVERGED * filters[0].P0))
    result = flown_optimal_plan(problem)
    assert result.method == "optimal" and result.feasible
    flown = predict(problem, result.schedule)  # the filter's own step, every 10 s, with its back-off
    assert flown.backoff_K[:, :, 1:].min() > 0.0 and flown.backoff_K.max(axis=2).min() > 0.5  # on every generator
    backed_off = flown.outputs + flown.backoff_K
    assert backed_off[:, :, 1:].max() <= 110.0 + 0.05
    assert flown.outputs[1, :, 1:].max() > flown.outputs[1, :, 0].max()  # the healthy one takes load ...
    assert backed_off[1].max() <= 110.0 + 0.05  # ... and is held to its own back-off too
    landing = [k for k, s in enumerate(problem.segments) if s.action_index == 7]
    assert result.schedule.displaced_A[0, landing].max() > 0.2  # load moved off the blocked one while landing


def test_backoff_is_the_covariance_of_the_estimate_the_manager_will_have(believed, design_model):
    """The back-off follows the filter's covariance with the measurement update the closed loop
    makes once per cycle: over the first cycle it is the open-loop propagation of the covariance
    now; after an update it drops below it, and it grows again within the cycle. A filter that has
    just restarted its disturbance states (its prior ``P0``) gets no smaller back-off over the
    first cycle than a converged one."""
    models, filters = believed
    generators = [AffineGenerator(design_model.with_effect("coolant_flow_reduction", **BLOCKAGE)),
                  AffineGenerator(design_model)]
    x0 = [np.full(models[0].n_states, 85.0), np.full(models[1].n_states, 60.0)]
    segments = split_segments([Segment(4, "5 cruise", 1800.0, ((0.0, 4.9),))], 300.0, 10.0)
    problem = _problem(generators, x0, segments, 110.0, _flown(filters, x0))
    schedule = Schedule.nominal(2, len(segments))
    updated = predict(problem, schedule).backoff_K
    never_updated = predict(dataclasses.replace(problem, window_s=1e9), schedule).backoff_K
    cycle = 30  # steps of 10 s in a 300-s cycle
    np.testing.assert_allclose(updated[:, :, :cycle + 1], never_updated[:, :, :cycle + 1], rtol=1e-9)
    assert np.all(updated[:, :, cycle + 1:] < never_updated[:, :, cycle + 1:])
    assert np.all(updated[:, :, cycle + 1] < updated[:, :, cycle])  # the update ...
    assert np.all(updated[:, :, 2 * cycle] > updated[:, :, cycle + 1])  # ... and the cycle's growth after it
    converged = predict(dataclasses.replace(problem, flown=_flown(filters, x0, CONVERGED * filters[0].P0)),
                        schedule).backoff_K
    assert np.all(converged[:, :, 1:cycle + 1] <= updated[:, :, 1:cycle + 1])
    with pytest.raises(InputError, match="cycle_s"):
        update_steps(10, 10.0, 0.0)


def test_displacement_during_landing_saves_rest(believed, design_model):
    """Forbidding displacement inside the landing (one displacement per action, the affine
    formulation's segments) costs rest that per-interval displacement saves."""
    models, filters = believed
    generators = [AffineGenerator(design_model.with_effect("coolant_flow_reduction", **BLOCKAGE)),
                  AffineGenerator(design_model)]
    x0 = [np.full(models[0].n_states, 92.0), np.full(models[1].n_states, 60.0)]
    landing = Segment(7, "7 landing", 1200.0, ((0.0, 5.0),))
    P0 = CONVERGED * filters[0].P0
    per_interval = flown_optimal_plan(_problem(generators, x0, split_segments([landing], 300.0, 10.0), 110.0,
                                               _flown(filters, x0, P0)))
    per_action = flown_optimal_plan(_problem(generators, x0, [landing], 110.0, _flown(filters, x0, P0)))
    assert per_interval.feasible and per_action.feasible
    assert per_interval.schedule.displaced_A[0].max() > 0.2
    assert per_interval.schedule.added_rest_s < per_action.schedule.added_rest_s - 30.0 or \
        (per_action.schedule.added_rest_s == 0 and per_interval.schedule.displaced_Ah(split_segments([landing], 300.0, 10.0))
         < per_action.schedule.displaced_Ah([landing]))


def test_plan_that_exceeds_thetamax_with_its_back_off_is_not_feasible(believed, design_model):
    models, filters = believed
    generators = [AffineGenerator(design_model.with_effect("coolant_flow_reduction", **BLOCKAGE)),
                  AffineGenerator(design_model)]
    x0 = [np.full(models[0].n_states, 109.5), np.full(models[1].n_states, 109.5)]  # both at the limit
    problem = _problem(generators, x0, split_segments([Segment(0, "x", 600.0, ((0.0, 7.0),))], 300.0, 10.0), 110.0,
                       _flown(filters, x0))
    result = flown_optimal_plan(problem)
    assert not result.feasible
    assert result.peak_C > 110.0
    managed = plan_with("optimal", problem, ManagerSettings(planner_model="nonlinear"), ("gen1", "gen2"), 110.0)
    assert not managed.feasible  # never feasible: its own prediction with its back-off is above θmax
    assert managed.details["lowest_peak_C"] > 110.0 and managed.details["response"]


def test_planner_model_settings_and_options_reject_bad_values(tmp_path, capsys):
    with pytest.raises(InputError, match="planner_model"):
        ManagerSettings(planner_model="quadratic")
    with pytest.raises(InputError, match="filter"):
        ManagerSettings(planner_model="nonlinear", filter="kf")
    with pytest.raises(InputError, match="interval_s"):
        split_segments([Segment(0, "a", 600.0, ((0.0, 5.0),))], 0.0, 10.0)
    with pytest.raises(InputError, match="step_s"):
        split_segments([Segment(0, "a", 600.0, ((0.0, 5.0),))], 300.0, 0.0)
    with pytest.raises(InputError, match="filter"):
        FlownPlanning([object()], np.zeros((1, 3)), np.zeros((1, 3, 3)))
    for extra, option in ((["--planner-model", "quadratic"], "--planner-model"),
                          (["--planner-model", "nonlinear", "--scheduler", "engineer"], "--planner-model"),
                          (["--planner-model", "nonlinear", "--filter", "kf"], "--filter"),
                          (["--confidence-sigmas", "-1"], "--confidence-sigmas")):
        assert main(["fly", "blockage_large", "--json", str(tmp_path / "x.json"), *extra]) == 2
        assert option in capsys.readouterr().err


def test_closed_loop_on_the_flown_model_keeps_every_generator_below_thetamax(tmp_path):
    """One hour, gen1's coolant nearly blocked from 10 min, the plant 10 % short in end-winding
    cooling and 5 % high in resistance (the default mismatch), θmax 104 °C: the manager plans on
    the flown model with the filter's back-off, displacing and resting per cycle."""
    from flight_scenarios import fly_short_on_the_flown_model

    flight = fly_short_on_the_flown_model(tmp_path, "optimal")
    assert flight["breach_s"] == 0.0
    assert max(flight["max_T_winding"].values()) <= 104.0  # gen1 reaches 107 °C unmanaged
    assert flight["plans"] and all(plan["method"].startswith("optimal") for plan in flight["plans"])
    assert all(plan["backoff_K"] > 0.1 for plan in flight["plans"] if plan["feasible"])
    assert flight["displaced_Ah"] > 0.0


def test_shed_on_the_flown_model_serves_all_it_can_within_thetamax(believed, design_model):
    """No rest left and both generators hot at full load: the manager sheds the least load that
    keeps θmax with the back-off, instead of switching generators off."""
    models, filters = believed
    generators = [AffineGenerator(design_model.with_effect("coolant_flow_reduction", **BLOCKAGE)),
                  AffineGenerator(design_model)]
    x0 = [np.full(models[0].n_states, 100.0), np.full(models[1].n_states, 100.0)]
    segments = split_segments([Segment(5, "6 cruise_combat", 1200.0, ((0.0, 7.0),))], 300.0, 10.0)
    flown = _flown(filters, x0, CONVERGED * filters[0].P0)
    problem = dataclasses.replace(_problem(generators, x0, segments, 110.0, flown), max_rest_s=0.0, rest_budget_s=0.0)
    managed = plan_with("optimal", problem, ManagerSettings(planner_model="nonlinear"), ("gen1", "gen2"), 110.0)
    assert managed.method == "shed" and not managed.feasible
    assert not managed.schedule.switched_off.any()
    not_served = managed.schedule.displaced_A.sum(axis=0)
    assert not_served.max() > 0.1 and not_served.min() >= -1e-6
    assert managed.peak_C <= 110.0 + 0.05  # its own prediction, back-off included
    assert managed.schedule.displaced_A[:, -1].max() < 7.0  # and it still serves load


def test_design_model_shedding_of_a_flown_problem_is_posed_and_judged_on_the_design_model(believed, design_model):
    """When the nonlinear planner's own shedding finds no plan (or a generator is off), the
    manager sheds on the design models within θmax minus the margin, as the affine planner: the
    shed plan's receivers are predicted on the design model (before, with the flown filters still
    in the problem, the prediction of one receiver raised an IndexError) and the plan is judged
    there, not on the flown model with its back-off."""
    from genthermal.schedule.flight.replanning import on_design_model
    from genthermal.schedule.planning.shed import shed_plan

    models, filters = believed
    generators = [AffineGenerator(design_model.with_effect("coolant_flow_reduction", **BLOCKAGE)),
                  AffineGenerator(design_model)]
    x0 = [np.full(models[0].n_states, 100.0), np.full(models[1].n_states, 80.0)]
    segments = split_segments([Segment(5, "6 cruise_combat", 600.0, ((0.0, 5.0),)),
                               Segment(7, "7 landing", 600.0, ((0.0, 5.0),))], 300.0, 10.0)
    problem = _problem(generators, x0, segments, 110.0, _flown(filters, x0, CONVERGED * filters[0].P0))
    settings = ManagerSettings(planner_model="nonlinear")
    design = on_design_model(problem, settings, 110.0)
    assert design.flown is None and design.limit_C == pytest.approx(110.0 - settings.margin_K)
    assert design.rise_backoff == settings.rise_backoff
    assert on_design_model(design, settings, 110.0) is design
    shed_plan(problem, np.array([True, False]), settings.margin_K)  # receivers predicted on the design model
    shed = shed_plan(design, np.array([True, False]), settings.margin_K)
    assert shed.schedule.displaced_A[1].min() < -0.1  # gen2 takes gen1's load ...
    assert shed.peak_C <= design.limit_C + 0.05  # ... within the design model's planning limit
    managed = plan_with("optimal", problem, settings, ("gen1", "gen2"), 110.0, switched_off=[True, False])
    assert managed.method == "shed" and managed.peak_C == pytest.approx(shed.peak_C)


def test_control_intervals_are_whole_steps_and_keep_the_mission_length():
    """The 49-min cruise piece of ``blockage_large`` cut into 5-min intervals gives ten windows of
    294 s; each is put on whole 10-s steps, so the timeline of the cut mission is exactly as long
    as the mission (it lost 4 s per window, and the nonlinear planner's flight ended 40 s early)."""
    segment = Segment(4, "5 cruise", 3240.0, ((0.0, 5.831), (300.0, 4.9)))
    split = split_segments([segment], 300.0, 10.0)
    lengths = np.array([s.duration_s for s in split])
    assert np.allclose(lengths / 10.0, np.round(lengths / 10.0)) and np.all(lengths <= 300.0 + 5.0)
    assert np.isclose(lengths.sum(), segment.duration_s)
    assert [s.levels[0][1] for s in split] == [5.831] + [4.9] * 10
    assert build_timeline(split, Schedule.nominal(1, len(split)), 1.9, 10.0).n_steps == 324


@pytest.mark.parametrize("shed", [False, True])
def test_padded_horizon_poses_no_more_equalities_than_variables(believed, design_model, shed):
    """Padding segments fix their displacements and rests; their load-balance rows then have no free
    variable and must not be posed as equalities (0 = 0). Counted as CasADi counts them (fixed
    variables and equality rows), the NLP has at most as many equalities as variables; before, a
    2-segment problem padded to 16 posed 14 redundant rows and CasADi warned it was overconstrained."""
    models, filters = believed
    generators = [AffineGenerator(design_model.with_effect("coolant_flow_reduction", **BLOCKAGE)),
                  AffineGenerator(design_model)]
    x0 = [np.full(models[0].n_states, 85.0), np.full(models[1].n_states, 60.0)]
    segments = [Segment(4, "5 cruise", 300.0, ((0.0, 4.9),)), Segment(7, "7 landing", 300.0, ((0.0, 5.0),))]
    problem = _problem(generators, x0, segments, 110.0, _flown(filters, x0, CONVERGED * filters[0].P0))
    transcription = FlownTranscription(problem, NonlinearSettings(), shed=shed)
    assert transcription.N_seg > len(segments)  # the case is padded
    lbw, ubw, lbg, ubg = transcription._bounds(np.zeros((2, len(filters[0].model.output_names), len(segments))))
    equalities = int(np.sum(lbw == ubw) + np.sum(lbg == ubg))
    assert equalities <= lbw.size
    balance = slice(transcription.n_equalities_expected - transcription.N_seg, transcription.n_equalities_expected)
    assert np.all(np.isinf(ubg[balance][len(segments):]))  # padding: free rows
    assert np.all(lbg[balance][:len(segments)] == 0.0)  # real segments: balanced (or shed: >= 0)


def test_solver_cache_keeps_only_the_most_recently_used_structures(believed, design_model, monkeypatch):
    """Each structure's solver is cached on the filters, but only the most recent
    ``MAX_CACHED_SOLVERS``: a long flight whose re-plans kept changing the structure built one
    solver per re-plan and held them all (a grid worker passed 10 GB). A structure used again is
    kept, the least recently used one goes, and an evicted one is rebuilt when needed."""
    import genthermal.schedule.planning.optimal_nlp as optimal_nlp

    models, _ = believed
    filters = [ExtendedKalmanFilter(m, 10.0) for m in models]  # a cache of their own
    generators = [AffineGenerator(design_model), AffineGenerator(design_model)]
    x0 = [np.full(models[0].n_states, 85.0), np.full(models[1].n_states, 60.0)]
    segments = [Segment(4, "5 cruise", 300.0, ((0.0, 4.9),)), Segment(7, "7 landing", 300.0, ((0.0, 5.0),))]
    problem = _problem(generators, x0, segments, 110.0, _flown(filters, x0))
    builds = []
    monkeypatch.setattr(optimal_nlp, "MAX_CACHED_SOLVERS", 3)
    monkeypatch.setattr(FlownTranscription, "_build", lambda self: builds.append(self._key()) or object())

    def solver(max_iter):  # max_iter is part of the structure's key
        return FlownTranscription(problem, NonlinearSettings(max_iter=max_iter))._solver()

    first = solver(100)
    for max_iter in (101, 102):
        solver(max_iter)
    assert solver(100) is first and len(builds) == 3  # used again: not rebuilt, now the most recent
    solver(103)  # evicts 101, the least recently used
    cache = filters[0].__dict__["_planning_solvers"]
    assert len(cache) == 3
    assert solver(100) is first and len(builds) == 4
    solver(101)
    assert len(builds) == 5 and len(cache) == 3  # 101 was evicted: built again
