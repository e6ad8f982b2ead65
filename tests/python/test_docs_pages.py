"""The documentation site's sources (tools/build_docs.sh builds them): every docs/*.md is in
the site (a glob toctree in the index), every C header is on the C core's page, every worked
example is reached from the getting-started page, and the docs extra names what the build
imports."""
import re
import runpy
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"


def load_conf():
    return runpy.run_path(str(DOCS / "conf.py"))


def test_the_index_takes_every_page(tmp_path):
    """A page added to docs/ is in the site without an edit of the index: conf.py puts the
    pages the index does not list in a toctree of their own (and none twice)."""
    conf = load_conf()
    index = (DOCS / "index.md").read_text()
    assert conf["MORE_PAGES"] in index
    built = conf["index_with_every_page"](index)
    assert conf["pages_not_listed"](built) == []
    for name in ("index", "getting-started", "refine"):
        (tmp_path / f"{name}.md").write_text(f"# {name}\n")
    listed_twice = conf["index_with_every_page"](index, tmp_path)
    assert listed_twice.count("\nrefine\n") == 1 and listed_twice.count("\ngetting-started\n") == 1


def test_every_c_header_is_on_the_c_core_page():
    page = (DOCS / "c-core.md").read_text()
    missing = [h.name for h in sorted((ROOT / "include" / "accelcal").glob("*.h"))
               if h.name != "accelcal.h" and f"`{h.name}`" not in page]
    assert not missing, missing


def test_every_example_is_linked_from_getting_started():
    page = (DOCS / "getting-started.md").read_text()
    missing = [p.stem for p in sorted((ROOT / "examples").glob("*.py"))
               if f"auto_examples/{p.stem}.rst" not in page]
    assert not missing, missing


def test_the_docs_extra_names_what_conf_py_loads():
    extra = re.search(r"^docs = \[(.*?)\]", (ROOT / "pyproject.toml").read_text(), re.M).group(1)
    names = {re.split(r"[<>=!~ ]", s.strip().strip('"'))[0].replace("-", "_").lower() for s in extra.split(",")}
    conf = (DOCS / "conf.py").read_text()
    for ext, dist in (("myst_parser", "myst_parser"), ("numpydoc", "numpydoc"),
                      ("sphinx_gallery.gen_gallery", "sphinx_gallery"), ("pydata_sphinx_theme", "pydata_sphinx_theme")):
        assert ext in conf and dist in names, (ext, names)
    assert "sphinx" in names


def test_every_benchmark_section_names_the_command_that_prints_it():
    page = (DOCS / "benchmarks.md").read_text()
    sections = re.findall(r"^## (.*)$", page, re.M)
    assert sections
    for title in sections:
        m = re.search(r"`python3 (tools/[\w./-]+\.py)[^`]*`", title)
        assert m and (ROOT / m.group(1)).is_file(), title
