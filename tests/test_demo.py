"""The main job, ``genthermal demo``, end to end on the built-in defaults."""

import json

import pytest

from genthermal.cli import main


@pytest.mark.slow
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
    # before and after on the same sensors: the diagnosis's own first round, not compare's two sensors
    diagnosis = json.loads((tmp_path / "discovery" / "diagnose" / "diagnosis.json").read_text())
    assert discovery["rmse_before"] == diagnosis["iterations"][0]["rmse_before"]
    for picture in ("mission_healthy.png", "blockage.png", "design_vs_simulation.png", "prediction.png"):
        assert (tmp_path / picture).stat().st_size > 10_000
    assert "Kalman filter" in capsys.readouterr().out
    # the optimal scheduler plans on the flown model: it rests less than the thesis heuristic and
    # keeps every generator below θmax (its rest against the engineer's baseline is in docs/guide/scheduling.md)
    assert flights["optimal"]["added_rest_s"] < flights["heuristic"]["added_rest_s"]
    assert set(flights) == {"heuristic", "engineer", "optimal"}
    assert all(flight["breach_s"] == 0.0 for flight in flights.values())
