"""Regenerate every doc built from the code, in one command.

    python scripts/gen_docs.py            # rewrite the generated docs (and parts of docs)
    python scripts/gen_docs.py --check    # write nothing; list those out of step, exit 1

| doc                                           | built by                                      |
|-----------------------------------------------|-----------------------------------------------|
| docs/registries.md (the whole page)           | ``bushenv.registries.markdown()``             |
| docs/diagnose.md, between the effects-table   | ``bushenv.diagnose.candidates.effects_table`` |
| markers                                       |                                               |

A doc generated in part keeps everything outside its ``<!-- NAME -->`` ... ``<!-- /NAME -->``
markers. ``tests/test_gen_docs.py`` runs ``--check``, so a registry entry added without
rerunning this fails the tests, naming the doc.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@dataclass(frozen=True)
class Generated:
    """One generated doc: its path under the checkout, the markers of the part generated
    (None: the whole file) and the function that builds the text."""

    path: str
    marker: str | None
    build: Callable[[], str]


def _registries() -> str:
    from bushenv.registries import markdown

    return markdown()


def _effects_table() -> str:
    from bushenv.diagnose.candidates import effects_table

    return effects_table()


GENERATED = (
    Generated("docs/registries.md", None, _registries),
    Generated("docs/diagnose.md", "effects-table", _effects_table),
)


class GenDocsError(Exception):
    """A doc's markers are missing; the message names the doc and the marker."""


def rendered(doc: Generated, current: str) -> str:
    """``current`` with the generated part rebuilt."""
    text = doc.build()
    if doc.marker is None:
        return text
    start, end = f"<!-- {doc.marker} -->", f"<!-- /{doc.marker} -->"
    if current.count(start) != 1 or current.count(end) != 1:
        raise GenDocsError(f"{doc.path}: needs one {start} and one {end} line around its table")
    head, rest = current.split(start)
    _, tail = rest.split(end)
    return f"{head}{start}\n{text.strip()}\n{end}{tail}"


def out_of_step(root: Path = ROOT, write: bool = False) -> list[str]:
    """The generated docs under ``root`` that differ from what the code builds (rewritten
    when ``write``)."""
    stale = []
    for doc in GENERATED:
        path = root / doc.path
        current = path.read_text(encoding="utf-8") if path.exists() else ""
        new = rendered(doc, current)
        if new != current:
            stale.append(doc.path)
            if write:
                path.write_text(new, encoding="utf-8")
    return stale


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--check", action="store_true", help="write nothing; exit 1 if any is stale")
    p.add_argument("--root", type=Path, default=ROOT, help="checkout to work in (default: this)")
    args = p.parse_args(argv)
    try:
        stale = out_of_step(args.root, write=not args.check)
    except GenDocsError as exc:
        print(f"gen_docs: {exc}", file=sys.stderr)
        return 2
    verb = "out of step (run: python scripts/gen_docs.py)" if args.check else "rewritten"
    for path in stale:
        print(f"{path}: {verb}", file=sys.stderr)
    return 1 if stale and args.check else 0


if __name__ == "__main__":
    sys.exit(main())
