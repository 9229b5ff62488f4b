"""The worked run of studies/2026-11-bouc-wen-benchmark/README.md: a user's own records, end to end, with the commands.

Records nobody here wrote: the public Bouc-Wen benchmark (../shared/data/bouc-wen-benchmark,
PROVENANCE.md there). As a user would, it runs the ``bushenv`` commands one after the other:

1. ``bushenv fit`` linear, nn and hybrid on the estimation record, judged on both test records;
2. ``bushenv attack`` the fitted NN against the fitted hybrid as the reference, keeping what it
   finds in a corpus (the hybrid is vetted first; refused, the attack is run again with
   ``--trust-reference`` and its verdicts marked unvetted); and the same attack with no
   reference (the physical criteria only);
3. ``bushenv replay`` the corpus;
4. ``bushenv diagnose`` the linear model's gap on the test records.

Every figure of the page is in ``OUT/summary.json`` (and the commands' own outputs in OUT).

    python studies/2026-11-bouc-wen-benchmark/your_bushing.py --data ../shared/data/bouc-wen-benchmark --out runs/your-bushing
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import time
from pathlib import Path

from bushenv.cli import main as bushenv

MODELS = ("linear", "nn", "hybrid")


def step(name: str, argv: list[str], expect=(0,)) -> float:
    print(f"\n$ bushenv {' '.join(argv)}", file=sys.stderr, flush=True)
    t0 = time.perf_counter()
    code = bushenv(argv)
    if code not in expect:
        raise SystemExit(f"{name}: bushenv exited {code}")
    return time.perf_counter() - t0


def refused(argv: list[str]) -> str | None:
    """The one-line refusal of ``bushenv argv`` (exit 2), or None when it ran (exit 0)."""
    err = io.StringIO()
    print(f"\n$ bushenv {' '.join(argv)}", file=sys.stderr, flush=True)
    with contextlib.redirect_stderr(err):
        code = bushenv(argv)
    sys.stderr.write(err.getvalue())
    if code not in (0, 2):
        raise SystemExit(f"bushenv exited {code}")
    return err.getvalue().strip().splitlines()[-1] if code == 2 else None


def run(data: Path, out: Path) -> dict:
    train = str(data / "train_multisine.csv")
    tests = [str(data / "test_multisine.csv"), str(data / "test_sinesweep.csv")]
    out.mkdir(parents=True, exist_ok=True)
    summary: dict = {"fit": {}, "attack": {}, "seconds": {}}
    for m in MODELS:
        path = out / f"{m}.npz"
        summary["seconds"][f"fit_{m}"] = step(
            "fit", ["fit", train, "--model", m, "--out", str(path), "--validate", *tests]
        )
        card = json.loads(path.with_suffix(".card.json").read_text())
        summary["fit"][m] = {Path(r["file"]).stem: r.get("metrics") for r in card["records"]}
    vetting = ["attack", "--model", str(out / "nn.npz"), "--reference", str(out / "hybrid.npz")]
    vetting += ["--out", str(out / "attack_vetting"), "--force", "--quiet"]
    summary["hybrid_as_judge_refused"] = refused(vetting)
    trust = [] if summary["hybrid_as_judge_refused"] is None else ["--trust-reference"]
    for name, extra in (
        ("hybrid_reference", ["--reference", str(out / "hybrid.npz"), *trust]),
        ("no_reference", []),
    ):
        where = out / f"attack_{name}"
        argv = ["attack", "--model", str(out / "nn.npz"), *extra, "--out", str(where)]
        argv += ["--save", "--corpus", str(out / "corpus"), "--force"]
        summary["seconds"][f"attack_{name}"] = step("attack", argv)
        report = json.loads((where / "report.json").read_text())
        summary["attack"][name] = {
            "criteria": report["criteria"],
            "judge": report["judge"],
            "notes": report["notes"],
            "scales": report["scales"],
            "rows": {
                f"{k}/{s}": {
                    "diverged": r["diverged"],
                    "evaluations_to_failure": r["evaluations_to_failure"],
                    "criterion": (r.get("first_failure") or {})
                    .get("verdict", {})
                    .get("first_criterion"),
                    "family": (r.get("first_failure") or {}).get("family"),
                }
                for k, e in report["models"].items()
                for s, r in e["searchers"].items()
            },
            "shrunk": [
                {"model": e["failed_model"], "family": e["family"], "final": e["shrink"]["final"]}
                for e in report["shrunk"]
                if e["shrink"]
            ],
        }
    summary["seconds"]["replay"] = step("replay", ["replay", str(out / "corpus")], (0, 1))
    diag = out / "diagnose"
    summary["seconds"]["diagnose"] = step(
        "diagnose", ["diagnose", train, *tests, "--out", str(diag), "--force"]
    )
    d = json.loads((diag / "report.json").read_text())
    summary["diagnose"] = {k: d.get(k) for k in ("effect", "gap_before", "gap_after", "shrink")}
    (out / "summary.json").write_text(json.dumps(summary, indent=1))
    return summary


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default="../shared/data/bouc-wen-benchmark")
    ap.add_argument("--out", default="runs/your-bushing")
    a = ap.parse_args()
    print(json.dumps(run(Path(a.data), Path(a.out)), indent=1))
