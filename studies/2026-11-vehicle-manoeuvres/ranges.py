"""Steps the standard manoeuvres keep the car's pivots beyond the ranges their laws hold
(``bushenv.vehicle.ranges.measure``):

    python studies/2026-11-vehicle-manoeuvres/ranges.py --bushings DIR [--seed 0] [--out F.json]

One line per manoeuvre and car on stderr; the table as JSON with ``--out``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from bushenv.vehicle.ranges import measure


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bushings", type=Path, required=True)
    ap.add_argument("--seed", type=int, default=0, help="the manoeuvres' seed (the road)")
    ap.add_argument("--out", type=Path)
    args = ap.parse_args(argv)
    result = measure(args.bushings, args.seed, say=lambda s: print(s, file=sys.stderr, flush=True))
    if args.out:
        args.out.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
