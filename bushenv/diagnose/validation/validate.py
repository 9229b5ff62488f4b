"""Blind validation of the gap diagnosis (``bushenv diagnose-validate``,
``bushenv/commands/diagnose_validate.py``, gives a ``ValidationConfig``).

Each case (``SETS``) draws, from ``(seed, case index)``, a specimen with a hidden label --
``none``, one effect or two -- and records; the records alone go to ``diagnose`` (linear
baseline; ``cross`` where the case says so, e.g. the widened set's quasi-static pulls), and
the answer is scored:

- single-class cases (incl. ``none``): top-1 (the named effect, or a named pair's first
  member) against the label, a confusion matrix, and how often exactly one effect was named;
- two-effect cases: a hit when both effects are ``top_two`` and something was named;
- the median shrink on cases named right (``none`` cases excluded), recomputed from the
  predictions the diagnosis returns, as a reader of ``predictions/*.csv`` would;
- abstentions (``ambiguous``, ``outside_candidates``) counted apart: in the rates they are
  not hits, and they name no effect; the share of answers naming an effect that is not in
  the label (the false-positive rate the rule is held to).

``reference``: the reference rubber (``reference_cases.py``). ``widened``: forms, programmes,
rates and noise the candidates do not assume (``widened_cases.py``).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.diagnose.candidates import effect_names
from bushenv.diagnose.errors import DiagnoseError
from bushenv.diagnose.fit import diagnose
from bushenv.diagnose.report import check_out_dir
from bushenv.diagnose.rule import AMBIGUOUS, OUTSIDE
from bushenv.diagnose.validation.outside_cases import make_outside_case
from bushenv.diagnose.validation.reference_cases import Case, make_case
from bushenv.diagnose.validation.widened_cases import make_widened_case
from bushenv.persist import write_text
from bushenv.progress import Progress, ProgressSpec

SETS: dict[str, Callable[[int, int], Case]] = {
    "reference": make_case,
    "widened": make_widened_case,
    "outside": make_outside_case,
}


@dataclass(frozen=True)
class ValidationConfig:
    """A validation run: ``cases`` cases of ``case_set`` from index ``start``, drawn from
    ``seed``, written to ``out`` (refused if it exists, unless ``force``)."""

    out: Path
    case_set: str = "reference"
    cases: int = 70
    seed: int = 0
    start: int = 0
    force: bool = False

    def checked(self) -> ValidationConfig:
        if self.cases < 1:
            raise DiagnoseError(f"--cases must be >= 1, got {self.cases}")
        if self.case_set not in SETS:
            raise DiagnoseError(f"unknown case set {self.case_set!r}; known: {', '.join(SETS)}")
        return self

    @property
    def command(self) -> str:
        """The command line that repeats this run."""
        return (
            f"bushenv diagnose-validate --set {self.case_set} --cases {self.cases} "
            f"--seed {self.seed} --start {self.start} --out {self.out}"
        )


def recomputed_shrink(result: dict[str, Any]) -> float:
    """1 - gap(augmented) / gap(baseline) over the judged records' predictions."""
    preds = result["predictions"]
    fm = np.concatenate([p["force_measured"] for p in preds])
    fb = np.concatenate([p["force_baseline"] for p in preds])
    fa = np.concatenate([p["force_augmented"] for p in preds])
    before = float(np.sqrt(np.mean((fm - fb) ** 2)))
    return 1.0 - float(np.sqrt(np.mean((fm - fa) ** 2))) / before if before > 0 else 0.0


def named_effects(result: dict[str, Any]) -> set[str]:
    """The effects an answer claims are there (none for an abstention or 'none')."""
    if result["effect"] in ("none", AMBIGUOUS, OUTSIDE):
        return set()
    return set(result["effect"].split("+"))


def judge_case(case: Case, result: dict[str, Any]) -> dict[str, Any]:
    named = result["effect"]
    first = named.split("+")[0]
    absent = sorted(named_effects(result) - set(case.label))
    row = {
        "case": case.index,
        "label": case.label_text,
        "named": named,
        "top1": first,
        "top_two": result["top_two"],
        "shrink": recomputed_shrink(result),
        "gap_before": result["gap_before"],
        "gap_after": result["gap_after"],
        "mode": result["mode"],
        "abstained": named in (AMBIGUOUS, OUTSIDE),
        "absent_named": absent,
        "drawn": case.drawn,
    }
    if len(case.label) <= 1:
        truth = case.label[0] if case.label else "none"
        row.update(kind="single", right=first == truth, exact=named == truth)
    else:
        row["kind"] = "pair"
        row["right"] = set(result["top_two"]) == set(case.label) and named != "none"
        row["pair_named"] = set(named.split("+")) == set(case.label)
    return row


def _rate(rows: list[dict], key: str) -> float | None:
    return float(np.mean([r[key] for r in rows])) if rows else None


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    singles = [r for r in rows if r["kind"] == "single"]
    pairs = [r for r in rows if r["kind"] == "pair"]
    names = ["none", *effect_names()]
    seen = {r["label"] for r in singles} | {r["top1"] for r in singles}
    classes = [c for c in names if c in seen] + sorted(seen - set(names))
    idx = {c: i for i, c in enumerate(classes)}
    confusion = np.zeros((len(classes), len(classes)), dtype=int)
    for r in singles:
        confusion[idx[r["label"]], idx[r["top1"]]] += 1
    right = [r["shrink"] for r in rows if r["right"] and r["label"] != "none"]
    return {
        "cases": len(rows),
        "single_cases": len(singles),
        "pair_cases": len(pairs),
        "single_top1_rate": _rate(singles, "right"),
        "single_named_exactly_rate": _rate(singles, "exact"),
        "pair_hit_rate": _rate(pairs, "right"),
        "pair_named_exactly_rate": _rate(pairs, "pair_named"),
        "median_shrink_named_right": float(np.median(right)) if right else None,
        "abstained_ambiguous": sum(r.get("named") == AMBIGUOUS for r in rows),
        "abstained_outside": sum(r.get("named") == OUTSIDE for r in rows),
        "absent_effect_named_rate": _rate([{"x": bool(r.get("absent_named"))} for r in rows], "x"),
        "classes": classes,
        "confusion": confusion.tolist(),
    }


def confusion_table(summary: dict[str, Any]) -> str:
    classes = summary["classes"]
    lines = ["| true \\ named | " + " | ".join(classes) + " |", "|" + "---|" * (len(classes) + 1)]
    for c, row in zip(classes, summary["confusion"], strict=True):
        lines.append(f"| {c} | " + " | ".join(str(v) for v in row) + " |")
    return "\n".join(lines)


def run_validation(
    n_cases: int,
    seed: int,
    progress: ProgressSpec = False,
    start: int = 0,
    case_set: str = "reference",
) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """Draw, diagnose and judge ``n_cases`` cases; returns per-case rows and the summary.

    ``progress``: a line per case on stderr (True), none (False), or to a callable."""
    say = Progress.of(progress, total=n_cases)
    make = SETS[case_set]
    rows: list[dict[str, Any]] = []
    for i in range(start, start + n_cases):
        t0 = time.monotonic()
        case = make(seed, i)
        # the default mode, or the cross mode where the case asks for it
        result = diagnose(case.train, case.tests, cross=True if case.cross else None)
        row = judge_case(case, result)
        row["seconds"] = round(time.monotonic() - t0, 2)
        rows.append(row)
        done = i + 1 - start
        say.update(
            done,
            f"case {done}/{n_cases}: label {row['label']:<22} named {row['named']:<22} "
            f"{'right' if row['right'] else 'WRONG'}  shrink {100 * row['shrink']:5.1f} %  "
            f"({row['seconds']:.1f} s)",
            force=True,
        )
    return rows, summarise(rows)


def report_text(summary: dict[str, Any], seed: int, case_set: str) -> str:
    pct = lambda v: "n/a" if v is None else f"{100 * v:.1f} %"  # noqa: E731
    return "\n".join(
        [
            f"Blind validation ({case_set} set): {summary['cases']} cases (seed {seed}), "
            "linear baseline",
            "",
            "Single-effect cases (incl. none): rows = hidden label, columns = top-1 named",
            "",
            confusion_table(summary),
            "",
            f"- top-1 on single-effect cases (incl. none): {pct(summary['single_top1_rate'])} "
            f"of {summary['single_cases']} (named exactly, no second effect added: "
            f"{pct(summary['single_named_exactly_rate'])})",
            f"- two-effect cases, both in the top two: {pct(summary['pair_hit_rate'])} of "
            f"{summary['pair_cases']} (pair named exactly: "
            f"{pct(summary['pair_named_exactly_rate'])})",
            f"- median shrink on cases named right (recomputed from the predictions): "
            f"{pct(summary['median_shrink_named_right'])}",
            f"- abstentions (counted as neither hit nor wrong effect): "
            f"{summary['abstained_ambiguous']} '{AMBIGUOUS}', {summary['abstained_outside']} "
            f"'{OUTSIDE}'",
            f"- answers naming an effect that is not there: "
            f"{pct(summary['absent_effect_named_rate'])} of {summary['cases']}",
            "",
        ]
    )


def write_validation(config: ValidationConfig, progress: ProgressSpec = False) -> str:
    """Run ``config``; write ``validation.json`` and ``validation.md`` under ``config.out``;
    returns the report's text."""
    config = config.checked()
    out = Path(config.out)
    check_out_dir(out, config.force)
    rows, summary = run_validation(
        config.cases, config.seed, progress, config.start, config.case_set
    )
    out.mkdir(parents=True, exist_ok=True)
    text = report_text(summary, config.seed, config.case_set)
    data = {"command": config.command, "summary": summary, "cases": rows}
    write_text(out / "validation.json", json.dumps(data, indent=2, default=str) + "\n")
    write_text(out / "validation.md", f"`{config.command}`\n\n{text}")
    return text
