"""Every command's --help: each option's default shown once, and an example."""

import re

import pytest

from bushenv.cli import COMMANDS, build_parser


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_help_states_each_default_once_and_gives_an_example(name):
    parser = build_parser(only=name)
    sub = next(a for a in parser._actions if hasattr(a, "choices") and a.choices)
    text = " ".join(sub.choices[name].format_help().split())
    assert "example:" in text
    assert not re.search(r"\(default[^)]*\)\s*\(default", text), text
