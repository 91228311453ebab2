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
