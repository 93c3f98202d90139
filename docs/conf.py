"""Sphinx configuration of the quadcosim documentation (``make docs``)."""

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE / "_ext"))

project = "quadcosim"
author = "The quadcosim authors"
copyright = "2026, The quadcosim authors"
extensions = ["myst_parser", "sphinx.ext.autodoc", "numpydoc", "quadcosim_docs"]
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["_build", "_generated/runs"]
html_theme = "pydata_sphinx_theme"
html_title = "quadcosim"
html_theme_options = {"navigation_depth": 2, "show_toc_level": 2}
myst_enable_extensions = ["colon_fence"]
myst_heading_anchors = 3
# pages include sections of the front page, whose headings start at level 2
suppress_warnings = ["myst.header", "myst.xref_missing"]
numpydoc_show_class_members = False
numpydoc_validation_checks = set()
autodoc_member_order = "bysource"
autodoc_mock_imports = []
