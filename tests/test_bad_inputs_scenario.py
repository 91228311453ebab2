"""Bad scenario (mission) files: one table row per case; a new bad input is one more row.

Each must end in exit code 2 with one line naming the field, before any simulation or output.
"""

import pytest

from genthermal.cli import main

# (case, file content (text or bytes), text the error must contain)
BAD_SCENARIOS = [
    ("empty file", "", "mapping"),
    ("binary file", b"\x00\xff\xfe\x00PK\x03\x04" * 20, "cannot read"),
    ("a list, not a mapping", "- {condition: 1, duration_min: 20}\n", "mapping"),
    ("YAML syntax error", "name: x\nactions: [\n", "line"),
    ("no name", "actions:\n  - {condition: 1, duration_min: 20}\n", "name"),
    ("no actions", "name: x\n", "actions"),
    ("empty actions", "name: x\nactions: []\n", "actions"),
    ("unknown top-level key", "name: x\nactoins: []\n", "actoins"),
    ("unknown action key", "name: x\nactions:\n  - {condition: 5, duraton_min: 20}\n", "duraton_min"),
    ("condition out of range", "name: x\nactions:\n  - {condition: 9, duration_min: 20}\n", "actions[0].condition"),
    ("condition misspelt", "name: x\nactions:\n  - {condition: cruse, duration_min: 20}\n", "cruise"),
    ("duration as text", "name: x\nactions:\n  - {condition: 5, duration_min: thirty}\n", "duration_min"),
    ("duration true", "name: x\nactions:\n  - {condition: 5, duration_min: true}\n", "duration_min"),
    ("duration negative", "name: x\nactions:\n  - {condition: 5, duration_min: -30}\n", "duration_min"),
    ("duration .nan", "name: x\nactions:\n  - {condition: 5, duration_min: .nan}\n", "duration_min"),
    ("duration of 1e12 min", "name: x\nactions:\n  - {condition: 5, duration_min: 1.0e+12}\n", "samples"),
    ("load above 120 %", "name: x\nactions:\n  - {load_percent: 500, duration_min: 20}\n", "load_percent"),
    ("phase share of 100", "name: x\nactions:\n  - {condition: 5, duration_min: 30, phase_share: [100, 100, 100]}\n",
     "phase_share[0]"),
    ("phase share of two phases", "name: x\nactions:\n  - {condition: 5, duration_min: 30, phase_share: [1, 1]}\n",
     "phase_share"),
    ("phase share zero", "name: x\nactions:\n  - {condition: 5, duration_min: 30, phase_share: [1, 0, 1]}\n",
     "phase_share[1]"),
    ("rated current zero", "name: x\nrated_current_A: 0\nactions:\n  - {condition: 5, duration_min: 30}\n",
     "rated_current_A"),
    ("inlet at 500 °C", "name: x\nT_inlet_C: 500\nactions:\n  - {condition: 5, duration_min: 30}\n", "T_inlet_C"),
    ("inlet as text", "name: x\nT_inlet_C: warm\nactions:\n  - {condition: 5, duration_min: 30}\n", "T_inlet_C"),
    ("a key given twice", "name: x\nname: y\nactions:\n  - {condition: 5, duration_min: 30}\n", "given twice"),
    ("brackets nested 5000 deep", "name: x\nd: " + "[" * 5000 + "]" * 5000 + "\n", "nested too deeply"),
]

FLEET = "name: x\ngenerators: {{count: 2}}\nfaults:\n  - {}\nactions:\n  - {{condition: 5, duration_min: 30}}\n"
# the generators and faults of a fleet scenario, read by plan and fly (same promise)
BAD_FLEET_SCENARIOS = [
    ("fault after the mission's end", FLEET.format("{generator: 1, kind: coolant_blockage, onset_min: 1000, k_flow: 0.5}"),
     "would never happen"),
    ("fault on generator 3 of 2", FLEET.format("{generator: 3, kind: coolant_blockage, onset_min: 10, k_flow: 0.5}"),
     "faults[0].generator"),
    ("unknown fault kind", FLEET.format("{generator: 1, kind: fire, onset_min: 10}"), "faults[0].kind"),
]


@pytest.mark.parametrize("content, named", [c[1:] for c in BAD_SCENARIOS], ids=[c[0] for c in BAD_SCENARIOS])
def test_bad_scenario_exits_2_naming_the_field(content, named, tmp_path, capsys):
    path = tmp_path / "mission.yaml"
    path.write_bytes(content if isinstance(content, bytes) else content.encode())
    out = tmp_path / "sim.csv"
    assert main(["simulate", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize("content, named", [c[1:] for c in BAD_FLEET_SCENARIOS],
                         ids=[c[0] for c in BAD_FLEET_SCENARIOS])
def test_bad_fleet_scenario_exits_2_naming_the_field(content, named, tmp_path, capsys):
    path = tmp_path / "fleet.yaml"
    path.write_text(content)
    assert main(["plan", str(path)]) == 2
    err = capsys.readouterr().err
    assert named in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_scenario_that_is_a_folder(tmp_path, capsys):
    folder = tmp_path / "missions.yaml"
    folder.mkdir()
    assert main(["simulate", str(folder), "--out", str(tmp_path / "x.csv")]) == 2
    assert "Traceback" not in capsys.readouterr().err
