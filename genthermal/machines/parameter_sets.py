"""Shipped parameter sets of a built-in machine: ``load_model("genco_rf201a:chapter7")`` reads one.

``chapter7`` is the calibration fitted to the thesis's chapter-7 outcomes (the study that writes it
is ``studies/chapter7_feasibility.py``; its figures are in docs/results/thesis-reproduction.md).
"""

from __future__ import annotations

from importlib import resources

#: Parameter set name → its file beside this module.
PARAMETER_SET_FILES = {"chapter7": "genco_rf201a_chapter7.yaml"}


def parameter_file(name: str = "chapter7"):
    """The shipped file (a Traversable) of the parameter set ``name`` (a key of :data:`PARAMETER_SET_FILES`)."""
    return resources.files(__package__).joinpath(PARAMETER_SET_FILES[name])
