"""The attack's state is declared where it is made: ``Campaign.__init__`` resolves the judge
and the models once, and no other method adds an attribute to the campaign."""

import ast
from pathlib import Path

SOURCE = Path(__file__).resolve().parents[2] / "bushenv" / "search" / "campaign.py"


def test_no_campaign_attribute_is_set_outside_init():
    cls = next(
        n for n in ast.parse(SOURCE.read_text()).body
        if isinstance(n, ast.ClassDef) and n.name == "Campaign"
    )  # fmt: skip
    made, late = set(), []
    for f in cls.body:
        if not isinstance(f, ast.FunctionDef):
            continue
        for node in ast.walk(f):
            if (
                isinstance(node, ast.Attribute)
                and isinstance(node.ctx, ast.Store)
                and isinstance(node.value, ast.Name)
                and node.value.id == "self"
            ):
                if f.name == "__init__":
                    made.add(node.attr)
                elif node.attr not in made:
                    late.append(f"{f.name}: self.{node.attr}")
    assert made and not late, late
