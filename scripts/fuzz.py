"""Fuzz every loader and env action space with thousands of hypothesis examples; print figures.

    python scripts/fuzz.py                        # 3000 examples per target, random seed
    python scripts/fuzz.py --examples 500 --seed 1 --only record_bytes,model_bytes

The targets and their oracles are those of tests/test_fuzz.py (which runs a few hundred each in
the fast suite). Unlike a test, a crash does not stop the run: each failing input is counted,
its first line of error kept, and the run goes on, so the figures say how many of the examples
broke bushenv. Prints one row per target (examples run, crashes, distinct errors, seconds) and
a total; exit code 1 when anything crashed.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from hypothesis import HealthCheck, Phase, given, seed, settings

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT))

import test_fuzz  # noqa: E402  (the shared oracles)


def run_target(name: str, examples: int, run_seed: int) -> dict:
    strategy, check = test_fuzz.TARGETS[name]
    stats = {"examples": 0, "crashes": 0, "errors": {}}

    def body(case) -> None:
        stats["examples"] += 1
        try:
            check(case)
        except Exception as exc:  # the point: count, keep going
            stats["crashes"] += 1
            text = str(exc).strip()
            line = f"{type(exc).__name__}: {text.splitlines()[0][:160] if text else ''}"
            stats["errors"][line] = stats["errors"].get(line, 0) + 1

    test = settings(
        max_examples=examples,
        deadline=None,
        database=None,
        phases=[Phase.generate],  # no shrinking: every example counts once
        suppress_health_check=list(HealthCheck),
    )(given(strategy)(body))
    test = seed(run_seed)(test)
    t0 = time.perf_counter()
    test()
    stats["seconds"] = time.perf_counter() - t0
    return stats


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--examples", type=int, default=3000, help="per target")
    parser.add_argument("--seed", type=int, default=None, help="default: time-based")
    parser.add_argument("--only", default="", help="comma list of targets (default: all)")
    args = parser.parse_args(argv)
    if args.examples < 1:
        parser.error(f"--examples must be >= 1, got {args.examples}")
    names = [n for n in args.only.split(",") if n] or list(test_fuzz.TARGETS)
    unknown = sorted(set(names) - set(test_fuzz.TARGETS))
    if unknown:
        parser.error(f"unknown target(s) {unknown}; known: {sorted(test_fuzz.TARGETS)}")
    run_seed = args.seed if args.seed is not None else int(time.time())
    print(f"fuzz seed {run_seed}; {args.examples} examples per target", flush=True)
    print(f"{'target':20s} {'examples':>9s} {'crashes':>8s} {'seconds':>8s}", flush=True)
    total = {"examples": 0, "crashes": 0, "seconds": 0.0}
    errors: dict[str, dict[str, int]] = {}
    for name in names:
        stats = run_target(name, args.examples, run_seed)
        print(
            f"{name:20s} {stats['examples']:9d} {stats['crashes']:8d} {stats['seconds']:8.1f}",
            flush=True,
        )
        for key in ("examples", "crashes", "seconds"):
            total[key] += stats[key]
        if stats["errors"]:
            errors[name] = stats["errors"]
    test_fuzz.close_cached_envs()
    print(f"{'total':20s} {total['examples']:9d} {total['crashes']:8d} {total['seconds']:8.1f}")
    for name, seen in errors.items():
        print(f"\n{name}: {sum(seen.values())} crash(es), {len(seen)} distinct")
        for line, count in sorted(seen.items(), key=lambda kv: -kv[1])[:10]:
            print(f"  {count:5d} x {line}")
    return 1 if total["crashes"] else 0


if __name__ == "__main__":
    sys.exit(main())
