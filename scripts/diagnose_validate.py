"""Blind validation of the gap diagnosis (the table in docs/diagnose.md).

    python scripts/diagnose_validate.py                      # the documented full run
    python scripts/diagnose_validate.py --cases 14 --seed 3 --out /tmp/v

Same as ``bushenv diagnose-validate``; defaults to the documented run (200 cases, seed 3,
out validation-diagnose/). Seeds 0 and 2 were used while developing the diagnosis (and seed 1
once, before its last two changes); seed 3 was not looked at before the documented run.
"""

from __future__ import annotations

import sys

from bushenv.cli import main

DEFAULTS = ["--cases", "200", "--seed", "3", "--out", "validation-diagnose"]

if __name__ == "__main__":
    args = sys.argv[1:]
    given = {a for a in args if a.startswith("--")}
    extra = []
    for i in range(0, len(DEFAULTS), 2):
        if DEFAULTS[i] not in given:
            extra += DEFAULTS[i : i + 2]
    sys.exit(main(["diagnose-validate", *args, *extra]))
