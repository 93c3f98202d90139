"""Sphinx configuration of the quadcosim documentation (``make docs``)."""

import os
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE / "_ext"))

project = "quadcosim"
author = "The quadcosim authors"
copyright = "2026, The quadcosim authors"
extensions = ["myst_nb", "sphinx.ext.autodoc", "numpydoc", "quadcosim_docs"]
source_suffix = {".md": "myst-nb", ".ipynb": "myst-nb", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "_generated/runs", "_generated/tables"]  # tables: included by the pages
html_theme = "pydata_sphinx_theme"
html_title = "quadcosim"
html_theme_options = {"navigation_depth": 2, "show_toc_level": 2}
# every page but the notebooks is a child of the index alone: its primary sidebar ("Section
# Navigation") would be empty, and would still take a column of the page (the header lists the pages)
html_sidebars = {"*": [], "guides/*": [], "_generated/*": [], "notebooks": ["sidebar-nav-bs"],
                 "_generated/notebooks/*": ["sidebar-nav-bs"]}
myst_enable_extensions = ["colon_fence", "dollarmath"]
# equations as MathML, made at build time (docs/_ext): they show offline, with no script
html_math_renderer = "mathml"
html_static_path = ["_static"]
html_css_files = ["mathml.css", "layout.css"]
# The notebooks (notebooks/*.py, made .ipynb in _generated/notebooks/ when the build starts) run
# once, into a cache under _build/ that tests/test_notebooks.py reads: a notebook is executed
# again only when its code changes (or the cache is cleared, as on a fresh clone).
nb_execution_mode = "cache"
nb_execution_cache_path = str(HERE / "_build" / ".jupyter_cache")
nb_execution_raise_on_error = True  # a failing cell fails the build, its traceback shown
nb_execution_show_tb = True
nb_execution_timeout = 300
nb_execution_in_temp = True
# the kernel draws inline figures whatever backend the build's environment names (CI's Agg)
os.environ["MPLBACKEND"] = "module://matplotlib_inline.backend_inline"
myst_heading_anchors = 3
# pages include sections of the front page, whose headings start at level 2
suppress_warnings = ["myst.header", "myst.xref_missing"]
numpydoc_show_class_members = False
numpydoc_validation_checks = set()
autodoc_member_order = "bysource"
autodoc_mock_imports = []
