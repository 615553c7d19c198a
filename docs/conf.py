"""Sphinx configuration of vtb's documentation site (built in CI with warnings as errors by
tests/test_docs.py; locally: ``sphinx-build -W -b html docs docs/_build``)."""

import vtb

project = "vtb"
author = "the vtb developers"
release = vtb.__version__
version = release

extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinx.ext.mathjax"]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
# the reproduction's sweep page is folded into its report
exclude_patterns = ["_build", "reproduction/sweep.md", "robust-study/article/sweep.md"]

# Markdown pages link to each other by file name and to headings by their slugs.
myst_heading_anchors = 3
myst_enable_extensions = ["dollarmath"]

autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
napoleon_numpy_docstring = True
napoleon_google_docstring = False
napoleon_use_ivar = True

html_theme = "alabaster"
html_title = f"vtb {release}"
