"""The hindsight plan: the least rest with the true plant and its fault known from the onset."""

import pytest

from genthermal.errors import InputError
from genthermal.mission import load_mission
from genthermal.schedule.sweeps.hindsight import hindsight_plan, hindsight_problem, hindsight_schedule
from genthermal.schedule.planning.plan import build_timeline, generator_inputs
from genthermal.simulate import simulate
from genthermal.schedule.power_system import PowerSystem

from flight_scenarios import SHORT


def _system(tmp_path, text):
    path = tmp_path / "scenario.yaml"
    path.write_text(text)
    return PowerSystem.from_mission(load_mission(str(path)))


def test_hindsight_plans_the_true_plant_from_the_onset_within_thetamax(tmp_path):
    system = _system(tmp_path, SHORT)  # gen1 blocked from 10 min, inlet +31 K
    problem = hindsight_problem(system)
    assert problem.flown is not None and problem.limit_C == system.limit_C and problem.rise_backoff == 0.0
    assert problem.flown.confidence_sigmas == 0.0  # no back-off: everything is known
    assert problem.inlet_C[0] == pytest.approx(system.mission.T_inlet_C + 31.0)
    assert sum(s.duration_s for s in problem.segments) == pytest.approx(system.mission.duration_s - 600.0)
    assert max(s.duration_s for s in problem.segments) <= 300.0 + 1e-9  # one control interval each
    planned = hindsight_schedule(problem)
    assert planned.peak_C <= system.limit_C + 0.1
    # flown on the true plant (the simulator, not the planner's own step), the plan holds θmax
    timeline = build_timeline(problem.segments, planned.schedule, system.rest_current_A, problem.dt_s)
    faults = tuple(range(len(system.faults)))
    for g in range(system.n_generators):
        model = system.plant_model(g, faults)
        frame = generator_inputs(timeline, g, 600.0, lambda t, g=g: system.inlet_C(g, t), system.mission.T_ambient_C,
                                 system.mission.power_factor, system.rated_current_A, model.spec.interface.generator)
        run = simulate(model, frame, x0=problem.flown.z0[g][:model.n_states])
        assert run[list(model.output_names)].to_numpy().max() <= system.limit_C + 0.2
    result = hindsight_plan(system)
    assert result.onset_s == 600.0 and result.rest_s == pytest.approx(planned.schedule.added_rest_s)
    assert result.served_all == (result.not_served_Ah == 0.0)
    none_left = hindsight_plan(system, rest_budget_s=0.0)  # no rest allowed: load goes unserved instead
    assert none_left.rest_s == 0.0
    assert none_left.not_served_Ah >= result.not_served_Ah


def test_hindsight_needs_a_fault(tmp_path):
    healthy = SHORT.split("faults:")[0] + "actions:" + SHORT.split("actions:")[1]
    with pytest.raises(InputError, match="faults"):
        hindsight_problem(_system(tmp_path, healthy))


def test_hindsight_margin_lowers_the_limit_and_is_checked(tmp_path):
    system = _system(tmp_path, SHORT)
    assert hindsight_problem(system, margin_K=2.5).limit_C == system.limit_C - 2.5
    with pytest.raises(InputError, match="margin_K"):
        hindsight_problem(system, margin_K=-1.0)
