"""Sphinx configuration of the accelcal documentation site (built by tools/build_docs.sh)."""
from __future__ import annotations

import inspect
import re
from pathlib import Path

import accelcal

DOCS = Path(__file__).resolve().parent
MORE_PAGES = "<!-- every other docs/*.md: conf.py puts them in a toctree here when the site is built -->"

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
# every parameter of a public function documented, every return (warnings, so errors with -W);
# the classes (and their members) left out: dataclasses whose fields their Attributes sections document
numpydoc_validation_checks = {"PR01", "PR02", "RT01", "GL08"}
numpydoc_validation_exclude = {rf"\.{name}(\.|$)" for name in accelcal.__all__
                               if inspect.isclass(getattr(accelcal, name))}

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


def pages_not_listed(index_text: str, docs_dir: Path = DOCS) -> list[str]:
    """The docs/*.md pages (docnames, sorted) that no toctree of the index lists."""
    listed = set()
    for block in re.findall(r"```\{toctree\}\n(.*?)```", index_text, re.S):
        listed |= {ln.strip() for ln in block.splitlines() if ln.strip() and not ln.startswith(":")}
    return sorted(p.stem for p in docs_dir.glob("*.md") if p.stem not in listed | {"index"})


def index_with_every_page(index_text: str, docs_dir: Path = DOCS) -> str:
    """The index with a toctree of the pages its own toctrees leave out, where MORE_PAGES stands:
    a page another change adds to docs/ is in the site without an edit of the index."""
    more = pages_not_listed(index_text, docs_dir)
    block = "```{toctree}\n:maxdepth: 1\n:caption: More pages\n\n" + "\n".join(more) + "\n```\n" if more else ""
    return index_text.replace(MORE_PAGES, block)


def _more_pages(app, docname, source):
    if docname == "index":
        source[0] = index_with_every_page(source[0])


def setup(app):
    app.connect("source-read", _more_pages)
