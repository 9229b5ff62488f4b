"""The two NARX training recipes side by side: accuracy on unseen records and the static force.

For each axis and seed s: the records ``bushenv reproduce --seed s`` measures on the reference
rubber (40 s at n = 1 to train; unseen n = 1 and n = 1.5 records, 20 s each, own drive and
noise seeds), the nn and the hybrid trained with ``--recipe free-run`` and ``--recipe
teacher-forcing`` (seed s), judged in free run from rest on both unseen records, and held at
+4 mm and -4 mm for 10 s: the force over the last second of the hold beside the reference's
(the rubber without its measurement chain).

    python studies/2026-11-training-recipes/fit_recipes.py --seeds 0-3 --axes axial,radial --md fit-recipes.md
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

RECIPES = ("free-run", "teacher-forcing")
# A variant is a recipe, optionally with "+lags": the first layer trained on the plain lags
# (--input-basis lags) as the papers' network was, instead of lag differences.
VARIANTS = RECIPES


def variant_options(variant: str) -> dict:
    recipe, _, basis = variant.partition("+")
    return {"recipe": recipe, **({"input_basis": basis} if basis else {})}


HOLD_M = 4e-3
HOLD_S = 10.0
TAIL_S = 1.0


def held_force(model, x_hold_m: float) -> float:
    """Mean force over the last second of a ``x_hold_m`` step held 10 s, N."""
    from bushenv.excitation import step_hold

    x = step_hold(x_hold_m, HOLD_S, model.dt, pre_s=1.0)
    model.reset(1)
    f = model.simulate(x)
    n = int(round(TAIL_S / model.dt))
    return float(np.mean(f[-n:])) if np.all(np.isfinite(f)) else float("nan")


def one_cell(axis: str, seed: int, models: list[str], variants: list[str]) -> list[dict]:
    from bushenv.identify import fit
    from bushenv.metrics import rms_ratio
    from bushenv.models import get_reference
    from bushenv.reproduce import _records

    train, same, test = _records(axis, seed, 40.0, 20.0)
    ref = get_reference("rubber", axis=axis, dt=train.dt)
    ref_hold = {s: held_force(ref, s * HOLD_M) for s in (1, -1)}
    rows = []
    for name in models:
        for recipe in variants:
            res = fit([train], name, variant_options(recipe), seed=seed, progress=False)
            m = res.model
            row = {"axis": axis, "seed": seed, "model": name, "recipe": recipe}
            row["fit_s"] = res.seconds
            for key, rec in (("unseen_n1", same), ("unseen_n15", test)):
                m.reset(1)
                row[key] = rms_ratio(rec.force, m.simulate(rec.displacement))
            for s in (1, -1):
                tag = "plus4" if s > 0 else "minus4"
                row[f"held_{tag}_n"] = held_force(m, s * HOLD_M)
                row[f"reference_{tag}_n"] = ref_hold[s]
            rows.append(row)
            print(
                f"{axis} seed {seed} {name:6s} {recipe:20s} {res.seconds:5.1f} s  unseen n=1 "
                f"{100 * row['unseen_n1']:5.2f} %  n=1.5 {100 * row['unseen_n15']:5.2f} %  "
                f"+4 mm {row['held_plus4_n']:8.1f} N (ref {ref_hold[1]:.1f})  -4 mm "
                f"{row['held_minus4_n']:8.1f} N (ref {ref_hold[-1]:.1f})",
                flush=True,
            )
    return rows


def held_verdict(row: dict, tag: str) -> str:
    """'wrong sign', or the held force as a fraction of the reference's."""
    f, ref = row[f"held_{tag}_n"], row[f"reference_{tag}_n"]
    if not np.isfinite(f):
        return "non-finite"
    if np.sign(f) != np.sign(ref):
        return "wrong sign"
    return f"{f / ref:.2f}"


def markdown(rows: list[dict], command: str, seconds: float) -> str:
    lines = [
        f"`{command}` ({seconds / 60:.0f} min on the shared 2-core machine).",
        "",
        "| axis | model | recipe | seeds | unseen n = 1 RMS % (min-max) | n = 1.5 RMS % "
        "(min-max) | held +4 mm: model / reference | held -4 mm: model / reference | fit s |",
        "|---|---|---|---:|---|---|---|---|---:|",
    ]
    keys = sorted({(r["axis"], r["model"], r["recipe"]) for r in rows})
    for axis, name, recipe in keys:
        sel = [r for r in rows if (r["axis"], r["model"], r["recipe"]) == (axis, name, recipe)]
        a = np.array([100 * r["unseen_n1"] for r in sel])
        b = np.array([100 * r["unseen_n15"] for r in sel])
        plus = ", ".join(held_verdict(r, "plus4") for r in sel)
        minus = ", ".join(held_verdict(r, "minus4") for r in sel)
        lines.append(
            f"| {axis} | {name} | {recipe} | {len(sel)} | {np.median(a):.2f} ({a.min():.2f}-"
            f"{a.max():.2f}) | {np.median(b):.2f} ({b.min():.2f}-{b.max():.2f}) | {plus} | "
            f"{minus} | {np.median([r['fit_s'] for r in sel]):.0f} |"
        )
    ref = {(r["axis"], t): r[f"reference_{t}_n"] for r in rows for t in ("plus4", "minus4")}
    lines += ["", "Reference held force (last second of a 10 s hold), N:"]
    for axis in sorted({r["axis"] for r in rows}):
        lines.append(
            f"- {axis}: +4 mm {ref[(axis, 'plus4')]:.1f} N, -4 mm {ref[(axis, 'minus4')]:.1f} N"
        )
    return "\n".join(lines) + "\n"


def seeds_of(text: str) -> list[int]:
    if "-" in text:
        lo, hi = (int(t) for t in text.split("-"))
        return list(range(lo, hi + 1))
    return [int(t) for t in text.split(",")]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", default="0-3", help="seed range a-b or list (default: 0-3)")
    p.add_argument("--axes", default="axial,radial", help="comma list (default: axial,radial)")
    p.add_argument("--models", default="nn,hybrid", help="comma list (default: nn,hybrid)")
    p.add_argument(
        "--recipes",
        default=",".join(VARIANTS),
        help="comma list of recipes, each optionally +lags (default: free-run,teacher-forcing)",
    )
    p.add_argument("--json", type=Path, default=None, help="write every row here")
    p.add_argument("--md", type=Path, default=None, help="write the summary table here")
    args = p.parse_args(argv)
    import torch

    torch.set_num_threads(1)
    t0 = time.perf_counter()
    rows = []
    for axis in args.axes.split(","):
        for seed in seeds_of(args.seeds):
            rows += one_cell(axis, seed, args.models.split(","), args.recipes.split(","))
            if args.json:
                args.json.write_text(json.dumps(rows, indent=1))
    command = "python studies/2026-11-training-recipes/fit_recipes.py " + " ".join(
        argv or sys.argv[1:]
    )
    text = markdown(rows, command.strip(), time.perf_counter() - t0)
    print(text)
    if args.md:
        args.md.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
