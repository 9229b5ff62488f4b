"""Files are written by ``bushenv.persist`` and progress is shown by ``bushenv.progress``
only: no other module saves a figure, renames a temporary file into place or defines a
Progress of its own."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "bushenv"


def _calls(tree: ast.AST, attr: str) -> list[int]:
    return [
        node.lineno
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
        and (
            (isinstance(node.func, ast.Attribute) and node.func.attr == attr)
            or (isinstance(node.func, ast.Name) and node.func.id == attr)
        )
    ]


def _atomic_recipe(tree: ast.AST) -> list[int]:
    """The temporary-file-and-rename recipe: os.replace, os.rename, tempfile.mkstemp."""
    return [
        node.lineno
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
        and isinstance(node.func, ast.Attribute)
        and isinstance(node.func.value, ast.Name)
        and (node.func.value.id, node.func.attr)
        in {("os", "replace"), ("os", "rename"), ("tempfile", "mkstemp")}
    ]


def _progress_definitions(tree: ast.AST) -> list[int]:
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.ClassDef) and node.name == "Progress":
            out.append(node.lineno)
        if isinstance(node, ast.Assign | ast.AnnAssign):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if any(isinstance(t, ast.Name) and t.id == "Progress" for t in targets):
                out.append(node.lineno)
    return out


def _offenders(check, home: str) -> list[str]:
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).as_posix()
        if rel == home:
            continue
        found += [f"{rel}:{line}" for line in check(ast.parse(path.read_text()))]
    return found


def test_every_figure_is_saved_through_persist():
    assert _offenders(lambda t: _calls(t, "savefig"), "persist.py") == []


def test_no_module_but_persist_writes_a_file_atomically_by_itself():
    assert _offenders(_atomic_recipe, "persist.py") == []


def test_there_is_one_progress():
    assert _offenders(_progress_definitions, "progress.py") == []


def test_the_scans_find_what_they_look_for():
    tree = ast.parse(
        "import os\nclass Progress: pass\nProgress = print\nfig.savefig('a.png')\n"
        "os.replace('a', 'b')\n"
    )
    assert _calls(tree, "savefig") == [4]
    assert _progress_definitions(tree) == [2, 3]
    assert _atomic_recipe(tree) == [5]
