"""Sphinx configuration of the accelcal documentation site (built by tools/build_docs.sh)."""
from __future__ import annotations

import accelcal

project = "accelcal"
author = "the accelcal authors"
copyright = "the accelcal authors, BSD-2-Clause"
version = release = accelcal.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "sphinx_gallery.gen_gallery",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "auto_examples/*.ipynb", "auto_examples/*.py", "auto_examples/*.zip",
                    "auto_examples/*.json", "auto_examples/*.md5"]

# Markdown: `#heading` anchors for links within and across pages, $...$ maths, tables
myst_heading_anchors = 4
myst_enable_extensions = ["dollarmath", "colon_fence"]

# API reference: one page per public name, numpydoc's sections
autosummary_generate = True
autodoc_typehints = "none"
autodoc_default_options = {"members": False}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False

# worked examples: every examples/*.py runs when the site is built; its figures go in its page
sphinx_gallery_conf = {
    "examples_dirs": "../examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/.*\.py$",          # run every example
    "download_all_examples": False,
    "remove_config_comments": True,
    "abort_on_example_error": True,
    "matplotlib_animations": False,
    "image_scrapers": ("matplotlib",),
    "write_computation_times": False,
}

html_theme = "pydata_sphinx_theme"
html_title = "accelcal"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
}
html_show_sourcelink = False
