#!/usr/bin/env bash
# Builds the documentation site into build/docs/html with every warning an error
# (sphinx -W --keep-going): docs/*.md through myst-parser, the API reference from the
# docstrings (autodoc, autosummary, numpydoc), and the worked examples of examples/
# run by sphinx-gallery, their figures in the pages.
#
#   bash tools/build_docs.sh                       # installs the package with its `docs` extra first
#   ACCELCAL_DOCS_INSTALL=0 bash tools/build_docs.sh   # the environment has them (tools/test_all.sh)
set -euo pipefail
cd "$(dirname "$0")/.."

if [ "${ACCELCAL_DOCS_INSTALL:-1}" = 1 ]; then
    echo "== installing the package with the docs extra"
    python3 -m pip install -q -e ".[docs]"
fi

# the API page lists every name of accelcal.__all__; it is generated, check it is current
python3 tools/gen_api_doc.py --check

# generated sources from an earlier build are stale: sphinx-gallery and autosummary write them again
rm -rf docs/auto_examples docs/generated docs/sg_execution_times.rst build/docs
export MPLBACKEND=Agg
python3 -m sphinx -W --keep-going -b html -j 1 -d build/docs/doctrees docs build/docs/html

# every worked example's page shows the figures it drew
python3 - <<'PY'
import re, sys
from pathlib import Path
html = Path("build/docs/html")
bad = []
for ex in sorted(Path("examples").glob("*.py")):
    page = html / "auto_examples" / (ex.stem + ".html")
    pngs = sorted(set(re.findall(rf"sphx_glr_{ex.stem}_\d+\.png", page.read_text()))) if page.exists() else []
    if not pngs or not all((html / "_images" / p).is_file() for p in pngs):
        bad.append(ex.name)
    else:
        print(f"   {ex.name}: {len(pngs)} figure(s)")
if bad:
    sys.exit(f"build_docs: no figure in the page of {', '.join(bad)}")
PY
echo "== site: build/docs/html/index.html"
