"""The partner test's false-positive rate, on single effects in forms no candidate shares.

    python studies/2026-11-diagnosis-validation/diagnose_partners.py --seed 1 --out p1.json
    python studies/2026-11-diagnosis-validation/diagnose_partners.py --summary p1.json p2.json
    python studies/2026-11-diagnosis-validation/diagnose_partners.py --label thermal+relaxation \
        --seed 5 --cases 10 --out tr.json

Runs ``diagnose`` (default mode) on ``validation/partner_cases.py`` cases and keeps, per case,
the answer, the answer the pair rule alone would give (the first pair that passed it, before
the richest-form test) and every tested pair's figures (``beyond_richest``). The summary: the
answers naming an effect that is not there, with and without the richest-form test, singles
named exactly, pairs both in the top two (also split by whether each effect shows, above three
times the noise, in at least two records: a judge held out confirms an effect only where it
shows in a record fitted and in one judged), poor-TRAIN cases, and the partners' shares beside
the richest form on true pairs and on invented ones (what ``partner.BEYOND_RICH_MIN`` is set
from).
"""

from __future__ import annotations

import argparse
import json
import sys
import time

from bushenv.diagnose.fit import diagnose
from bushenv.diagnose.rule import AMBIGUOUS, OUTSIDE
from bushenv.diagnose.validation.partner_cases import make_partner_case


def named_set(named: str) -> set[str]:
    return set() if named in ("none", AMBIGUOUS, OUTSIDE) else set(named.split("+"))


def run_order(case) -> list[tuple[str, float | None]]:
    """The case's records in the order its session ran them, the rests between (its start
    unknown: the specimen may have run warm before)."""
    names = [r.name for r in case.train + case.tests]
    order, rests = case.drawn["order"], case.drawn["rests_s"]
    return [(names[i], None if j == 0 else rests[j - 1]) for j, i in enumerate(order)]


def run(
    seed: int, cases: int, start: int, label: tuple[str, ...] | None = None, order: bool = False
) -> list[dict]:
    rows = []
    t0 = time.monotonic()
    for n, i in enumerate(range(start, start + cases)):
        case = make_partner_case(seed, i, label=label)
        r = diagnose(case.train, case.tests, run_order=run_order(case) if order else None)
        before = next((p["effect"] for p in r["pairs"] if p.get("passes_pair_rule")), None)
        rows.append(
            {
                "case": i,
                "label": case.label_text,
                "named": r["effect"],
                "named_by_pair_rule": before or r["effect"],
                "top_two": r["top_two"],
                "poor_train": case.drawn["poor_train"],
                "visible": case.drawn["visible"],
                "visible_by_record": case.drawn["visible_by_record"],
                "noise_fraction": case.drawn["noise_fraction"],
                "tested": [
                    {"pair": p["effect"], "checks": p["beyond_richest"]}
                    for p in r["pairs"]
                    if p.get("beyond_richest")
                ],
            }
        )
        done = n + 1
        eta = (time.monotonic() - t0) / done * (cases - done)
        print(f"case {done}/{cases} {case.label_text:<22} -> {r['effect']:<22} "
              f"(about {eta:.0f} s left)", file=sys.stderr)  # fmt: skip
    return rows


SHOWS = 3.0  # an effect shows in a record where its share of the force is 3 x the noise's


def shown_in(row: dict) -> int:
    """The fewest records any effect of the case shows in (a judge held out needs two)."""
    counts = [sum(v >= SHOWS * row["noise_fraction"] for v in shares)
              for shares in row.get("visible_by_record", {}).values()]  # fmt: skip
    return min(counts) if counts else 0


def summary(rows: list[dict]) -> str:
    label = [set() if r["label"] == "none" else set(r["label"].split("+")) for r in rows]
    out = [f"{len(rows)} cases"]
    for key in ("named", "named_by_pair_rule"):
        wrong = sum(bool(named_set(r[key]) - lab) for r, lab in zip(rows, label, strict=True))
        out.append(f"{key}: answers naming an absent effect {wrong} of {len(rows)} "
                   f"({100 * wrong / len(rows):.1f} %)")  # fmt: skip
    singles = [r for r in rows if "+" not in r["label"]]
    exact = sum(r["named"] == r["label"] for r in singles)
    out.append(f"singles named exactly {exact} of {len(singles)}")
    poor = [r for r in singles if r["poor_train"]]
    right = sum(r["named"] == r["label"] for r in poor)
    outside = sum(r["named"] == OUTSIDE for r in poor)
    out.append(f"poor TRAIN named exactly {right} of {len(poor)}; outside_candidates {outside}")
    pairs = [r for r in rows if "+" in r["label"]]
    hit = sum(set(r["top_two"]) == set(r["label"].split("+")) and r["named"] != "none"
              for r in pairs)  # fmt: skip
    exact_p = sum(named_set(r["named"]) == set(r["label"].split("+")) for r in pairs)
    out.append(f"pairs both in top two {hit} of {len(pairs)}; named exactly {exact_p}")
    if pairs and all("visible_by_record" in r for r in pairs):
        for seen, part in (("in two records or more", [r for r in pairs if shown_in(r) >= 2]),
                           ("in one record or none", [r for r in pairs if shown_in(r) < 2])):  # fmt: skip
            hit = sum(set(r["top_two"]) == set(r["label"].split("+")) and r["named"] != "none"
                      for r in part)  # fmt: skip
            exact_p = sum(named_set(r["named"]) == set(r["label"].split("+")) for r in part)
            out.append(f"  pairs whose effects each show {seen}: {len(part)}; both in top two "
                       f"{hit}, named exactly {exact_p}")  # fmt: skip
    for kind in ("true", "invented"):
        shares = []
        for r, lab in zip(rows, label, strict=True):
            for t in r["tested"]:
                for c in t["checks"]:
                    # a pair tested beside the best single's richest form: all three true
                    true = set(c["member"].split("+")) | {c["beside_richest"]} <= lab
                    if true == (kind == "true"):
                        shares.append(round(c["share"], 2))
        out.append(f"{kind} partners' shares beside the richest form: {sorted(shares)}")
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--cases", type=int, default=40)
    ap.add_argument("--start", type=int, default=0)
    ap.add_argument("--out", default="partners.json")
    ap.add_argument("--label", help="every case this effect or pair, e.g. thermal+relaxation")
    ap.add_argument("--summary", nargs="*", help="only summarise these JSON files")
    ap.add_argument(
        "--run-order", action="store_true", help="give the diagnosis the order the records ran"
    )
    a = ap.parse_args(argv)
    if a.summary:
        rows = [row for p in a.summary for row in json.load(open(p, encoding="utf-8"))]
    else:
        label = tuple(a.label.split("+")) if a.label else None
        rows = run(a.seed, a.cases, a.start, label, a.run_order)
        with open(a.out, "w", encoding="utf-8") as f:
            json.dump(rows, f, indent=1)
    print(summary(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
