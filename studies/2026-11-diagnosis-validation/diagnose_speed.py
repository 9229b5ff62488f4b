"""``bushenv diagnose`` (default mode, files and figures written) timed at a given rate.

    python studies/2026-11-diagnosis-validation/diagnose_speed.py --rate 3000 [--run-order]

The records of ``scripts/bench.py --only diagnose`` (``validation/timing_cases.py``: the
reference rubber with all its effects, RPC-like random, the last TEST with a held step: 60, 40,
30 and 20 s) made at ``--rate`` Hz;
prints the wall time, the CPU time and the load average before and after (the machine is
shared: state the load beside the time). ``--run-order``: the records given as one session
in their order, 60 s rests between (the heat carried from record to record). ``--lone``: the
case where one record alone shows the gap and is judged again half against half
(``diagnose/halves.py``; ``timing_cases.lone_records``).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

from bushenv.cli import main as cli
from bushenv.diagnose.validation.timing_cases import lone_records, rubber_records
from bushenv.records import save_csv

LENGTHS_S = (60.0, 40.0, 30.0, 20.0)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rate", type=float, default=3000.0, help="sample rate (Hz)")
    ap.add_argument("--run-order", action="store_true", help="one session, 60 s rests")
    ap.add_argument("--lone", action="store_true", help="one record alone shows the gap")
    a = ap.parse_args(argv)
    dt = 1.0 / a.rate
    print(f"making 4 records at {a.rate:g} Hz", file=sys.stderr)
    recs = (lone_records if a.lone else rubber_records)(LENGTHS_S, dt)
    with tempfile.TemporaryDirectory() as tmp:
        paths = [str(save_csv(r, Path(tmp) / f"{r.name}.csv")) for r in recs]
        order = Path(tmp) / "order.csv"
        order.write_text("record,rest_before_s\nrec0,\nrec1,60\nrec2,60\nrec3,60\n")
        more = ["--run-order", str(order)] if a.run_order else []
        load0 = os.getloadavg()
        t0, c0 = time.perf_counter(), time.process_time()
        code = cli(["diagnose", paths[0], paths[2], paths[3], "--train", paths[1],
                    "--out", str(Path(tmp) / "out"), *more])  # fmt: skip
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        load1 = os.getloadavg()
        report = json.loads((Path(tmp) / "out" / "report.json").read_text(encoding="utf-8"))
    if code != 0:
        print(f"bushenv diagnose exited {code}", file=sys.stderr)
        return code
    samples = sum(int(round(s * a.rate)) for s in LENGTHS_S)
    print(f"{a.rate:g} Hz, {samples} samples: {wall:.1f} s wall, {cpu:.1f} s CPU; load average "
          f"(1 min) {load0[0]:.1f} before, {load1[0]:.1f} after; named {report['effect']}"
          + (f" on {', '.join(report['named_on_records'])}" if report.get("named_on_records")
             else ""))  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
