"""``python -m genthermal``: the ``genthermal`` command line (:mod:`genthermal.cli`)."""

import sys

from .cli import main

if __name__ == "__main__":
    sys.exit(main())
