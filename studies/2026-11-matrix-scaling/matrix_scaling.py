"""How a campaign matrix scales: measured on this machine, projected to a cluster.

    python studies/2026-11-matrix-scaling/matrix_scaling.py [--cells 8] [--budget 256] [--ray] [--json FILE]

Measures, in one run, the evaluations per second of the same matrix with 1 and 2 local worker
processes (and on a local Ray instance with --ray), plus Ray's per-task overhead (no-op tasks),
then projects what a 100-node cluster would give for a matrix of 10,000 runs, splitting the time
into evaluation, transfer and scheduling. Prints a markdown table (studies/2026-11-matrix-scaling/README.md).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from pathlib import Path


def _noop(i: int) -> int:
    return i


def measure(backend, cells) -> dict:
    from bushenv.search.matrix import run_matrix

    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        rows = run_matrix(cells, Path(d), backend, progress=lambda s: None)
        wall = time.perf_counter() - t0
    evals = sum(r["evaluations"] for r in rows)
    cell_s = [r["wall_s"] for r in rows]
    return {
        "backend": backend.name,
        "workers": backend.workers,
        "cells": len(rows),
        "evaluations": evals,
        "wall_s": wall,
        "evaluations_per_s": evals / wall,
        "mean_cell_s": sum(cell_s) / len(cell_s),
        "result_bytes": sum(len(json.dumps(r)) for r in rows) / len(rows),
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--cells", type=int, default=8, help="cells in the measured matrix")
    p.add_argument("--budget", type=int, default=256, help="evaluations per cell")
    p.add_argument("--model", default="nn")
    p.add_argument("--ray", action="store_true", help="also measure a local Ray instance")
    p.add_argument("--json", type=Path)
    args = p.parse_args(argv)

    from bushenv.execution import LocalBackend, RayBackend
    from bushenv.search.matrix import make_cells

    seeds = list(range(max(1, args.cells // 2)))
    cells = make_cells([args.model], ["axial"], ["random", "cma"], seeds, args.budget)
    print(f"matrix of {len(cells)} cells x {args.budget} evaluations ({args.model}, axial)")
    rows = []
    with LocalBackend(workers=1) as b:
        measure(b, cells[:1])  # warm the compiled-kernel cache
        rows.append(measure(b, cells))
    with LocalBackend(workers=2) as b:
        rows.append(measure(b, cells))
    task_overhead_s = None
    if args.ray:
        b = RayBackend(num_cpus=2)
        try:
            rows.append(measure(b, cells))
            n = 1000
            t0 = time.perf_counter()
            b.map(_noop, list(range(n)))
            task_overhead_s = (time.perf_counter() - t0) / n
        finally:
            b.close()
    for r in rows:
        print(
            f"  {r['backend']:5s} {r['workers']} workers: {r['evaluations_per_s']:9.0f} evals/s "
            f"({r['wall_s']:.1f} s wall, {r['mean_cell_s']:.2f} s per cell)"
        )
    speedup = rows[1]["evaluations_per_s"] / rows[0]["evaluations_per_s"]
    print(f"  2 workers vs 1: {speedup:.2f}x")

    # Projection: 10,000 runs on 100 nodes of 2 cores (this machine's size) each.
    runs, nodes, cores = 10_000, 100, 2
    cell_s = rows[0]["mean_cell_s"]
    per_core_eff = speedup / 2  # what the second local core delivered
    waves = math.ceil(runs / (nodes * cores))
    eval_s = waves * cell_s / per_core_eff
    overhead = task_overhead_s if task_overhead_s is not None else 1e-3
    sched_s = runs * overhead / nodes  # head dispatches; spread over node raylets
    transfer_s = runs * rows[0]["result_bytes"] / 10e6  # results to the driver over ~10 MB/s
    total = eval_s + sched_s + transfer_s
    proj = {
        "runs": runs,
        "nodes": nodes,
        "cores_per_node": cores,
        "mean_cell_s": cell_s,
        "waves": waves,
        "evaluation_s": eval_s,
        "scheduling_s": sched_s,
        "transfer_s": transfer_s,
        "total_s": total,
        "ray_task_overhead_s": task_overhead_s,
        "single_machine_s": runs * cell_s / speedup,
    }
    print(
        f"projection, {runs} runs on {nodes} nodes x {cores} cores: {total:.0f} s "
        f"(evaluation {eval_s:.0f} s, scheduling {sched_s:.1f} s, transfer {transfer_s:.2f} s); "
        f"this machine alone: {proj['single_machine_s'] / 3600:.1f} h"
    )
    if args.json:
        args.json.write_text(json.dumps({"measured": rows, "projection": proj}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
