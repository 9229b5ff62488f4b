"""Every error class bushenv defines is under the one root: bad input (exit 2) is a
``BadInput``, so no module can add an error the command line reads as a bug."""

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "bushenv"


def test_no_module_defines_an_error_on_a_bare_builtin():
    offenders = []
    for path in PACKAGE.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if (
                isinstance(node, ast.ClassDef)
                and node.name.endswith("Error")
                and node.name != "BushenvError"
            ):
                bases = {b.id for b in node.bases if isinstance(b, ast.Name)}
                if bases & {"ValueError", "Exception", "RuntimeError", "TypeError"}:
                    offenders.append(f"{path.relative_to(PACKAGE)}:{node.lineno} {node.name}")
    assert not offenders, "subclass bushenv.errors.BadInput (or BushenvError): " + ", ".join(
        offenders
    )
