"""Sessions of two records: how often a thermal drift is named when each record is judged by a
fit on the other alone (the default mode with one TEST).

    python studies/2026-11-diagnosis-validation/diagnose_two_records.py [--out two.json] \
        [--run-order]

The specimen of ``bushenv/diagnose/validation/thermal_session.py`` (heat fed by ``c v^2``, a 60 s leak,
a quarter of the stiffness and damping lost at the session's hottest; and the relaxing one,
two Maxwell arms) runs every ordered pair of its four programmes (a strong 4 Hz sine, broad
random motion, a slow small sine, slow random motion) as a session of two records, cold and
after a hot run (warm). Prints each answer and, per specimen, the answers naming it, naming an
absent effect and abstaining. Deterministic.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import time
from pathlib import Path

from bushenv.diagnose.validation.thermal_session import (
    diagnose_session,
    programmes,
    relaxing_forces,
    thermal_forces,
)


def run(run_order: bool = False) -> list[dict]:
    progs = programmes()
    sessions = [(a, b, w) for a, b in itertools.permutations(progs, 2) for w in (False, True)]
    sessions += [(a, b, None) for a, b in itertools.permutations(progs, 2)]
    rows, t0 = [], time.monotonic()
    for n, (a, b, warm) in enumerate(sessions):
        order = (a, b)
        if warm is None:
            forces, label = relaxing_forces(progs), "relaxation"
        else:
            forces, label = thermal_forces(progs, order, warm), "thermal"
        r = diagnose_session(forces, progs, order, run_order)
        rows.append({"label": label, "order": list(order), "warm": warm,
                     "named": r["effect"], "top_two": r["top_two"]})  # fmt: skip
        eta = (time.monotonic() - t0) / (n + 1) * (len(sessions) - n - 1)
        print(f"{n + 1}/{len(sessions)} {label:<10} {a:>6} then {b:<6} "
              f"{'warm' if warm else 'cold' if warm is False else '':<4} -> {r['effect']} "
              f"(about {eta:.0f} s left)", file=sys.stderr)  # fmt: skip
    return rows


def summary(rows: list[dict]) -> str:
    out = []
    for label in ("thermal", "relaxation"):
        part = [r for r in rows if r["label"] == label]
        named = sum(r["named"] == label for r in part)
        absent = sum(bool(set(r["named"].split("+")) - {label, "none", "outside_candidates",
                                                          "ambiguous"}) for r in part)  # fmt: skip
        abstain = sum(r["named"] in ("none", "outside_candidates", "ambiguous") for r in part)
        top = sum(label in r["top_two"] for r in part)
        out.append(f"{label}: {len(part)} sessions, named {named}, in the top two {top}, "
                   f"an absent effect named {absent}, abstained {abstain}")  # fmt: skip
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="two_records.json")
    ap.add_argument(
        "--run-order", action="store_true", help="tell the diagnosis the order and the rests"
    )
    a = ap.parse_args(argv)
    rows = run(a.run_order)
    Path(a.out).write_text(json.dumps(rows, indent=1), encoding="utf-8")
    for r in rows:
        print(f"{r['label']:<10} {' then '.join(r['order']):<16} "
              f"{'' if r['warm'] is None else 'warm' if r['warm'] else 'cold':<4} "
              f"{r['named']:<22} {'/'.join(r['top_two'])}")  # fmt: skip
    print(summary(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
