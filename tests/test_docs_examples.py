"""The manual's examples run: every ``python`` code block of the pages listed here is executed,
in order, in one namespace per page (a later block may use an earlier one's names)."""

import re
from pathlib import Path

import pytest

DOCS = Path(__file__).resolve().parents[1] / "docs"
PAGES = ["getting-started.md"]


def python_blocks(text: str) -> list[str]:
    """The bodies of the fenced ```python blocks of a markdown page, in order."""
    return re.findall(r"^```python\n(.*?)^```", text, flags=re.M | re.S)


def test_python_blocks_are_found_in_a_page():
    page = "text\n```python\nx = 1\n```\n```\nnot python\n```\n```python\ny = x + 1\n```\n"
    assert python_blocks(page) == ["x = 1\n", "y = x + 1\n"]


@pytest.mark.parametrize("page", PAGES)
def test_every_python_example_of_the_page_runs(page, capsys):
    blocks = python_blocks((DOCS / page).read_text(encoding="utf-8"))
    assert blocks, f"docs/{page} has no python example"
    namespace: dict = {"__name__": "__docs_example__"}
    for i, block in enumerate(blocks):
        code = compile(block, f"docs/{page} python block {i + 1}", "exec")
        exec(code, namespace)  # noqa: S102  the manual's own examples
    assert capsys.readouterr().out  # each page's examples print what they show
