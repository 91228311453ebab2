"""The robustness sweep: its cases differ from the planning model, and its summary keys."""

import pytest

from genthermal.cli import main
from genthermal.mission import Mission
from genthermal.schedule.power_system import PowerSystem
from genthermal.schedule.sweeps.sweep import FAULT_TYPES, robustness_case, summarise


def test_cases_cover_the_grid_and_differ_from_the_planning_model():
    cases = [robustness_case(i) for i in range(60)]
    systems = [PowerSystem.from_mission(Mission.from_dict(c)) for c in cases]
    assert {c["name"].split(":")[1] for c in cases} == set(FAULT_TYPES)
    assert {s.n_generators for s in systems} == {2, 3, 4}
    hours = [s.mission.duration_s / 3600 for s in systems]
    assert 2.0 <= min(hours) and max(hours) <= 8.0 + 1e-9
    factors = [f for s in systems for f in s.plant_mismatch.values()]
    assert min(factors) < 0.8 and max(factors) > 1.2 and all(0.7 - 1e-9 <= f <= 1.3 + 1e-9 for f in factors)
    assert robustness_case(7) == robustness_case(7) != robustness_case(7, seed=1)


def run(breach, rest, delay=None, alarms=0):
    return {"status": "ok", "wall_s": 1.0, "breach_s": breach, "added_rest_s": rest, "detect_delay_s": delay,
            "false_alarms": alarms}


def test_summary_keys_and_the_best_baseline_ratio():
    records = [
        {"name": "a", "faulty": True, "runs": {"heuristic": run(0, 600), "engineer": run(0, 300),
                                               "optimal": run(20, 150, 300.0)}},
        {"name": "b", "faulty": False, "runs": {"heuristic": run(0, 0), "engineer": run(0, 0),
                                                "optimal": run(0, 0, None, 1)}},
        {"name": "c", "faulty": True, "runs": {"heuristic": run(0, 0), "engineer": run(0, 4.0),  # rounding, no rest
                                               "optimal": run(0, 120, 600.0)}},
    ]
    summary = summarise(records, ("heuristic", "engineer", "optimal"))
    assert summary["robustness"]["cases"] == 3
    assert summary["robustness"]["breach_s"]["optimal"] == 20
    assert summary["robustness"]["breached_cases"]["optimal"] == {"a": 20}
    assert summary["robustness"]["breach_free_fraction"]["optimal"] == pytest.approx(2 / 3)
    rest = summary["rest_vs_best_baseline"]
    assert rest["per_case"][0] == {"case": "a", "optimal_rest_s": 150.0, "best_baseline": "engineer",
                                   "best_baseline_rest_s": 300.0, "ratio": pytest.approx(0.5),  # not the thesis heuristic
                                   "optimal_not_served_Ah": 0.0, "best_baseline_not_served_Ah": 0.0,
                                   "hindsight_rest_s": None, "hindsight_not_served_Ah": None,
                                   "optimal_cost_min": 2.5, "best_baseline_by_cost": "engineer",
                                   "best_baseline_cost_min": 5.0, "cost_vs_best_baseline": pytest.approx(0.5),
                                   "sheds": False}
    assert rest["per_case"][1]["ratio"] is None and rest["cases_optimal_rests_more"] == ["c"]
    assert rest["mean_ratio"] == pytest.approx(270 / 300)
    assert summary["detect_delay_s"]["median"] == 450.0 and summary["detect_delay_s"]["max"] == 600.0
    assert {"case": "a", "scheduler": "heuristic"} in summary["detect_delay_s"]["not_detected"]
    assert summary["false_alarms"]["on_healthy_flights"] == 1


def test_rest_is_the_time_rested_and_one_step_more_is_more(monkeypatch):
    """``rested_s`` (whole steps flown in the minimum power mode) is the rest when a record has it,
    not the mission time over the nominal duration (the actions' rounding to the step); a flight
    that never re-planned rested none; and one 10-s step more than the best baseline is more."""
    def flown(rested, added, replans=3, not_served=0.0):
        return {**run(0, added), "rested_s": rested, "replans": replans,
                "shed": {"not_served_Ah": {"gen1": not_served, "gen2": 0.0}}}
    records = [{"name": "x", "faulty": True, "hindsight": {"rest_s": 30.0, "not_served_Ah": 0.1},
                "runs": {"heuristic": flown(60.0, 52.0), "engineer": flown(50.0, 42.0, not_served=0.5),
                         "optimal": flown(60.0, 52.0)}},
               {"name": "y", "faulty": True,
                "runs": {"heuristic": {**run(0, 14.0), "replans": 0}, "engineer": {**run(0, 14.0), "replans": 0},
                         "optimal": {**run(0, 14.0), "replans": 0}}}]
    rest = summarise(records, ("heuristic", "engineer", "optimal"))["rest_vs_best_baseline"]
    x, y = rest["per_case"]
    assert (x["optimal_rest_s"], x["best_baseline"], x["best_baseline_rest_s"]) == (60.0, "engineer", 50.0)
    assert (x["best_baseline_not_served_Ah"], x["hindsight_rest_s"], x["hindsight_not_served_Ah"]) == (0.5, 30.0, 0.1)
    assert y["optimal_rest_s"] == y["best_baseline_rest_s"] == 0.0  # 14 s of rounding, no re-plan: no rest
    assert rest["cases_optimal_rests_more"] == ["x"]


def test_cost_at_the_managers_price_when_one_scheduler_sheds_and_another_rests():
    """Case s: the heuristic rests 65 min and leaves 0.69 A·h unserved, the engineer rests 100 min
    and leaves 0.65 A·h, the optimal scheduler as the engineer: by rest the heuristic is the best
    baseline (ratio 100/65), by the price (rest min + 1000 min per A·h) the engineer (755 against
    750 min: the 35 more minutes save 0.04 A·h). Case q: nobody sheds; only there the rest ratio
    without shedding counts."""
    def flown(rested_min, not_served_Ah):
        return {**run(0, 60.0 * rested_min), "rested_s": 60.0 * rested_min, "replans": 5,
                "shed": {"not_served_Ah": {"gen1": not_served_Ah, "gen2": 0.0}}}
    records = [{"name": "s", "faulty": True, "runs": {"heuristic": flown(65, 0.69), "engineer": flown(100, 0.65),
                                                      "optimal": flown(100, 0.65)}},
               {"name": "q", "faulty": True, "runs": {"heuristic": flown(20, 0.0), "engineer": flown(10, 0.0),
                                                      "optimal": flown(4, 0.0)}}]
    rest = summarise(records, ("heuristic", "engineer", "optimal"))["rest_vs_best_baseline"]
    s, q = rest["per_case"]
    assert (s["best_baseline"], s["ratio"]) == ("heuristic", pytest.approx(100 / 65))
    assert s["best_baseline_by_cost"] == "engineer" and s["sheds"]
    assert s["optimal_cost_min"] == pytest.approx(750.0) and s["best_baseline_cost_min"] == pytest.approx(750.0)
    assert s["cost_vs_best_baseline"] == pytest.approx(1.0)
    assert rest["cases_optimal_rests_more"] == ["s"] and rest["cases_optimal_costs_more"] == []
    assert rest["mean_ratio"] == pytest.approx(104 / 75)  # the key: rest only
    assert rest["without_shedding"] == {"cases": 1, "mean_ratio": pytest.approx(0.4),
                                        "optimal_total_rest_s": 240.0, "best_baseline_total_rest_s": 600.0}
    assert rest["mean_cost_ratio"] == pytest.approx(754 / 760)
    # the optimal flight shedding 0.01 A·h more to rest 5 min less costs more
    records[0]["runs"]["optimal"] = flown(95, 0.66)
    rest = summarise(records, ("heuristic", "engineer", "optimal"))["rest_vs_best_baseline"]
    assert rest["cases_optimal_costs_more"] == ["s"] and rest["cases_optimal_rests_more"] == ["s"]
    assert rest["per_case"][0]["cost_vs_best_baseline"] == pytest.approx(755 / 750)


def test_hindsight_records_join_their_case():
    import genthermal.schedule.sweeps.sweep as sweep

    document = robustness_case(5)
    flights = [{"case": document["name"], "scheduler": sweep.HINDSIGHT, "status": "ok",
                "hindsight": {"rest_s": 120.0, "not_served_Ah": 0.0}},
               {"case": "elsewhere", "scheduler": sweep.HINDSIGHT, "status": "error", "error": "boom"}]
    record = sweep.case_records([document, robustness_case(6)], flights, ("optimal",))
    assert record[0]["hindsight"] == {"rest_s": 120.0, "not_served_Ah": 0.0}
    assert "hindsight" not in record[1]


def test_a_flight_that_fails_or_runs_too_long_is_reported_not_lost(monkeypatch):
    import genthermal.schedule.flight.closed_loop as closed_loop
    import genthermal.schedule.sweeps.sweep as sweep

    document = robustness_case(6)  # 2 generators, 4.5 h

    def broken(system, scheduler, settings, preflight=None):
        raise ZeroDivisionError("division by zero in a planner")
    monkeypatch.setattr(closed_loop, "fly", broken)
    failed = sweep.fly_flight(document, "engineer")
    assert failed["status"] == "error" and "ZeroDivisionError" in failed["error"] and failed["wall_s"] >= 0
    monkeypatch.undo()
    stopped = sweep.fly_flight(document, "engineer", cpu_limit_s=1e-3)
    assert stopped["status"] == "timeout" and "limit 0.001 s" in stopped["error"]
    records = sweep.case_records([document, robustness_case(9)], [failed, stopped], ("engineer", "optimal"))
    runs = records[0]["runs"]
    assert runs["engineer"]["status"] == "timeout" and runs["optimal"]["status"] == "unfinished"
    summary = summarise(records, ("engineer", "optimal"))
    assert summary["robustness"]["breach_free_fraction"] == {"engineer": 0.0, "optimal": 0.0}
    assert {(f["case"], f["scheduler"], f["status"]) for f in summary["robustness"]["failed_flights"]} >= {
        (document["name"], "engineer", "timeout"), (document["name"], "optimal", "unfinished")}


def test_cpu_limit_must_be_positive():
    from genthermal.schedule.flight.manager_settings import ManagerSettings

    with pytest.raises(ValueError, match="cpu_limit_s"):
        ManagerSettings(cpu_limit_s=0.0)


def test_sweep_rejects_an_unknown_scheduler(tmp_path, capsys):
    assert main(["sweep", "--cases", "1", "--schedulers", "engineer,magic", "--json", str(tmp_path / "s.json")]) == 2
    assert "--schedulers" in capsys.readouterr().err


def test_sweep_prints_json_without_a_file_and_writes_one_with_it(tmp_path, capsys, monkeypatch):
    import json

    import genthermal.schedule.sweeps.sweep as sweep
    records = [{"name": "a", "faulty": False, "runs": {"engineer": run(0, 0.0)}}]
    monkeypatch.setattr(sweep, "run_sweep", lambda documents, schedulers, *rest, **options: records)
    assert main(["sweep", "--cases", "1", "--schedulers", "engineer"]) == 0
    printed = json.loads(capsys.readouterr().out)
    assert printed["cases"] == records and printed["robustness"]["cases"] == 1
    assert printed["provenance"]["command"].startswith("genthermal sweep --cases 1 --schedulers engineer")
    target = tmp_path / "s.json"
    assert main(["sweep", "--cases", "1", "--schedulers", "engineer", "--json", str(target)]) == 0
    assert json.loads(target.read_text())["cases"] == records
    assert main(["sweep", "--cases", "1", "--schedulers", "engineer", "--json", str(target)]) == 2  # no --force
    assert main(["sweep", "--cases", "1", "--schedulers", "engineer", "--json", str(target), "--force"]) == 0


def test_a_flight_without_a_re_plan_is_every_schedulers_flight():
    """The scheduler is called only to re-plan: a flight that never re-planned, flown again with
    another scheduler, is the same flight (the sweep then reuses it)."""
    import genthermal.schedule.sweeps.sweep as sweep

    document = {"name": "case900:healthy:2gen:1.0h", "actions": [{"condition": c, "duration_min": 15} for c in (1, 2, 3, 5)],
                "generators": {"count": 2, "plant_mismatch": {"h_end_air": 1.2, "R0": 0.8}}, "faults": []}
    first, second = sweep.fly_case(document, ("heuristic", "engineer"))
    assert first["status"] == "ok" and first["summary"]["replans"] == 0
    assert second["same_flight_as"] == "heuristic" and second["summary"]["scheduler"] == "engineer"
    flown = sweep.fly_flight(document, "engineer")
    assert flown["summary"] == second["summary"]
    runs = sweep.case_records([document], [first, second], ("heuristic", "engineer"))[0]["runs"]
    assert runs["engineer"]["same_flight_as"] == "heuristic" and "same_flight_as" not in runs["heuristic"]


def test_sweep_only_flies_the_named_cases_of_the_grid_and_checks_them(monkeypatch, capsys):
    import json

    import genthermal.schedule.sweeps.sweep as sweep
    flown = {}

    def fake(documents, schedulers, *rest, **options):
        flown["names"], flown["planner"], flown["hindsight"] = [d["name"] for d in documents], rest[-2], rest[-1]
        return [{"name": d["name"], "faulty": bool(d["faults"]), "runs": {"engineer": run(0, 0.0)}} for d in documents]
    monkeypatch.setattr(sweep, "run_sweep", fake)
    assert main(["sweep", "--cases", "20", "--only", "15,3", "--schedulers", "engineer", "--planner-model",
                 "nonlinear"]) == 0
    assert flown["names"] == [robustness_case(15)["name"], robustness_case(3)["name"]]  # the grid's own cases
    assert flown["planner"] == "nonlinear" and flown["hindsight"] is True
    provenance = json.loads(capsys.readouterr().out)["provenance"]
    assert "--only 15,3" in provenance["command"] and provenance["optimal_planner_model"] == "nonlinear"
    assert main(["sweep", "--cases", "20", "--only", "3", "--schedulers", "engineer", "--no-hindsight"]) == 0
    assert flown["hindsight"] is False and "--no-hindsight" in json.loads(capsys.readouterr().out)["provenance"]["command"]
    for only, message in (("15,x", "indices"), ("20", "not in the grid"), ("3,3", "more than once"), ("", "indices")):
        assert main(["sweep", "--cases", "20", "--only", only, "--schedulers", "engineer"]) == 2
        error = capsys.readouterr().err
        assert "--only" in error and message in error


def test_schedulers_share_a_flight_only_when_they_plan_on_the_same_model():
    import genthermal.schedule.sweeps.sweep as sweep

    assert sweep.planner_model_of("optimal", "nonlinear") == "nonlinear"
    assert sweep.planner_model_of("engineer", "nonlinear") == "affine"
    document = {"name": "case901:healthy:2gen:1.0h", "actions": [{"condition": c, "duration_min": 15} for c in (1, 2, 3, 5)],
                "generators": {"count": 2, "plant_mismatch": {"h_end_air": 1.2, "R0": 0.8}}, "faults": []}
    first, second, third = sweep.fly_case(document, ("heuristic", "optimal", "engineer"), optimal_planner_model="nonlinear")
    assert first["summary"]["replans"] == 0 and "same_flight_as" not in second  # another re-plan test: flown
    assert second["planner_model"] == "nonlinear" and second["status"] == "ok"
    assert third["same_flight_as"] == "heuristic"
    with pytest.raises(Exception, match="optimal_planner_model"):
        sweep.run_sweep([], ("optimal",), optimal_planner_model="quadratic")


def test_robustness_report_merges_a_re_fly_into_the_grid(tmp_path, capsys, benchmark_script):
    """A partial re-fly replaces its cases of the whole grid and every summary key is recomputed
    from the merged cases; a re-fly of another grid or other schedulers is refused."""
    import json

    report_module = benchmark_script("robustness_report")
    schedulers = ("heuristic", "engineer", "optimal")

    def grid(cases):
        return {**summarise(cases, schedulers), "provenance": {"command": "whole"}, "cases": cases}
    old = [{"name": "case0:a", "faulty": True, "runs": {"heuristic": run(0, 600), "engineer": run(0, 300),
                                                  "optimal": run(50, 400)}},
           {"name": "case1:b", "faulty": True, "runs": {s: run(0, 0) for s in schedulers}}]
    new_a = {"name": "case0:a", "faulty": True, "runs": {"heuristic": run(0, 600), "engineer": run(0, 300),
                                                   "optimal": run(0, 200)}}
    whole, refly = tmp_path / "grid.json", tmp_path / "refly.json"
    whole.write_text(json.dumps(grid(old)))
    refly.write_text(json.dumps({**grid([new_a]), "provenance": {"command": "refly a"}}))
    assert report_module.main([str(whole), "--merge", str(refly), "--png", str(tmp_path / "g.png")]) == 0
    merged = json.loads(whole.read_text())
    assert [c["name"] for c in merged["cases"]] == ["case0:a", "case1:b"] and merged["cases"][0]["runs"]["optimal"]["added_rest_s"] == 200
    assert merged["robustness"]["breach_s"]["optimal"] == 0 and merged["rest_vs_best_baseline"]["mean_ratio"] == pytest.approx(200 / 300)
    assert merged["provenance"]["command"] == "whole" and merged["provenance"]["merged"][0]["cases"] == ["case0:a"]
    out = capsys.readouterr().out
    assert "| case0:a | 3.3 | 5.0 (engineer) | – | 0.00 / 0.00 / – | 3.3 / 5.0 (engineer) | 0.67 |" in out
    assert "Over the 2 cases where no scheduler sheds load: optimal 3.3 min, best baseline 5.0 min (ratio 0.67)" in out
    stranger = tmp_path / "stranger.json"
    stranger.write_text(json.dumps(grid([{**new_a, "name": "case9:z"}])))
    assert report_module.main([str(whole), "--merge", str(stranger), "--png", str(tmp_path / "g.png")]) == 2
    assert "not in the grid" in capsys.readouterr().err
    # a re-fly of the optimal scheduler alone replaces its flight and keeps the baselines'
    optimal_only = [{"name": "case1:b", "faulty": True, "runs": {"optimal": run(0, 60)}}]
    alone = tmp_path / "alone.json"
    alone.write_text(json.dumps({**summarise(optimal_only, ("optimal",)), "provenance": {"command": "refly b"},
                                 "cases": optimal_only}))
    assert report_module.main([str(whole), "--merge", str(alone), "--png", str(tmp_path / "g.png")]) == 0
    merged = json.loads(whole.read_text())
    assert merged["cases"][1]["runs"]["optimal"]["added_rest_s"] == 60
    assert merged["cases"][1]["runs"]["heuristic"] == run(0, 0) and merged["provenance"]["merged"][1]["schedulers"] == ["optimal"]
    capsys.readouterr()
    milp = [{"name": "case1:b", "faulty": True, "runs": {"milp": run(0, 0)}}]
    alone.write_text(json.dumps({**summarise(milp, ("milp",)), "cases": milp}))
    assert report_module.main([str(whole), "--merge", str(alone), "--png", str(tmp_path / "g.png")]) == 2
    assert "--add joins new ones" in capsys.readouterr().err


def test_robustness_report_cuts_a_grid_to_the_cases_a_partial_re_fly_flew(tmp_path, capsys, benchmark_script):
    """``--merged-only``: the optimal scheduler re-flown on case 0 alone is compared with case 0's
    baselines, not joined with the grid's own optimal flight of case 1."""
    import json

    report_module = benchmark_script("robustness_report")
    schedulers = ("heuristic", "engineer", "optimal")
    cases = [{"name": "case0:a", "faulty": True, "runs": {"heuristic": run(0, 600), "engineer": run(0, 300),
                                                    "optimal": run(0, 400)}},
             {"name": "case1:b", "faulty": True, "runs": {"heuristic": run(0, 100), "engineer": run(0, 100),
                                                    "optimal": run(30, 900)}}]
    refly = [{"name": "case0:a", "faulty": True, "runs": {"optimal": run(0, 150)}}]
    whole, partial = tmp_path / "grid.json", tmp_path / "refly.json"
    whole.write_text(json.dumps({**summarise(cases, schedulers), "provenance": {"command": "whole"}, "cases": cases}))
    partial.write_text(json.dumps({**summarise(refly, ("optimal",)), "provenance": {"command": "refly a"},
                                   "cases": refly}))
    assert report_module.main([str(whole), "--merge", str(partial), "--merged-only", "--png", str(tmp_path / "g.png")]) == 0
    cut = json.loads(whole.read_text())
    assert [c["name"] for c in cut["cases"]] == ["case0:a"] and cut["robustness"]["breach_s"]["optimal"] == 0
    assert cut["rest_vs_best_baseline"]["mean_ratio"] == pytest.approx(150 / 300)
    capsys.readouterr()


def test_the_flown_heuristic_counts_as_a_baseline_where_the_sweep_flew_it():
    """Case a: the heuristic on the flown model rests 100 s, less than the other two baselines, so
    it is the best baseline there; case b has no such flight and compares with the other two."""
    records = [{"name": "a", "faulty": True, "runs": {"heuristic": run(0, 600), "engineer": run(0, 300),
                                                      "heuristic_flown": run(0, 100), "optimal": run(0, 150)}},
               {"name": "b", "faulty": True, "runs": {"heuristic": run(0, 600), "engineer": run(0, 300),
                                                      "optimal": run(0, 150)}}]
    rest = summarise(records, ("heuristic", "engineer", "optimal"))["rest_vs_best_baseline"]
    (a, b) = rest["per_case"]
    assert (a["best_baseline"], a["best_baseline_rest_s"], a["ratio"]) == ("heuristic_flown", 100.0, pytest.approx(1.5))
    assert (b["best_baseline"], b["best_baseline_rest_s"]) == ("engineer", 300.0)
    assert rest["cases_optimal_rests_more"] == ["a"]


def test_the_sweep_flies_the_flown_heuristic_on_the_nonlinear_model():
    import genthermal.schedule.sweeps.sweep as sweep

    assert sweep.planner_model_of(sweep.FLOWN_HEURISTIC, "affine") == "nonlinear"
    assert sweep.FLOWN_HEURISTIC in sweep.SWEEP_SCHEDULERS


def test_the_sweep_flies_the_optimal_scheduler_on_the_flown_model_under_its_own_name():
    """``optimal_flown`` is the optimal scheduler planning on the nonlinear model whatever the
    sweep's ``--planner-model``, so one grid holds both optimal flights side by side."""
    import genthermal.schedule.sweeps.sweep as sweep

    assert sweep.FLOWN_OPTIMAL in sweep.SWEEP_SCHEDULERS
    assert sweep.planner_model_of(sweep.FLOWN_OPTIMAL, "affine") == "nonlinear"
    document = {"name": "case902:healthy:2gen:0.75h", "actions": [{"condition": c, "duration_min": 15} for c in (1, 3, 5)],
                "generators": {"count": 2, "plant_mismatch": {"h_end_air": 1.2}}, "faults": []}
    (flight,) = sweep.fly_case(document, (sweep.FLOWN_OPTIMAL,), optimal_planner_model="affine")
    assert flight["status"] == "ok", flight.get("error")
    assert (flight["scheduler"], flight["planner_model"]) == ("optimal_flown", "nonlinear")
    assert flight["summary"]["breach_s"] == 0
    # flown directly, with fly_flight's default design model, the name still decides the model
    # (it flew the optimal scheduler on the design model under the flown name)
    direct = sweep.fly_flight(document, sweep.FLOWN_OPTIMAL)
    assert direct["planner_model"] == "nonlinear" and direct["summary"] == flight["summary"]


def test_the_flown_optimal_scheduler_meets_the_same_baselines():
    """Its comparison is a key of its own, beside the optimal scheduler's, with the same best
    baseline per case (here the flown heuristic in case a, the engineer's in case b)."""
    records = [{"name": "a", "faulty": True, "runs": {"heuristic": run(0, 600), "engineer": run(0, 300),
                                                      "heuristic_flown": run(0, 100), "optimal": run(0, 150),
                                                      "optimal_flown": run(0, 50)}},
               {"name": "b", "faulty": True, "runs": {"heuristic": run(0, 600), "engineer": run(0, 300),
                                                      "heuristic_flown": run(0, 400), "optimal": run(0, 150),
                                                      "optimal_flown": run(0, 400)}}]
    summary = summarise(records, ("heuristic", "engineer", "heuristic_flown", "optimal", "optimal_flown"))
    flown, design = summary["flown_optimal_vs_best_baseline"], summary["rest_vs_best_baseline"]
    assert [c["best_baseline"] for c in flown["per_case"]] == [c["best_baseline"] for c in design["per_case"]]
    assert [c["optimal_rest_s"] for c in flown["per_case"]] == [50.0, 400.0]
    assert flown["mean_ratio"] == pytest.approx(450 / 400) and design["mean_ratio"] == pytest.approx(300 / 400)
    assert flown["cases_optimal_rests_more"] == ["b"]
    assert "flown_optimal_vs_best_baseline" not in summarise(records, ("heuristic", "engineer", "optimal"))


def test_robustness_report_adds_another_schedulers_flights(tmp_path, capsys, benchmark_script):
    """The same grid flown with the flown heuristic joins each case; the best baseline then counts
    it. Grids with other cases, or a scheduler flown in both, are refused."""
    import json

    report_module = benchmark_script("robustness_report")
    schedulers = ("heuristic", "engineer", "optimal")
    cases = [{"name": "case0:a", "faulty": True, "runs": {"heuristic": run(0, 600), "engineer": run(0, 300),
                                                        "optimal": run(0, 200)}}]
    whole, other = tmp_path / "grid.json", tmp_path / "flown.json"
    whole.write_text(json.dumps({**summarise(cases, schedulers), "provenance": {"command": "whole"}, "cases": cases}))
    flown_cases = [{"name": "case0:a", "faulty": True, "runs": {"heuristic_flown": run(0, 120)}}]
    other.write_text(json.dumps({**summarise(flown_cases, ("heuristic_flown",)), "provenance": {"command": "flown"},
                                 "cases": flown_cases}))
    assert report_module.main([str(whole), "--add", str(other), "--png", str(tmp_path / "g.png")]) == 0
    joined = json.loads(whole.read_text())
    assert set(joined["cases"][0]["runs"]) == {"heuristic", "engineer", "optimal", "heuristic_flown"}
    assert joined["rest_vs_best_baseline"]["per_case"][0]["best_baseline"] == "heuristic_flown"
    assert joined["rest_vs_best_baseline"]["mean_ratio"] == pytest.approx(200 / 120)
    assert joined["provenance"]["added"][0]["schedulers"] == ["heuristic_flown"]
    assert "| heuristic_flown | 1/1 |" in capsys.readouterr().out
    optimal_flown = tmp_path / "optimal_flown.json"
    optimal_flown_cases = [{"name": "case0:a", "faulty": True, "runs": {"optimal_flown": run(0, 60)}}]
    optimal_flown.write_text(json.dumps({**summarise(optimal_flown_cases, ("optimal_flown",)), "cases": optimal_flown_cases}))
    assert report_module.main([str(whole), "--add", str(optimal_flown), "--png", str(tmp_path / "g.png")]) == 0
    assert json.loads(whole.read_text())["flown_optimal_vs_best_baseline"]["mean_ratio"] == pytest.approx(60 / 120)
    out = capsys.readouterr().out
    assert "The optimal scheduler on the flown model (optimal_flown) against the same baselines" in out
    assert "| case0:a | 1.0 | 2.0 (heuristic_flown) |" in out
    assert report_module.main([str(whole), "--add", str(other), "--png", str(tmp_path / "g.png")]) == 2
    assert "both flew ['heuristic_flown']" in capsys.readouterr().err
    stranger = tmp_path / "stranger.json"
    stranger_cases = [{**flown_cases[0], "name": "case9:z", "runs": {"milp": run(0, 0)}}]
    stranger.write_text(json.dumps({**summarise(stranger_cases, ("milp",)), "cases": stranger_cases}))
    assert report_module.main([str(whole), "--add", str(stranger), "--png", str(tmp_path / "g.png")]) == 2
    assert "differ in their cases" in capsys.readouterr().err


def test_every_fault_the_grid_draws_lies_in_the_catalogue_plausible_range():
    """A fault drawn outside the range the diagnosis calls plausible is refused in flight (case 13
    once drew k_exc 147 against the catalogue's 100): the grid's faults must be nameable."""
    from genthermal.effects import CATALOGUE
    drawn = [(f["effect"], name, value) for i in range(60) for f in robustness_case(i)["faults"]
             if f["kind"] == "effect" for name, value in f["values"].items()]
    assert {effect for effect, _, _ in drawn} == {"phase_short_circuit", "end_winding_stray_loss", "excitation_iron_loss"}
    for effect, name, value in drawn:
        parameter = next(p for p in CATALOGUE[effect].parameters if p.name == name)
        assert parameter.is_plausible(value), (effect, name, value)
    k_exc = [value for effect, _, value in drawn if effect == "excitation_iron_loss"]
    assert max(k_exc) > 90.0  # the draw still reaches the severe end of the range
