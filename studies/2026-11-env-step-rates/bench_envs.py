"""Step rate of every bushenv environment with every available model, beside CartPole-v1.

Measures, in one run on this machine: Gymnasium's CartPole-v1 (single env through gym.make, and
its numpy-vectorised CartPoleVectorEnv), BushRig-v0 single and vectorised (the array
VectorEnv), QuarterCar-v0 single, its vector env and the QuarterCarBatch integrator under it
(road searches call it directly). Random actions are drawn in bulk beforehand; episodes that
end are reset inside the timed loop (as a rollout would).
Each figure is the best of ``--repeats`` runs (other jobs on shared cores only ever slow a run
down). Prints a table; ``--json FILE`` also writes the rows.

    python studies/2026-11-env-step-rates/bench_envs.py                      # all models found, defaults
    python studies/2026-11-env-step-rates/bench_envs.py --steps 5000 --num-envs 256 --json bench.json
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")

import gymnasium as gym  # noqa: E402
import numpy as np  # noqa: E402

import bushenv  # noqa: E402,F401  (registers the envs)
from bushenv.models import ModelError, get_model  # noqa: E402
from bushenv.rigs.quartercar_batch import QuarterCarBatch  # noqa: E402

MODELS = ("linear", "nn", "hybrid", "boucwen", "rubber")


def available(name: str, axes=("axial", "radial")) -> bool:
    try:
        for axis in axes:
            get_model(name, axis)
    except ModelError:
        return False
    return True


REPEATS = 3


def time_single(env, actions) -> float:
    """Seconds per env step over ``actions`` (resets on episode end are included)."""
    env.reset(seed=0)
    for a in actions[: max(50, len(actions) // 10)]:  # warm-up: compile, caches
        _, _, term, trunc, _ = env.step(a)
        if term or trunc:
            env.reset()
    env.reset(seed=0)
    step, reset = env.step, env.reset
    t0 = time.perf_counter()
    for a in actions:
        _, _, term, trunc, _ = step(a)
        if term or trunc:
            reset()
    return (time.perf_counter() - t0) / len(actions)


def time_vector(env, actions) -> float:
    """Seconds per vector step (all sub-envs); autoreset is the env's own."""
    env.reset(seed=0)
    for a in actions[: max(5, len(actions) // 10)]:
        env.step(a)
    env.reset(seed=0)
    t0 = time.perf_counter()
    for a in actions:
        env.step(a)
    return (time.perf_counter() - t0) / len(actions)


def time_batch(batch, road) -> float:
    t0 = time.perf_counter()
    batch.simulate(road)
    return (time.perf_counter() - t0) / road.shape[0]


def row(env_id, model, mode, n, sec_per_step, cartpole_us):
    us_env_step = sec_per_step * 1e6 / n
    return {
        "env": env_id,
        "model": model,
        "mode": mode,
        "num_envs": n,
        "env_steps_per_s": n / sec_per_step,
        "us_per_env_step": us_env_step,
        "x_cartpole_single": us_env_step / cartpole_us if cartpole_us else 1.0,
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=20000, help="single-env steps per measurement")
    ap.add_argument("--vector-steps", type=int, default=500, help="vector steps per measurement")
    ap.add_argument("--num-envs", type=int, default=256, help="sub-environments when vectorised")
    ap.add_argument("--quartercar-steps", type=int, default=2000)
    ap.add_argument("--models", nargs="*", default=list(MODELS))
    ap.add_argument("--repeats", type=int, default=3, help="best of this many runs")
    ap.add_argument("--json", metavar="FILE", help="also write the rows as JSON")
    args = ap.parse_args(argv)
    global REPEATS
    REPEATS = max(1, args.repeats)
    rng = np.random.default_rng(0)
    n = args.num_envs
    rows = []

    # every measurement is a job; the jobs run round-robin ``repeats`` times and each keeps
    # its best, so a busy moment on the shared cores cannot skew one ratio against another
    jobs = []  # (env, model, mode, num_envs, callable -> seconds per step)
    cp_actions = [int(a) for a in rng.integers(0, 2, args.steps)]
    cp = gym.make("CartPole-v1")
    jobs.append(("CartPole-v1", "-", "single", 1, lambda: time_single(cp, cp_actions)))
    cpv = gym.make_vec("CartPole-v1", num_envs=n, vectorization_mode="vector_entry_point")
    cp_vacts = rng.integers(0, 2, (args.vector_steps, n))
    jobs.append(("CartPole-v1", "-", "vector (numpy)", n, lambda: time_vector(cpv, cp_vacts)))

    models = [m for m in args.models if available(m)]
    missing = sorted(set(args.models) - set(models))
    if missing:
        print(f"models without a default file here (skipped): {missing}", flush=True)
    for m in models:
        acts = list(rng.uniform(-1, 1, (args.steps, 1)).astype(np.float32))
        env = gym.make("BushRig-v0", model=m)
        jobs.append(("BushRig-v0", m, "single", 1, lambda e=env, a=acts: time_single(e, a)))
        venv = gym.make_vec(
            "BushRig-v0", num_envs=n, vectorization_mode="vector_entry_point", model=m
        )
        vacts = rng.uniform(-1, 1, (args.vector_steps, n, 1)).astype(np.float32)
        jobs.append(
            ("BushRig-v0", m, "vector (arrays)", n, lambda e=venv, a=vacts: time_vector(e, a))
        )
    for m in models:
        acts = list(rng.uniform(-0.3, 0.3, (args.quartercar_steps, 1)).astype(np.float32))
        env = gym.make("QuarterCar-v0", model=m)
        jobs.append(
            ("QuarterCar-v0", m, "single (pymunk)", 1, lambda e=env, a=acts: time_single(e, a))
        )
        batch = QuarterCarBatch(n, model=m)
        road = np.clip(np.cumsum(rng.uniform(-0.01, 0.01, (200, n)), axis=0), -0.1, 0.1)
        batch.simulate(road[:20])  # warm-up
        jobs.append(
            ("QuarterCar-v0", m, "QuarterCarBatch", n, lambda b=batch, r=road: time_batch(b, r))
        )
        qvenv = gym.make_vec(
            "QuarterCar-v0", num_envs=n, vectorization_mode="vector_entry_point", model=m
        )
        qacts = rng.uniform(-0.3, 0.3, (args.vector_steps, n, 1)).astype(np.float32)
        jobs.append(
            ("QuarterCar-v0", m, "vector (arrays)", n, lambda e=qvenv, a=qacts: time_vector(e, a))
        )

    best = [float("inf")] * len(jobs)
    for rep in range(REPEATS):
        print(f"round {rep + 1}/{REPEATS}", flush=True)
        for k, (env_id, m, mode, num, fn) in enumerate(jobs):
            best[k] = min(best[k], fn())
            print(f"  {env_id:<14} {m:<8} {mode:<18} {best[k] * 1e6 / num:9.3f} us/env-step",
                  flush=True)  # fmt: skip
    cartpole_us = best[0] * 1e6
    for (env_id, m, mode, num, _), sec in zip(jobs, best, strict=True):
        rows.append(row(env_id, m, mode, num, sec, cartpole_us))

    print()
    print(f"{'env':<14} {'model':<8} {'mode':<18} {'N':>5} {'env-steps/s':>13} "
          f"{'us/env-step':>12} {'x CartPole':>11}")  # fmt: skip
    for r in rows:
        print(
            f"{r['env']:<14} {r['model']:<8} {r['mode']:<18} {r['num_envs']:>5} "
            f"{r['env_steps_per_s']:>13,.0f} {r['us_per_env_step']:>12.3f} "
            f"{r['x_cartpole_single']:>11.2f}"
        )
    if args.json:
        meta = {
            "python": sys.version.split()[0],
            "machine": platform.machine(),
            "load_average": os.getloadavg(),
            "steps": args.steps,
            "repeats": REPEATS,
            "num_envs": n,
        }
        with open(args.json, "w", encoding="utf-8") as fh:
            json.dump({"meta": meta, "rows": rows}, fh, indent=2)
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
