"""The layout holds: imports run one way between the top-level packages, modules and
functions stay short.

The data flow of the design card is geometry -> quasi1d -> cases/postprocess -> workflow,
and the imports follow it, so that each package can be read, tested and changed
without the ones above it.  Imports inside functions count: a lazy import is still a
dependency (it only hides a cycle from the interpreter, not from the reader).
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[1]
PACKAGES = ("geometry", "quasi1d", "cases", "postprocess", "workflow")
#: The packages each package may import besides itself and the modules of
#: ``rotorflow/`` (errors, the gmsh context manager, the version), which lie below
#: every package and import none.
ALLOWED = {
    "rotorflow": set(),
    "geometry": set(),
    "quasi1d": {"geometry"},
    "postprocess": {"geometry", "quasi1d"},
    "cases": {"geometry", "quasi1d", "postprocess"},
    "workflow": {"geometry", "quasi1d", "cases", "postprocess"},
}
#: The target is about 400 lines; 450 leaves a little slack for docstrings, so that a
#: module is split by responsibility, not trimmed of its explanations to pass.
MAX_MODULE_LINES = 450
#: The target is about 80 lines (one screen), whole nested functions included.
MAX_FUNCTION_LINES = 80

#: Modules others are splitting right now (issue 12). Expected to fail, strictly: a
#: module that passes turns the run red, so the lead empties this set as the splits
#: land and the rules then hold for every module.
BEING_SPLIT: set[str] = set()
#: Imports against the direction that others are removing (issue 12).
IMPORTS_BEING_REMOVED: set[str] = set()
#: Of BEING_SPLIT, those with functions over the limit.
FUNCTIONS_BEING_SPLIT: set[str] = set()
#: Over the limits and not (yet) being split by anyone: listed so that the rule holds
#: for everything else.
NOT_YET_SPLIT_MODULES: set[str] = set()
NOT_YET_SPLIT_FUNCTIONS: set[str] = set()


def modules() -> list[str]:
    """Every module of the package, as a path from the repository's root."""
    return sorted(p.relative_to(REPO).as_posix() for pkg in ("rotorflow", *PACKAGES)
                  for p in (REPO / pkg).rglob("*.py"))


def params(expected: dict[str, str]) -> list:
    """Every module, those in ``expected`` marked as strict expected failures."""
    return [pytest.param(m, marks=pytest.mark.xfail(strict=True, reason=expected[m]))
            if m in expected else m for m in modules()]


def dotted(rel: str) -> list[str]:
    """``geometry/export/stl.py`` -> ["rotorflow", "geometry", "export", "stl"] (the
    folders are installed as subpackages of rotorflow, see pyproject.toml)."""
    parts = list(Path(rel).with_suffix("").parts)
    return parts if parts[0] == "rotorflow" else ["rotorflow", *parts]


def imported(rel: str) -> list[tuple[int, str]]:
    """(line, absolute dotted name) of every rotorflow import of a module, anywhere in it."""
    package = dotted(rel)[:-1]  # for __init__.py too: its package
    out = []
    for node in ast.walk(ast.parse((REPO / rel).read_text())):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module.split(".") if node.module else []
            if node.level:  # relative: from the module's package, up level - 1
                base = package[:len(package) - node.level + 1] + base
            # ``from rotorflow import workflow`` imports the package it names.
            out += [(node.lineno, ".".join([*base, a.name])) if base == ["rotorflow"]
                    else (node.lineno, ".".join(base)) for a in node.names]
    return [(n, name) for n, name in out if name.split(".")[0] == "rotorflow"]


def violations(rel: str) -> list[str]:
    own = rel.split("/")[0]
    bad = []
    for line, name in imported(rel):
        top = name.split(".")[1] if "." in name else ""
        if top not in PACKAGES or top == own or top in ALLOWED[own]:
            continue  # rotorflow's own modules, the package itself, or downstream
        bad.append(f"{rel}:{line} imports {name}")
    return bad


@pytest.mark.parametrize("rel", params({m: "import being removed by another change"
                                        for m in IMPORTS_BEING_REMOVED}))
def test_imports_follow_the_data_flow(rel):
    assert violations(rel) == []


def test_the_import_check_can_fail(tmp_path, monkeypatch):
    """A quasi1d module importing postprocess, or anyone importing workflow, is caught,
    relative imports and imports inside functions included."""
    monkeypatch.setattr(sys.modules[__name__], "REPO", tmp_path)
    (tmp_path / "quasi1d").mkdir()
    (tmp_path / "quasi1d" / "m.py").write_text(
        "from rotorflow.geometry import table\n"
        "def f():\n    from ..postprocess import report\n")
    (tmp_path / "postprocess").mkdir()
    (tmp_path / "postprocess" / "r.py").write_text(
        "from rotorflow import errors, workflow\nimport rotorflow.quasi1d\n")
    assert violations("quasi1d/m.py") == [
        "quasi1d/m.py:3 imports rotorflow.postprocess"]
    assert violations("postprocess/r.py") == ["postprocess/r.py:1 imports rotorflow.workflow"]


@pytest.mark.parametrize("rel", params(
    {**{m: "over the limit, not yet assigned" for m in NOT_YET_SPLIT_MODULES},
     **{m: "being split by another change" for m in BEING_SPLIT}}))
def test_modules_are_short(rel):
    lines = len((REPO / rel).read_text().splitlines())
    assert lines <= MAX_MODULE_LINES, f"{rel} has {lines} lines"


def long_functions(rel: str) -> list[str]:
    tree = ast.parse((REPO / rel).read_text())
    return [f"{rel}:{node.lineno} {node.name} has {node.end_lineno - node.lineno + 1} lines"
            for node in ast.walk(tree)
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef)
            and node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES]


@pytest.mark.parametrize("rel", params(
    {**{m: "long function, not yet assigned" for m in NOT_YET_SPLIT_FUNCTIONS},
     **{m: "being split by another change" for m in FUNCTIONS_BEING_SPLIT}}))
def test_functions_are_short(rel):
    assert long_functions(rel) == []


def test_the_expected_failures_name_modules_that_exist():
    """A listed module that was split away or renamed is taken off the lists."""
    listed = (BEING_SPLIT | IMPORTS_BEING_REMOVED | FUNCTIONS_BEING_SPLIT
              | NOT_YET_SPLIT_MODULES | NOT_YET_SPLIT_FUNCTIONS)
    assert sorted(listed - set(modules())) == []


def test_pyproject_installs_every_package_of_the_tree():
    """Each folder with an __init__.py is a subpackage of rotorflow in pyproject.toml, from
    that folder, and pyproject names no package the tree does not have (a missing entry
    installs a wheel without it; an editable install hides that)."""
    import tomllib

    conf = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    tree = {".".join(dotted(p.relative_to(REPO).as_posix())[:-1]): p.parent.relative_to(REPO)
            for pkg in ("rotorflow", *PACKAGES) for p in (REPO / pkg).rglob("__init__.py")}
    assert sorted(conf["packages"]) == sorted(tree)
    for name, folder in tree.items():
        assert Path(conf["package-dir"][name]) == folder, name
