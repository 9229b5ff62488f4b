"""No module imports another package's private names (a leading underscore): what a package
shares it names in public, so the one-axis and the three-axis code cannot lean on each other's
internals."""

import ast
from pathlib import Path

import bushenv

ROOT = Path(bushenv.__file__).parent


def private_imports(root: Path) -> list[str]:
    """``file:line module.name`` of every private name imported from another package."""
    found = []
    for path in sorted(root.rglob("*.py")):
        package = ".".join(("bushenv", *path.relative_to(root).parent.parts))
        for node in ast.walk(ast.parse(path.read_text())):
            if not (isinstance(node, ast.ImportFrom) and (node.module or "").startswith("bushenv")):
                continue
            is_package = (root.parent / node.module.replace(".", "/")).is_dir()
            source = node.module if is_package else node.module.rpartition(".")[0]
            for alias in node.names:
                name = alias.name
                if name.startswith("_") and not name.startswith("__") and source != package:
                    where = f"{path.relative_to(root.parent)}:{node.lineno}"
                    found.append(f"{where} {node.module}.{name}")
    return found


def test_no_private_name_is_imported_across_packages():
    assert private_imports(ROOT) == []


def test_the_scan_finds_a_private_import_from_another_package(tmp_path):
    pkg = tmp_path / "bushenv"
    (pkg / "a").mkdir(parents=True)
    (pkg / "b").mkdir()
    (pkg / "a" / "inner.py").write_text("_hidden = 1\n")
    (pkg / "a" / "same.py").write_text("from bushenv.a.inner import _hidden\n")
    (pkg / "b" / "other.py").write_text("from bushenv.a.inner import _hidden, public\n")
    assert private_imports(pkg) == ["bushenv/b/other.py:1 bushenv.a.inner._hidden"]
