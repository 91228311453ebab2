"""Print the lowest versions pyproject.toml allows, as pip requirements (``casadi==3.7.0 ...``).

Every runtime dependency and the ``test`` extra must declare a floor (``>=``); the floors CI job
installs exactly these versions, so the floors in pyproject.toml are checked, not hoped for.
"""

import re
import sys
import tomllib


def floors(pyproject_path: str) -> list[str]:
    """``name==floor`` for each runtime and test dependency; SystemExit if one has no floor."""
    with open(pyproject_path, "rb") as file:
        project = tomllib.load(file)["project"]
    # fmpy's own floor (0.3.30, the first to pass tests/test_fmu.py) needs numpy >= 2.1.3, so it
    # cannot share an environment with numpy's floor 1.26; it is checked by the tests job instead.
    requirements = [*project["dependencies"],
                    *(r for r in project["optional-dependencies"]["test"] if not r.startswith("fmpy"))]
    pinned = []
    for requirement in requirements:
        match = re.match(r"^\s*([A-Za-z0-9_.\-\[\]]+)\s*>=\s*([0-9][0-9.]*)", requirement)
        if not match:
            raise SystemExit(f"{pyproject_path}: {requirement!r} has no floor (name>=version)")
        pinned.append(f"{match.group(1)}=={match.group(2)}")
    return pinned


if __name__ == "__main__":
    print(" ".join(floors(sys.argv[1])))
