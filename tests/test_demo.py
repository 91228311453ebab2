"""The main job, ``genthermal demo``, end to end on the built-in defaults."""

import json

import pytest

from genthermal.cli import main


def test_demo_runs_end_to_end(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path)]) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["model"]["nodes"] == {"all_nodes": 19, "without_intermediate": 12, "states": 8}
    assert summary["simulation"]["peak_T_winding"] < 110.0
    assert summary["blockage"]["peak_T_winding"] > 110.0  # the fault the load management must fix
    if summary["c_library"]["compiled"]:
        assert summary["c_library"]["max_abs_difference_K"] < 1e-9
    assert max(summary["estimation"]["filter_rmse"].values()) < 1.0
    for minutes in summary["estimation"]["improved_minutes"].values():
        assert min(minutes.values()) >= 20.0
    for summary_of_flight in summary["load_management"]["summaries"].values():
        assert summary_of_flight["breach_s"] == 0
    flights = summary["load_management"]["summaries"]
    discovery = summary["discovery"]
    assert discovery["verdict"] != "none" and discovery["rmse_after"] < 0.2 * discovery["rmse_before"]
    for picture in ("mission_healthy.png", "blockage.png", "design_vs_simulation.png", "prediction.png"):
        assert (tmp_path / picture).stat().st_size > 10_000
    assert "Kalman filter" in capsys.readouterr().out
    if flights["optimal"]["added_rest_s"] > flights["heuristic"]["added_rest_s"]:
        pytest.xfail("known regression since offset-free planning (issue 9): on blockage_large (seed 0) the optimal "
                     "flight rests 58.7 min, the heuristic's 35 min: at 200-215 min IPOPT finds no feasible schedule "
                     "and the fallback flies the min-max schedule with a 54.8-min rest (seeds 1 and 2: optimal 6.3 "
                     "and 6.7 min, heuristic 30 and 30 min)")
