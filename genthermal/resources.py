"""Files shipped inside the package: C templates, scenarios and demo data.

There is one copy of each file. In the repository they live where a reader looks for them
(``codegen/`` and ``scenarios/`` at the top); ``genthermal/data/codegen`` and
``genthermal/data/scenarios`` are symbolic links to those folders, so a built wheel holds real
copies under ``genthermal/data/`` and an installed genthermal reads them from there through
:mod:`importlib.resources`, never from outside the package.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from .errors import GenthermalError

#: ``genthermal/data`` of the installed package.
PACKAGE_DATA = Path(str(resources.files("genthermal") / "data"))
#: C ABI templates, the example program, its Makefile and ``ABI.md``.
TEMPLATE_DIR = PACKAGE_DATA / "codegen"
#: Shipped mission scenarios, ``<name>.yaml``.
SCENARIO_DIR = PACKAGE_DATA / "scenarios"
#: Shipped measurement files.
DEMO_DATA_DIR = SCENARIO_DIR / "data"
#: A slice of a real bench motor's profile (MIT, Liu et al. 2024), its machine file and column map.
BENCH_MOTOR_DIR = PACKAGE_DATA / "bench_motor"


class MissingResourceError(GenthermalError):
    """A file that ships with genthermal is not where the installation should have put it."""


def shipped_file(path: Path) -> Path:
    """Return ``path`` (a file under :data:`PACKAGE_DATA`) or raise MissingResourceError.

    Raises
    ------
    MissingResourceError
        The installation lacks the file: a broken or partial install, with the fix in the message.
    """
    if not Path(path).is_file():
        raise MissingResourceError(f"{path} is missing from the genthermal installation; reinstall it "
                                   "(pip install --force-reinstall genthermal)")
    return Path(path)



def is_model_file(path: Path) -> bool:
    """True for a shipped YAML file that is a model file (a stand-in plant: a ``machine:`` key),
    False for a mission scenario."""
    return any(line.startswith("machine:") for line in Path(path).read_text(encoding="utf-8").splitlines())


def shipped_data_names(suffix: str) -> list[str]:
    """Names (without ``suffix``) of the shipped data files with that suffix: for ``.yaml`` the
    model files of stand-in plants (``rig_plant``), for ``.csv`` the records (``hidden_effect_demo``)."""
    paths = DEMO_DATA_DIR.glob(f"*{suffix}")
    return sorted(path.name[:-len(suffix)] for path in paths if suffix != ".yaml" or is_model_file(path))


def shipped_data_missions() -> list[str]:
    """Names of the mission scenarios shipped beside the data (``low_load_calibration``)."""
    return sorted(path.stem for path in DEMO_DATA_DIR.glob("*.yaml") if not is_model_file(path))


def shipped_data_file(reference: str, suffix: str) -> Path | None:
    """The shipped data file that ``reference`` names, when it is not a file here.

    ``reference`` is a bare name (``rig_plant``) or a file name (``rig_plant.yaml``) of a file in
    :data:`DEMO_DATA_DIR` with ``suffix``; an existing file, a path with folders or an unknown
    name gives None (the caller then reads ``reference`` as a path, or reports it missing).
    """
    text = str(reference)
    if not text or Path(text).exists() or Path(text).name != text:
        return None
    name = text if text.endswith(suffix) else text + suffix
    candidate = DEMO_DATA_DIR / name
    return candidate if candidate.is_file() else None
