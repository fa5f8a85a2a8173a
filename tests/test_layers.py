"""The package's layers (docs/architecture.md, issue 17): imports point one way
(cli <- applications <- shared edge <- models <- stages <- base), there are no import
cycles, and no module uses another module's private (underscore) names.

The first two are import-linter contracts declared in ``pyproject.toml``; this suite runs
``lint-imports`` on them so a later change cannot bring a cycle back.
"""

from __future__ import annotations

import ast
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "mlplc2"


def _lint_imports() -> str:
    exe = Path(sys.executable).with_name("lint-imports")
    if not exe.exists():
        found = shutil.which("lint-imports")
        if found is None:
            pytest.skip("import-linter is not installed (pip install 'mlplc2[test]')")
        exe = Path(found)
    return str(exe)


def test_the_import_contracts_hold():
    """``lint-imports`` (layers + acyclic siblings, pyproject.toml) exits 0 and keeps every contract."""
    proc = subprocess.run([_lint_imports(), "--no-cache"],       # reads ROOT/pyproject.toml
                          capture_output=True, text=True, cwd=ROOT)
    report = proc.stdout[proc.stdout.find("Contracts"):] if "Contracts" in proc.stdout else proc.stdout
    assert proc.returncode == 0, report + proc.stderr
    n = len(tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["importlinter"]["contracts"])
    assert f"Contracts: {n} kept, 0 broken" in proc.stdout, report


def _module_name(path: Path) -> str:
    return ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts).removesuffix(".__init__")


def private_uses(path: Path) -> list[str]:
    """Every use in ``path`` of another mlplc2 module's underscore name: ``from .x import _y``,
    or ``x._y`` where ``x`` is an mlplc2 module bound by an import. Importing a private
    *module* of the package (``from . import _fast``) is fine; using its private names is not."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    modules: set[str] = set()       # local names bound to mlplc2 modules
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").startswith("mlplc2")):
            for alias in node.names:
                if node.module is None or (PACKAGE / (node.module or "").replace(".", "/") / f"{alias.name}.py").exists():
                    modules.add(alias.asname or alias.name)      # a module
                elif alias.name.startswith("_") and not alias.name.startswith("__"):
                    found.append(f"{path.name}:{node.lineno}: from {'.' * node.level}{node.module} "
                                 f"import {alias.name}")
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("mlplc2."):
                    modules.add(alias.asname or alias.name.split(".")[0])
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in modules
                and node.attr.startswith("_") and not node.attr.startswith("__")):
            found.append(f"{path.name}:{node.lineno}: {node.value.id}.{node.attr}")
    return found


def test_no_module_uses_another_modules_private_names():
    found = [use for path in sorted(PACKAGE.rglob("*.py")) for use in private_uses(path)]
    assert not found, "private names used across modules:\n" + "\n".join(found)


def test_the_private_name_check_finds_what_it_should(tmp_path):
    """The checker itself: an underscore import and an underscore attribute of an imported
    module are found; a private module, a dunder and a public name are not."""
    sample = tmp_path / "sample.py"     # read as if it were a module of mlplc2
    sample.write_text("from . import _fast, io\nfrom .io import _to_rgb, open_source, __all__\n"
                      "x = io._is_camera\ny = _fast.copy_chain\n", encoding="utf-8")
    found = private_uses(sample)
    assert [f.split(": ", 1)[1] for f in found] == ["from .io import _to_rgb", "io._is_camera"]


def test_cli_is_imported_by_no_module_of_the_package():
    importers = []
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.name in ("cli.py", "__main__.py"):
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and (node.module == "cli" or (node.module or "").endswith(".cli")
                                                     or any(a.name == "cli" for a in node.names)):
                importers.append(f"{_module_name(path)}:{node.lineno}")
    assert not importers, importers


def test_the_model_base_class_knows_no_family():
    """models/base.py (the generic contract) imports no family's stages: the attention fields'
    type aside (``Output.fields``), nothing of the front end, the targets or a baseline."""
    tree = ast.parse((PACKAGE / "models" / "base.py").read_text(encoding="utf-8"))
    imported = {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) and node.level}
    assert imported <= {"_validation", "attention"}, imported
