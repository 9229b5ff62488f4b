"""Argument parsing lives in the command layer (``bushenv/commands``) and ``bushenv.cli``
only; library modules take typed values. ``NOT_YET_MOVED`` lists the command modules still
inside their library packages (to move, then delete from the list): it may only shrink."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "bushenv"
NOT_YET_MOVED = {
    "diagnose/report.py",
    "diagnose/validate.py",
    "reference/calibration.py",
}


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
    assert found <= NOT_YET_MOVED, (
        f"argparse outside bushenv/commands: {sorted(found - NOT_YET_MOVED)}"
    )
    assert NOT_YET_MOVED <= found, f"moved already, drop from the list: {NOT_YET_MOVED - found}"
