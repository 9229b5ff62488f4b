"""``bushenv diagnose`` (default mode, files and figures written) timed at a given rate.

    python studies/2026-11-diagnosis-validation/diagnose_speed.py --rate 3000 [--run-order]

The records of ``scripts/bench.py --only diagnose`` (the reference rubber with all its effects,
RPC-like random, the last TEST with a held step: 60, 40, 30 and 20 s) made at ``--rate`` Hz;
prints the wall time, the CPU time and the load average before and after (the machine is
shared: state the load beside the time). ``--run-order``: the records given as one session
in their order, 60 s rests between (the heat carried from record to record).
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

from bushenv import excitation as ex
from bushenv.cli import main as cli
from bushenv.records import Record, save_csv
from bushenv.reference.rubber import RubberBushing

LENGTHS_S = (60.0, 40.0, 30.0, 20.0)
N_INDEX = (1.0, 1.0, 1.3, 1.5)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rate", type=float, default=3000.0, help="sample rate (Hz)")
    ap.add_argument("--run-order", action="store_true", help="one session, 60 s rests")
    a = ap.parse_args(argv)
    dt = 1.0 / a.rate
    ref = RubberBushing.preset("axial", dt=dt, seed=0)
    with tempfile.TemporaryDirectory() as tmp:
        paths = []
        for i, (seconds, n) in enumerate(zip(LENGTHS_S, N_INDEX, strict=True)):
            print(f"record {i + 1}/4: {seconds:g} s at {a.rate:g} Hz", file=sys.stderr)
            x = ex.random_rpc(n, seconds, dt, seed=i)
            if i == 3:
                x = ex.sequence(x, ex.step_hold(3e-3, 0.25 * seconds, dt, rise_s=0.05))
            ref.reset()
            rec = Record.from_arrays(x, ref.simulate(x), dt, name=f"rec{i}")
            paths.append(str(save_csv(rec, Path(tmp) / f"rec{i}.csv")))
        order = Path(tmp) / "order.csv"
        order.write_text("record,rest_before_s\nrec0,\nrec1,60\nrec2,60\nrec3,60\n")
        more = ["--run-order", str(order)] if a.run_order else []
        load0 = os.getloadavg()
        t0, c0 = time.perf_counter(), time.process_time()
        code = cli(["diagnose", paths[0], paths[2], paths[3], "--train", paths[1],
                    "--out", str(Path(tmp) / "out"), *more])  # fmt: skip
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        load1 = os.getloadavg()
    if code != 0:
        print(f"bushenv diagnose exited {code}", file=sys.stderr)
        return code
    samples = sum(int(round(s * a.rate)) for s in LENGTHS_S)
    print(f"{a.rate:g} Hz, {samples} samples: {wall:.1f} s wall, {cpu:.1f} s CPU; load average "
          f"(1 min) {load0[0]:.1f} before, {load1[0]:.1f} after")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
