"""Three-axis diagnosis on the coupled reference with one effect withheld: the hit rate.

    python studies/2026-11-diagnose-three-axis/diagnose_three_axis.py [--seeds 10] [--held-out]

Every case of ``bushenv.diagnose.validation.three_axis_cases.SPECS`` (``none``, relaxation,
friction and hardening on each coordinate, coupled friction, the elastic coupling, relaxation
with coupling) for seeds 0..N-1, each a TRAIN and a TEST record diagnosed by
``bushenv.diagnose.fit.diagnose`` (linear three-axis baseline, the default mode: every record
used; ``--held-out``: fitted on TRAIN, judged on TEST). Writes ``results[_held_out].json``
beside this script and prints the table of the README.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from bushenv.diagnose.fit import diagnose
from bushenv.diagnose.validation.three_axis_cases import SPECS, make_case, score

HERE = Path(__file__).parent


def run(seeds: int, held_out: bool) -> list[dict]:
    rows = []
    for seed in range(seeds):
        for spec in SPECS:
            t0 = time.perf_counter()
            train, test = make_case(spec, seed)
            result = diagnose(train, [test], cross=False if held_out else None)
            row = {"seed": seed, **score(result, spec), "seconds": time.perf_counter() - t0}
            rows.append(row)
            print(f"seed {seed} {spec.name:20s} {'hit ' if row['hit'] else 'MISS'} "
                  f"{row['answer']:40s} shrink {100 * row['shrink']:5.1f} % "
                  f"{row['effects']}", flush=True)  # fmt: skip
    return rows


def table(rows: list[dict]) -> str:
    lines = [
        "| case | hits | every coordinate it acts on | median shrink (hits) | effect named where "
        "none acts | other effect named where it acts |",
        "|---|---|---|---|---|---|",
    ]
    for spec in SPECS:
        r = [x for x in rows if x["case"] == spec.name]
        hits = [x for x in r if x["hit"]]
        shrink = np.median([x["shrink"] for x in hits]) if hits and spec.coords else None
        lines.append(
            f"| {spec.name} | {len(hits)}/{len(r)} | "
            f"{sum(x['every_coordinate'] for x in r)}/{len(r)} | "
            f"{'-' if shrink is None else f'{100 * shrink:.0f} %'} | "
            f"{sum(bool(x['false_coordinates']) for x in r)} | "
            f"{sum(bool(x['wrong_effects']) for x in r)} |"
        )
    hits = [x for x in rows if x["hit"]]
    named = [x for x in hits if x["case"] != "none"]
    lines.append(
        f"| **all** | **{len(hits)}/{len(rows)}** | "
        f"{sum(x['every_coordinate'] for x in rows)}/{len(rows)} | "
        f"{100 * np.median([x['shrink'] for x in named]):.0f} % | "
        f"{sum(bool(x['false_coordinates']) for x in rows)} | "
        f"{sum(bool(x['wrong_effects']) for x in rows)} |"
    )
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10)
    parser.add_argument("--held-out", action="store_true")
    args = parser.parse_args()
    rows = run(args.seeds, args.held_out)
    name = "results_held_out.json" if args.held_out else "results.json"
    (HERE / name).write_text(json.dumps(rows, indent=1) + "\n")
    print(table(rows))
    print(f"median seconds per case: {np.median([x['seconds'] for x in rows]):.1f}")


if __name__ == "__main__":
    main()
