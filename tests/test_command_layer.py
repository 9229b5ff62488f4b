"""Argument parsing lives in the command layer (``bushenv/commands``) and ``bushenv.cli``
only; library modules take typed values."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "bushenv"


def _imports_argparse(path: Path) -> bool:
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import) and any(a.name == "argparse" for a in node.names):
            return True
        if isinstance(node, ast.ImportFrom) and node.module == "argparse":
            return True
    return False


def test_argparse_is_imported_by_the_command_layer_only():
    found = {
        str(p.relative_to(PACKAGE))
        for p in PACKAGE.rglob("*.py")
        if _imports_argparse(p) and p.parent.name != "commands" and p.name != "cli.py"
    }
    assert not found, f"argparse outside bushenv/commands: {sorted(found)}"


def test_the_scan_sees_an_argparse_import(tmp_path):
    (tmp_path / "a.py").write_text("import argparse\n")
    (tmp_path / "b.py").write_text("from argparse import ArgumentParser\n")
    (tmp_path / "c.py").write_text("x = 'import argparse'\n")
    assert [_imports_argparse(tmp_path / n) for n in ("a.py", "b.py", "c.py")] == [
        True,
        True,
        False,
    ]
