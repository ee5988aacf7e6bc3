"""Sphinx configuration of the docs site: the Markdown pages (MyST) and the reference that
`_ext/corobot_docs` generates from the code at build time.

Build: `.venv/bin/python -m sphinx -W --keep-going -b html docs build/docs` (offline: the
theme ships its assets; tests/packaging/test_docs_site.py builds it with warnings as errors).
"""

import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(DOCS.parent))  # the package and the tools, from this checkout

project = "corobot-drake"
author = "corobot-drake's authors"
copyright = "the corobot-drake authors (MIT)"


extensions = ["myst_parser", "sphinx.ext.autodoc", "corobot_docs"]
source_suffix = {".md": "markdown"}
exclude_patterns = ["_build", "_ext"]
root_doc = "index"

myst_heading_anchors = 4
"""`page.md#a-heading` links resolve to the heading (GitHub's slugs), and Sphinx checks them."""
myst_enable_extensions = ["colon_fence"]

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"show-inheritance": True}
suppress_warnings = ["ref.python"]
"""Only "more than one target found": a signature's `type` also names the attributes called
`type` (`commands.Arg.type`, `Ros2.type`); a missing target is not warned of unless nitpicky."""

smartquotes = False
"""Text as written (the ranges' words are the loader's, character for character)."""

html_theme = "furo"
html_title = "corobot-drake"
html_static_path = []
html_show_sourcelink = False
