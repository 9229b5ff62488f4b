"""``bushenv replay``: run a regression corpus again; every changed verdict is named.

    bushenv replay CORPUS_DIR [CASE.json ...]

Each case (``corpus.py``) is judged on the models it names against the reference it records,
at its scales; a verdict that differs from the recorded one is printed with the case's name
and whether the model file or the reference changed since. A model file that is no longer
where the case was recorded is replayed from the copy kept with the corpus (its sha256
checked), and a ``note:`` line says so; so does a model file that changed while its verdict
held. Exit 0 when every case holds, 1 when some verdict changed, 2 when a case cannot be read
or a model or reference it names is gone.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bushenv.progress import Progress
from bushenv.search.corpus import CorpusError, case_files, check, load_case

EXAMPLE = "bushenv replay runs/your-bushing/corpus"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("paths", nargs="+", metavar="PATH", help="corpus folders or case files")
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")


def _cases(paths: list[str]) -> list[Path]:
    out: list[Path] = []
    for text in paths:
        p = Path(text)
        if p.is_dir():
            out += case_files(p)
        elif p.is_file():
            out.append(p)
        else:
            raise CorpusError(f"{p}: no such corpus folder or case file")
    if not out:
        raise CorpusError(f"no case files (*.json) in {', '.join(paths)}")
    return out


def run(args: argparse.Namespace) -> int:
    files = _cases(args.paths)
    progress = Progress(total=len(files), quiet=args.quiet, every_s=0.0)
    changed = 0
    said: set[str] = set()
    for k, path in enumerate(files, start=1):
        notes: list[str] = []
        problems = check(load_case(path), notes=notes)
        changed += bool(problems)
        for msg in problems:
            print(msg)
        for note in notes:
            if note not in said:  # one kept model stands in for many cases: say it once
                said.add(note)
                print(f"note: {note}")
        progress.update(k, f"{path.name}: {'CHANGED' if problems else 'holds'}")
    print(f"{len(files) - changed} of {len(files)} cases hold their recorded verdicts")
    return 1 if changed else 0
