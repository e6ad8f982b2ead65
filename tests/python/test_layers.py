"""The package's import graph: one home per concept, no sideways imports.

The four method packages (calibrate, diagnose, simulate, estimators) build on the base
layer and never import one another; every import sits at the top of its module; no
module imports another module's private name.
"""
from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[2] / "python" / "accelcal"
METHODS = ("calibrate", "diagnose", "simulate", "estimators")
TOP = ("cli", "capture", "__init__", "__main__", "api")


def _modules():
    for p in sorted(PKG.rglob("*.py")):
        rel = p.relative_to(PKG).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts = parts[:-1] or ["__init__"]
        yield p, parts


def _resolve(parts: list[str], is_pkg: bool, node: ast.ImportFrom) -> list[str]:
    """The absolute module path (within accelcal) an ImportFrom names."""
    if node.level == 0:
        mod = (node.module or "").split(".")
        if mod[0] != "accelcal":
            return []
        return mod[1:]
    base = parts if is_pkg else parts[:-1]
    base = base[: len(base) - (node.level - 1)] if node.level > 1 else base
    return base + (node.module.split(".") if node.module else [])


def _imports(path: Path, parts: list[str]):
    tree = ast.parse(path.read_text(encoding="utf-8"))
    is_pkg = path.name == "__init__.py"
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            target = _resolve(parts, is_pkg, node)
            if target or node.level:
                yield node, target, [a.name for a in node.names]
        elif isinstance(node, ast.Import):
            for a in node.names:
                if a.name.startswith("accelcal."):
                    yield node, a.name.split(".")[1:], []


def _family(mod: list[str]) -> str | None:
    return mod[0] if mod and mod[0] in METHODS else None


def test_method_packages_do_not_import_each_other():
    bad = []
    for path, parts in _modules():
        mine = _family(parts)
        if mine is None:
            continue
        for node, target, names in _imports(path, parts):
            cands = [target] + [target + [n] for n in names]
            for c in cands:
                other = _family(c)
                if other is not None and other != mine:
                    bad.append(f"{path.relative_to(PKG)}:{node.lineno} imports {'.'.join(c)}")
                    break
    assert not bad, "sideways imports between method packages:\n" + "\n".join(bad)


def test_base_layer_imports_no_method_package():
    bad = []
    for path, parts in _modules():
        if _family(parts) is not None or parts[0] in TOP:
            continue
        for node, target, names in _imports(path, parts):
            if _family(target) is not None or any(_family(target + [n]) for n in names):
                bad.append(f"{path.relative_to(PKG)}:{node.lineno} imports {'.'.join(target)}")
    assert not bad, "base-layer modules importing a method package:\n" + "\n".join(bad)


# The one deliberate exception: plotting.pyplot() imports matplotlib on first use (0.3 s that
# every command would pay at start-up, although only --report draws).
DEFERRED = {("plotting.py", "matplotlib"), ("plotting.py", "matplotlib.pyplot")}


def test_imports_are_at_the_top():
    bad = []
    for path, parts in _modules():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        top = set(id(n) for n in tree.body)
        for node in ast.walk(tree):
            if isinstance(node, (ast.Import, ast.ImportFrom)) and id(node) not in top:
                mods = [a.name for a in node.names] if isinstance(node, ast.Import) else [node.module]
                if all((str(path.relative_to(PKG)), m) in DEFERRED for m in mods):
                    continue
                bad.append(f"{path.relative_to(PKG)}:{node.lineno}")
    assert not bad, "imports inside functions or blocks:\n" + "\n".join(bad)


def test_no_private_names_cross_modules():
    bad = []
    for path, parts in _modules():
        for node, target, names in _imports(path, parts):
            if not isinstance(node, ast.ImportFrom):
                continue
            for n in names:
                if n.startswith("_") and not n.startswith("__") and n not in ("_core",):
                    bad.append(f"{path.relative_to(PKG)}:{node.lineno} imports {n} from {'.'.join(target)}")
    assert not bad, "private names imported across modules:\n" + "\n".join(bad)


@pytest.mark.parametrize("limit", [500])
def test_modules_stay_readable(limit):
    big = [f"{p.relative_to(PKG)}: {n} lines" for p, _ in _modules()
           if (n := len(p.read_text(encoding="utf-8").splitlines())) > limit]
    assert not big, f"modules over {limit} lines:\n" + "\n".join(big)


def test_top_level_stays_small():
    """The top level holds the API, the float model and the commands' shared steps; every other
    module lives in the subpackage of its concern (docs/design.md's map)."""
    top = sorted(p.stem for p in PKG.glob("*.py"))
    assert len(top) <= 15, f"{len(top)} modules at the top of the package: {top}"


def test_design_map_names_the_tree():
    """docs/design.md's module map names every top-level module, every subpackage and every module in
    a subpackage (as `name`), so the map and the tree agree."""
    design = (PKG.parents[1] / "docs" / "design.md").read_text(encoding="utf-8")
    start = design.index("Python (`python/accelcal/`)")
    table = design[start:design.index("\n## ", start)]
    named = set(re.findall(r"`([\w/]+)`", table))
    missing = []
    for p in sorted(PKG.glob("*.py")):
        if p.stem not in named:
            missing.append(p.name)
    for d in sorted(q for q in PKG.iterdir() if (q / "__init__.py").exists()):
        if f"{d.name}/" not in named:
            missing.append(f"{d.name}/")
        for p in sorted(d.glob("*.py")):
            if p.stem not in ("__init__", "__main__") and p.stem not in named:
                missing.append(f"{d.name}/{p.name}")
    assert not missing, "modules docs/design.md's map does not name:\n" + "\n".join(missing)
