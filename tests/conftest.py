"""Shared fixtures: the thesis generator models are built once per test session."""

import importlib.util
import os
import sys
from pathlib import Path

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")  # figures go to files in the tests, whatever the user's default
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the repository root: the studies/ package

from genthermal.design import linear_design_model
from genthermal.machines import build_model


@pytest.fixture(scope="session")
def plant_model():
    """Nonlinear simulation model of the thesis generator with its default parameters."""
    return build_model()


@pytest.fixture(scope="session")
def design_model(plant_model):
    """Linear design model (thesis 5.2) derived from the same network."""
    return linear_design_model(plant_model)


@pytest.fixture(scope="session")
def benchmark_script():
    """``benchmark_script(name)``: the script ``benchmarks/<name>.py`` loaded as a module (the
    benchmarks are scripts, not a package), once per test session."""
    loaded = {}

    def load(name: str):
        if name not in loaded:
            spec = importlib.util.spec_from_file_location(
                name, Path(__file__).resolve().parents[1] / "benchmarks" / f"{name}.py")
            loaded[name] = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(loaded[name])
        return loaded[name]

    return load


@pytest.fixture(autouse=True)
def _close_figures():
    """Close the figures a test opened: plotting functions return their figure to the caller, and
    pyplot keeps every one alive until it is closed (more than 20 made matplotlib warn)."""
    yield
    pyplot = sys.modules.get("matplotlib.pyplot")  # only if the test (or the code it ran) used it
    if pyplot is not None:
        pyplot.close("all")
