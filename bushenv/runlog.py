"""Results of many independent cells, one JSON line each, as they finish: resumable runs.

The campaign matrix and the population study both fan cells out over a backend (a process
pool or Ray) in whatever order they finish. Each finished cell is appended to a ``.jsonl`` file,
flushed and fsynced, so an interrupted run loses at most the cells in flight and resumes with
the rest. A torn last line (a kill mid-write) is dropped with a message; any other corrupt line
is an error naming the line.
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from bushenv.errors import BadInput
from bushenv.persist import json_default, write_text
from bushenv.progress import Progress


class RunLogError(BadInput):
    """A results file that cannot be read or continued; the message names file and line."""


class RunLog:
    """The results file at ``path``; a row is finished when it holds ``keys`` and
    ``result_keys``. Errors are raised as ``error`` (the caller's ``ValueError`` subclass)."""

    def __init__(
        self,
        path: Path,
        keys: Sequence[str],
        result_keys: Sequence[str],
        error: type[Exception] = RunLogError,
        say: Callable[[str], None] | None = None,
    ) -> None:
        self.path, self.keys, self.result_keys = Path(path), tuple(keys), tuple(result_keys)
        self.error, self.say = error, say or (lambda msg: None)

    def key(self, cell: dict[str, Any]) -> str:
        return "|".join(str(cell[k]) for k in self.keys)

    def _row(self, line: str, require_results: bool) -> dict[str, Any] | None:
        try:
            row = json.loads(line)
        except json.JSONDecodeError:
            return None
        needed = (*self.keys, *self.result_keys) if require_results else self.keys
        if not isinstance(row, dict) or any(k not in row for k in needed):
            return None
        return row

    def read(self, require_results: bool = True) -> dict[str, dict[str, Any]]:
        """Finished rows by key. Only the last line may be torn: it is dropped and cut from the
        file, so that cell runs again. A complete last line that lost only its newline is kept
        and the newline restored, so the next append starts a line of its own."""
        done: dict[str, dict[str, Any]] = {}
        if not self.path.exists():
            return done
        if not self.path.is_file():
            raise self.error(f"{self.path}: not a regular file")
        raw = self.path.read_bytes()
        try:
            text = raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise self.error(
                f"{self.path}: not a results file (not UTF-8 text at byte {exc.start}); "
                "move it away or pass another --out"
            ) from None
        lines = text.splitlines()
        for i, line in enumerate(lines, start=1):
            if not line.strip():
                continue
            row = self._row(line, require_results)
            if row is None:
                if i == len(lines):
                    self.say(
                        f"{self.path} line {i}: incomplete last line (interrupted write) dropped"
                    )
                    keep = (
                        text[: text.rstrip("\n").rfind("\n") + 1] if "\n" in text.rstrip() else ""
                    )
                    write_text(self.path, keep)
                    continue
                raise self.error(f"{self.path} line {i}: corrupt result line; fix or remove it")
            done[self.key(row)] = row
        if text and not text.endswith("\n") and self.path.read_bytes() == raw:
            with self.path.open("a") as fh:
                fh.write("\n")
        return done

    def append(self, row: dict[str, Any]) -> None:
        with self.path.open("a") as fh:
            fh.write(json.dumps(row, sort_keys=True, default=json_default) + "\n")
            fh.flush()
            os.fsync(fh.fileno())


def _without_last_line(text: str) -> str:
    body = text.rstrip("\n")
    return text[: body.rfind("\n") + 1] if "\n" in body else ""


def run_cells(
    cells: list[dict[str, Any]],
    fn: Callable[[dict[str, Any]], dict[str, Any]],
    log: RunLog,
    backend,
    resume: bool,
    progress: Progress,
    describe: Callable[[dict[str, Any]], str],
    what: str = "cells",
    weight: Callable[[dict[str, Any]], float] | None = None,
) -> list[dict[str, Any]]:
    """Run ``fn`` on every cell not yet in ``log`` over ``backend``; all rows in cell order.

    ``weight(cell)``: the cell's expected cost relative to the others, for the time left
    (default: every cell the same)."""
    weight = weight or (lambda cell: 1.0)
    log.path.parent.mkdir(parents=True, exist_ok=True)
    if not resume and log.path.exists():
        raise log.error(f"{log.path} exists; pass --resume to continue or --out elsewhere")
    done = log.read() if resume else {}
    todo = [c for c in cells if log.key(c) not in done]
    progress.total = sum(weight(c) for c in todo)
    progress.say(
        f"{what}: {len(cells)} cells, {len(cells) - len(todo)} already done, "
        f"{len(todo)} to run on {backend.name} ({backend.workers} workers)"
    )
    work = 0.0
    for n, (i, row) in enumerate(backend.imap_unordered(fn, todo), start=1):
        row["worker_backend"] = backend.name
        log.append(row)
        done[log.key(todo[i])] = row
        work += weight(todo[i])
        progress.update(work, f"[{n}/{len(todo)}] {describe(row)}", force=True)
    return [done[log.key(c)] for c in cells]
