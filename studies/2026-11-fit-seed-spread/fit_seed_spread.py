"""How much an identified model's accuracy depends on its training seed.

The bench identifies each model once (seed 0) and judges it on an unseen n = 1 record and on
an n = 1.5 record (50 % beyond the training amplitude). One seed is one draw: this script fits
the same model on the same training record with seeds 0..N-1 and judges every fit on the same
two records (the bench's PAPER_RECORDS, radial reference), beside the papers' figure (seed 002
Table 4: NN 4.5 %, Bouc-Wen 3.7 %; seed 000 Table 2: hybrid 4.6 %). The seed changes the
initial weights and the training windows (NN, hybrid) or the global search's population
(Bouc-Wen); the records stay fixed.

    python studies/2026-11-fit-seed-spread/fit_seed_spread.py                          # nn hybrid boucwen, 8 seeds
    python studies/2026-11-fit-seed-spread/fit_seed_spread.py --models nn --seeds 12 --md studies/2026-11-fit-seed-spread/results.md

Writes a table (and with --md a markdown file beside a strip plot of the RMS ratios; text below
the notes marker of an existing file is kept).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "scripts"))
from bench import paper_record  # noqa: E402  (the bench's records, not a copy of them)

from bushenv.reproduce import PAPER as PUBLISHED  # noqa: E402

# The papers' radial RMS ratios, %: seed 002 Table 4 (NN, Bouc-Wen), seed 000 Table 2 (hybrid).
PAPER = {
    "nn": PUBLISHED["table4"]["nn"][0],
    "hybrid": PUBLISHED["table2"]["radial"]["hybrid"][0],
    "boucwen": PUBLISHED["table4"]["boucwen"][0],
}
VERDICTS = ("unseen_same_amplitude", "unseen_n1.5")
NOTES_MARKER = "<!-- notes: kept when the tables are rewritten -->"
LABEL = {"unseen_same_amplitude": "unseen n = 1", "unseen_n1.5": "n = 1.5"}


def fit_and_judge(item: tuple[str, int]) -> dict:
    """One fit with one seed, judged on both records (runs in a worker process)."""
    from bushenv.identify import fit_model
    from bushenv.metrics import rms_ratio

    name, seed = item
    train = paper_record("train", False)[0]
    t0 = time.perf_counter()
    model = fit_model(name, train.displacement, train.force, train.dt, seed=seed, progress=False)
    row = {"model": name, "seed": seed, "seconds": time.perf_counter() - t0}
    for key in VERDICTS:
        rec = paper_record(key, False)[0]
        model.reset(1)
        row[key] = 100.0 * rms_ratio(rec.force, model.simulate(rec.displacement))
    return row


def summary(rows: list[dict]) -> list[str]:
    lines = [
        "| model | verdict | min % | median % | max % | fits within the papers' figure |",
        "|---|---|---:|---:|---:|---:|",
    ]
    for name in dict.fromkeys(r["model"] for r in rows):
        mine = [r for r in rows if r["model"] == name]
        for key in VERDICTS:
            vals = [r[key] for r in mine]
            ok = sum(v <= PAPER[name] for v in vals)
            lines.append(
                f"| {name} | {LABEL[key]} | {min(vals):.2f} | {statistics.median(vals):.2f} | "
                f"{max(vals):.2f} | {ok} of {len(vals)} (<= {PAPER[name]} %) |"
            )
    return lines


def per_seed(rows: list[dict]) -> list[str]:
    lines = ["| model | seed | fit s | unseen n = 1 % | n = 1.5 % |", "|---|---:|---:|---:|---:|"]
    for r in rows:
        lines.append(
            f"| {r['model']} | {r['seed']} | {r['seconds']:.1f} | "
            f"{r['unseen_same_amplitude']:.2f} | {r['unseen_n1.5']:.2f} |"
        )
    return lines


def plot(rows: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(r["model"] for r in rows))
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6), sharey=True)
    for ax, key in zip(axes, VERDICTS, strict=True):
        for i, name in enumerate(names):
            vals = [r[key] for r in rows if r["model"] == name]
            jitter = [i + 0.06 * ((j % 5) - 2) for j in range(len(vals))]
            ax.plot(jitter, vals, "o", alpha=0.7)
            ax.hlines(PAPER[name], i - 0.3, i + 0.3, colors="k", linestyles="--")
        ax.set_xticks(range(len(names)), names)
        ax.set_title(f"judged on {LABEL[key]} (one dot per seed)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("RMS ratio, %  (dashed: the papers')")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    from bushenv.execution import LocalBackend, local_cores

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--models", nargs="+", default=["nn", "hybrid", "boucwen"], choices=PAPER)
    ap.add_argument("--seeds", type=int, default=8, help="seeds 0..N-1 (default 8)")
    ap.add_argument("--workers", type=int, default=local_cores())
    ap.add_argument("--md", type=Path, help="write the tables here and a plot beside it")
    args = ap.parse_args(argv)
    if args.seeds < 1:
        ap.error(f"--seeds must be >= 1, got {args.seeds}")
    items = [(m, s) for m in args.models for s in range(args.seeds)]
    rows: list[dict | None] = [None] * len(items)
    t0 = time.perf_counter()
    with LocalBackend(args.workers) as backend:
        for done, (i, row) in enumerate(backend.imap_unordered(fit_and_judge, items), 1):
            rows[i] = row
            print(
                f"[{done}/{len(items)} {time.perf_counter() - t0:5.0f} s] {row['model']} seed "
                f"{row['seed']}: fit {row['seconds']:.1f} s, unseen n = 1 "
                f"{row['unseen_same_amplitude']:.2f} %, n = 1.5 {row['unseen_n1.5']:.2f} %",
                flush=True,
            )
    table = summary(rows) + [""] + per_seed(rows)
    print("\n".join(table))
    if args.md:
        png = args.md.with_suffix(".png")
        png.parent.mkdir(parents=True, exist_ok=True)
        plot(rows, png)
        head = [
            "# Identified models' accuracy against their training seed",
            "",
            f"`python studies/2026-11-fit-seed-spread/fit_seed_spread.py --models {' '.join(args.models)} --seeds "
            f"{args.seeds} --md {args.md}` ({time.perf_counter() - t0:.0f} s, {args.workers} "
            "workers; fit times are with the other worker busy). Training record, judged records "
            "and reference: the bench's (`scripts/bench.py`, PAPER_RECORDS, radial).",
            "",
            f"![RMS ratios per seed]({Path(png).relative_to(args.md.parent).as_posix()})",
            "",
        ]
        # Hand-written notes below NOTES_MARKER in an existing file are kept.
        notes = ""
        if args.md.exists() and NOTES_MARKER in (old := args.md.read_text()):
            notes = "\n" + old[old.index(NOTES_MARKER) :]
        args.md.write_text("\n".join(head + table) + "\n" + notes)
        print(f"wrote {args.md} and {png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
