"""Mission documents shared by the closed-loop tests (imported by test modules, not a test)."""

#: One hour, two generators, gen1's coolant nearly blocked from 10 min (internal convection held,
#: inlet +31 K): a short flight that still needs the load manager.
SHORT = """name: short_blockage
generators: {count: 2}
faults:
  - {generator: 1, kind: coolant_blockage, onset_min: 10, k_flow: 0.2, n_flow: 0.0, inlet_rise_C: 31}
actions:
  - {condition: taxi, duration_min: 15}
  - {condition: cruise_combat, duration_min: 30}
  - {condition: landing, duration_min: 15}
"""


def fly_short_on_the_flown_model(tmp_path, scheduler: str) -> dict:
    """:data:`SHORT` with θmax 104 °C flown by ``genthermal fly`` with ``scheduler`` planning on the
    flown model, the fault told; the flight's JSON record."""
    import json

    from genthermal.cli import main

    scenario = tmp_path / "short.yaml"
    scenario.write_text(SHORT.replace("generators: {count: 2}", "generators: {count: 2, limit_C: 104}"))
    out = tmp_path / "flight.json"
    assert main(["fly", str(scenario), "--scheduler", scheduler, "--planner-model", "nonlinear", "--tell-fault",
                 "--json", str(out)]) == 0
    return json.loads(out.read_text())
