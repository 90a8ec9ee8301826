"""flutter/ solves flutter from modal matrices and GAFs as data: it reads no deck and calls no
aerodynamics (DESIGN.md section 2). Checked twice: the import statements of every flutter/*.py
(including imports inside functions), and the modules actually loaded by importing all of them in a
fresh interpreter (which also catches an indirect import through another package)."""
from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

FLUTTER = Path(__file__).resolve().parents[2] / "flutter"
FORBIDDEN = ("aero", "pyNastran", "structures.common.nastran", "structures.bdf")


def _forbidden(name: str) -> bool:
    return any(name == f or name.startswith(f + ".") for f in FORBIDDEN)


def _imports(path: Path) -> set[str]:
    """Every module named by an import statement anywhere in the file."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0:
            names.add(node.module)
            names |= {f"{node.module}.{a.name}" for a in node.names}
    return names


def test_no_flutter_module_imports_decks_or_aero():
    files = sorted(FLUTTER.glob("*.py"))
    assert len(files) >= 15 and not (FLUTTER / "run.py").exists()
    offending = {p.name: sorted(n for n in _imports(p) if _forbidden(n)) for p in files}
    assert {k: v for k, v in offending.items() if v} == {}


def test_importing_flutter_loads_no_deck_reader_or_aero():
    names = [f"flutter.{p.stem}" for p in sorted(FLUTTER.glob("*.py")) if p.stem != "__init__"]
    code = ("import importlib, sys\n"
            f"for n in {names!r}: importlib.import_module(n)\n"
            "print('\\n'.join(sorted(sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], cwd=FLUTTER.parent, capture_output=True,
                         text=True, check=True).stdout.split()
    assert "flutter.solve" in out and "flutter.pk" in out
    assert [m for m in out if _forbidden(m)] == []


def test_the_forbidden_list_catches_an_aero_import(tmp_path):
    """The check itself: a module with a function-level aero import and a pyNastran import."""
    src = tmp_path / "bad.py"
    src.write_text("import numpy\nfrom pyNastran.bdf.bdf import BDF\n\ndef f():\n"
                   "    from aero.gaf import generalized_aero_forces\n")
    assert sorted(n for n in _imports(src) if _forbidden(n)) == [
        "aero.gaf", "aero.gaf.generalized_aero_forces", "pyNastran.bdf.bdf",
        "pyNastran.bdf.bdf.BDF"]
