"""How often the diagnosis names an effect that is not there, from validation runs.

    python studies/2026-11-diagnosis-validation/diagnose_validate.py --set widened --cases 30 --out v/
    python studies/2026-11-diagnosis-validation/diagnose_false_positives.py v/validation.json [more.json ...]

Per candidate effect E: among the cases whose hidden label lacks E, the share whose answer
names E (alone or in a pair) -- the false-positive rate of naming E, measured on cases without
it. Overall: the share of answers that name any effect not in the label (the rule's target:
at most 5 %). Abstentions (``ambiguous``, ``outside_candidates``) name no effect.
"""

from __future__ import annotations

import json
import sys

from bushenv.diagnose.candidates import effect_names
from bushenv.diagnose.rule import AMBIGUOUS, OUTSIDE


def named_set(named: str) -> set[str]:
    return set() if named in ("none", AMBIGUOUS, OUTSIDE) else set(named.split("+"))


def main(paths: list[str]) -> int:
    if not paths:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    rows = []
    for p in paths:
        try:
            rows += json.loads(open(p, encoding="utf-8").read())["cases"]
        except (OSError, ValueError, KeyError) as exc:
            print(f"{p}: not a validation.json ({type(exc).__name__}: {exc})", file=sys.stderr)
            return 2
    label = [set() if r["label"] == "none" else set(r["label"].split("+")) for r in rows]
    named = [named_set(r["named"]) for r in rows]
    print(f"{len(rows)} cases from {', '.join(paths)}")
    print("| effect | cases without it | named anyway | rate |")
    print("|---|---|---|---|")
    for e in effect_names():
        without = [n for lab, n in zip(label, named, strict=True) if e not in lab]
        hits = sum(e in n for n in without)
        rate = hits / len(without) if without else 0.0
        print(f"| {e} | {len(without)} | {hits} | {100 * rate:.1f} % |")
    wrong = sum(bool(n - lab) for lab, n in zip(label, named, strict=True))
    print(f"answers naming an effect that is not there: {wrong} of {len(rows)} "
          f"({100 * wrong / len(rows):.1f} %)")  # fmt: skip
    abst = sum(r["named"] in (AMBIGUOUS, OUTSIDE) for r in rows)
    print(f"abstentions ({AMBIGUOUS}, {OUTSIDE}): {abst}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
