"""Regenerate the README's pictures: run ``genthermal demo`` and copy the figures it draws.

Run ``python benchmarks/readme_figures.py`` from the repository root.
"""

import shutil
import sys
import tempfile
from pathlib import Path

from genthermal.cli import main as genthermal

FIGURES = {
    "mission_healthy.png": "mission_healthy.png",
    "blockage.png": "blockage.png",
    "design_vs_simulation.png": "design_vs_simulation.png",
    "prediction.png": "prediction.png",
    "load_management/schedule_heuristic.png": "schedule_heuristic.png",
    "load_management/schedule_optimal.png": "schedule_optimal.png",
    "discovery/diagnose/round_1_overlay.png": "discovery_overlay.png",
}


def main() -> int:
    target = Path(__file__).resolve().parent / "figures"
    target.mkdir(exist_ok=True)
    with tempfile.TemporaryDirectory() as folder:
        if genthermal(["demo", "--out", folder]) != 0:
            return 1
        for source, name in FIGURES.items():
            shutil.copyfile(Path(folder) / source, target / name)
            print(f"wrote {target / name}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
