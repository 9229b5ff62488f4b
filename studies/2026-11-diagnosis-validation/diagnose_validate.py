"""Blind validation of the gap diagnosis (studies/2026-11-diagnosis-validation/README.md).

    python studies/2026-11-diagnosis-validation/diagnose_validate.py                    # reference set: 200 cases, seed 3
    python studies/2026-11-diagnosis-validation/diagnose_validate.py --set widened      # widened set: 200 cases, seed 11
    python studies/2026-11-diagnosis-validation/diagnose_validate.py --cases 14 --seed 5 --out /tmp/v

Same as ``bushenv diagnose-validate``; defaults to the documented runs (200 cases, out
validation-diagnose-<set>/). Seeds 0, 1 and 2 were used while developing the diagnosis; seed 3
(reference) and seed 11 (widened) were run once at the end.
"""

from __future__ import annotations

import sys

from bushenv.cli import main

SEEDS = {"reference": "3", "widened": "11", "outside": "0"}

if __name__ == "__main__":
    args = sys.argv[1:]
    case_set = args[args.index("--set") + 1] if "--set" in args else "reference"
    defaults = ["--set", case_set, "--cases", "200", "--seed", SEEDS.get(case_set, "0")]
    defaults += ["--out", f"validation-diagnose-{case_set}"]
    given = {a for a in args if a.startswith("--")}
    extra = []
    for i in range(0, len(defaults), 2):
        if defaults[i] not in given:
            extra += defaults[i : i + 2]
    sys.exit(main(["diagnose-validate", *args, *extra]))
