"""Run every ``python`` block of the README with the given interpreter, in the current folder.

``python3 .ci/readme_examples.py README.md PYTHON``: CI's wheel job runs the README's Python
examples as written, against the installed wheel, from an empty folder. Exits non-zero on the
first block that fails, naming it.
"""

import re
import subprocess
import sys
from pathlib import Path


def main(readme: str, python: str) -> int:
    blocks = re.findall(r"```python\n(.*?)```", Path(readme).read_text(encoding="utf-8"), flags=re.S)
    if not blocks:
        print(f"{readme}: no python block", file=sys.stderr)
        return 1
    for index, code in enumerate(blocks, start=1):
        print(f"-- README python block {index} of {len(blocks)}", flush=True)
        if subprocess.run([python, "-c", code]).returncode != 0:
            print(f"README python block {index} failed:\n{code}", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
