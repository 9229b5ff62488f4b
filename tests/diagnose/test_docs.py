"""docs/diagnose.md shows the effects table the registry builds."""

from pathlib import Path

from bushenv.diagnose.candidates import effects_table

DOC = Path(__file__).resolve().parents[2] / "docs" / "diagnose.md"


def test_the_docs_effects_table_is_the_registrys():
    text = DOC.read_text()
    start = text.index("<!-- effects-table -->") + len("<!-- effects-table -->")
    end = text.index("<!-- /effects-table -->")
    assert text[start:end].strip() == effects_table(), "rerun effects_table() into the docs"
