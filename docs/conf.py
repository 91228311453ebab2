"""Sphinx configuration of the genthermal documentation (Sphinx + MyST-NB).

Build: ``python3 -m sphinx -W --keep-going -b html docs docs/_build/html``. Pages are MyST Markdown;
a page with a Jupytext header (``kernelspec:``) is a notebook whose code cells run on every build.
"""

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
# The notebook kernels import this tree too, whatever genthermal is installed.
os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, (str(ROOT), os.environ.get("PYTHONPATH"))))
# The notebook kernels inherit this: figures drawn in a cell show inline (CI exports MPLBACKEND=Agg).
os.environ["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"
os.environ.setdefault("GENTHERMAL_PROGRESS", "0")

import genthermal  # noqa: E402

project = "genthermal"
author = "genthermal developers"
copyright = "genthermal developers, MIT licence"
release = version = genthermal.__version__

extensions = [
    "myst_nb",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
]
source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb"}
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "**.ipynb_checkpoints", "jupyter_execute"]
root_doc = "index"

myst_enable_extensions = ["colon_fence", "dollarmath", "deflist"]
myst_heading_anchors = 3

# Notebook pages run on every build; an example that raises fails the build.
nb_execution_mode = "force"
nb_execution_raise_on_error = True
nb_execution_timeout = 300
nb_execution_show_tb = True
nb_execution_in_temp = True  # files a page writes (my_motor.py) land in a temporary folder
nb_merge_streams = True
nb_render_markdown_format = "myst"  # Markdown a cell displays may hold tables

napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_rtype = False
autodoc_typehints = "description"
autodoc_member_order = "bysource"
autodoc_default_options = {"members": False}

nitpicky = False
html_theme = "furo"
html_title = f"genthermal {release}"
html_static_path = []
