"""The 3-axis table: planar models identified on random n = 1, judged on unseen coupled records.

    python scripts/planar_benchmark.py [--seeds 0 1] [--quiet] [--out docs/planar_benchmark.json]

For each seed: the planar reference (with load-cell noise, its own noise seed) is driven by
60 s of independent random motion at n = 1 on all axes; linear (3x3 K, C by least squares),
the per-axis networks (seed 000 §4.2's kind), the MIMO network, the MIMO hybrid, the vector
Bouc-Wen and the hybrid on it (``hybrid-bw``; default options) are identified from it; each
is run free on the unseen records of ``bushenv.motions`` (n = 1.5) against the
reference. Prints RMS ratio and MAX error
(% of max |f|, as seed 000 Table 3) per axis, beside Table 3, and writes the numbers as JSON.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time

import numpy as np

from bushenv.identify.mimo_options import MimoOptions as TrainOptions
from bushenv.identify.mimo_train import fit_mimo
from bushenv.identify.vector_boucwen import fit_vector_boucwen
from bushenv.metrics import max_error_ratio, rms_ratio
from bushenv.models.base import PAPER_DT, velocity_of
from bushenv.models.planar_base import COORDS
from bushenv.models.planar_hybrid_bw import compose
from bushenv.models.planar_linear import fit_linear
from bushenv.motions import random_independent, verification_motions
from bushenv.progress import Progress
from bushenv.reference.planar import PlanarRubber

MODELS = ("linear", "nn-axis", "nn", "hybrid", "boucwen", "hybrid-bw")
TABLE3 = {  # seed 000 Table 3, RMS ratio / MAX in %, linear / NN / hybrid
    "axial": {"rms": (10.9, 5.2, 5.1), "max": (24.9, 9.3, 8.4)},
    "radial": {"rms": (5.1, 3.0, 3.0), "max": (20.7, 8.3, 7.8)},
}


def reference(uncoupled: bool, seed: int) -> PlanarRubber:
    """The preset (noise on); ``uncoupled``: coupling off and friction axis by axis."""
    if not uncoupled:
        return PlanarRubber.preset(seed=seed)
    ref = PlanarRubber.preset(seed=seed, friction_yield="axis")
    return ref.without_effects("coupling")


def parse_options(text: str) -> TrainOptions:
    """``key=value,key=value`` over ``TrainOptions``; ValueError naming an unknown key or value."""
    fields = {f.name: f.type for f in dataclasses.fields(TrainOptions)}
    kwargs = {}
    for item in filter(None, text.split(",")):
        key, _, value = item.partition("=")
        key = key.strip()
        if key not in fields:
            raise ValueError(f"--options: unknown key {key!r}; known: {', '.join(fields)}")
        try:
            kwargs[key] = (int if fields[key] in (int, "int") else float)(value)
        except ValueError:
            raise ValueError(f"--options: {key}={value!r} is not a number") from None
    return TrainOptions(**kwargs)


def run_seed(
    seed: int, progress: Progress, done: list[int], uncoupled: bool = False, options=None
) -> dict:
    dt = PAPER_DT
    q = random_independent(1.0, 60.0, dt, seed)
    f = reference(uncoupled, seed).simulate(q)
    models = {"linear": fit_linear(q, velocity_of(q, dt), f, dt)}
    for kind in MODELS[1:4]:
        t0 = time.perf_counter()
        models[kind] = fit_mimo(q, f, dt, kind=kind, seed=seed, options=options)
        done[0] += 1
        progress.update(done[0], f"seed {seed}: {kind} trained in {time.perf_counter() - t0:.0f} s")
    t0 = time.perf_counter()
    models["boucwen"] = fit_vector_boucwen([(q, f)], dt)[0]
    done[0] += 1
    progress.update(done[0], f"seed {seed}: boucwen fitted in {time.perf_counter() - t0:.0f} s")
    t0 = time.perf_counter()  # hybrid-bw: that Bouc-Wen as backbone, the MIMO net on its residual
    residual = f - models["boucwen"].simulate(q)
    net = fit_mimo(q, residual, dt, kind="nn", seed=seed, options=options)
    models["hybrid-bw"] = compose(models["boucwen"], net)
    done[0] += 1
    progress.update(done[0], f"seed {seed}: hybrid-bw trained in {time.perf_counter() - t0:.0f} s")
    out = {}
    for name, qt in verification_motions(dt, seed).items():
        ft = reference(uncoupled, seed + 100).simulate(qt)
        out[name] = {}
        for kind, m in models.items():
            pred = m.simulate(qt)
            out[name][kind] = {
                c: {
                    "rms": 100 * rms_ratio(ft[:, i], pred[:, i]),
                    "max": 100 * max_error_ratio(ft[:, i], pred[:, i]),
                    "max_abs": float(np.abs(ft[:, i] - pred[:, i]).max()),
                    "at_rest": bool(np.all(qt[:, i] == 0)),
                }
                for i, c in enumerate(COORDS)
            }
    return out


def coupling_shares(seed: int = 0) -> str:
    """How much of the reference's force the coupling carries on the n = 1.5 independent record:
    RMS of (coupled - switched off) / RMS of coupled, per axis, specimen without noise."""
    q = verification_motions(PAPER_DT, seed)["random independent"]
    full = PlanarRubber.preset(measurement=False)
    f = full.simulate(q)
    cases = {
        "elastic coupling off": full.without_effects("coupling"),
        "friction axis by axis": PlanarRubber.preset(measurement=False, friction_yield="axis"),
    }
    lines = []
    for name, m in cases.items():
        g = m.simulate(q)
        shares = [100 * rms_ratio(f[:, i], g[:, i]) for i in range(3)]
        lines.append(
            f"{name}: " + ", ".join(f"{c} {v:.1f} %" for c, v in zip(COORDS, shares, strict=True))
        )
    return "\n".join(lines)


def table(results: dict[int, dict]) -> str:
    """Markdown: per record and axis, RMS / MAX % for each model (mean over seeds, and range)."""
    seeds = sorted(results)
    records = list(results[seeds[0]])
    head = (
        "| record | axis | "
        + " | ".join(f"{k} RMS / MAX %" for k in MODELS)
        + " | nn-axis / nn RMS |"
    )
    lines = [head, "|" + "---|" * (len(MODELS) + 3)]
    for rec in records:
        for c in COORDS:
            if results[seeds[0]][rec]["linear"][c]["at_rest"]:
                # only load-cell noise to compare with: the force the model invents, in N
                unit = "N m" if c == "rotation" else "N"
                cells = [
                    f"{np.mean([results[s][rec][k][c]['max_abs'] for s in seeds]):.0f} {unit}"
                    for k in MODELS
                ]
                lines.append(f"| {rec} | {c} at rest: max error | " + " | ".join(cells) + " | - |")
                continue
            cells = []
            for k in MODELS:
                r = [results[s][rec][k][c]["rms"] for s in seeds]
                m = [results[s][rec][k][c]["max"] for s in seeds]
                spread = f" ({min(r):.1f}-{max(r):.1f})" if len(seeds) > 1 else ""
                cells.append(f"{np.mean(r):.1f}{spread} / {np.mean(m):.1f}")
            ratio = np.mean(
                [
                    results[s][rec]["nn-axis"][c]["rms"] / results[s][rec]["nn"][c]["rms"]
                    for s in seeds
                ]
            )
            lines.append(f"| {rec} | {c} | " + " | ".join(cells) + f" | {ratio:.2f} |")
    for c, t in TABLE3.items():
        cells = [
            f"{t['rms'][0]} / {t['max'][0]}",
            "-",
            f"{t['rms'][1]} / {t['max'][1]}",
            f"{t['rms'][2]} / {t['max'][2]}",
            "-",
            "-",
        ]
        lines.append(f"| seed 000 Table 3 | {c} | " + " | ".join(cells) + " | - |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--out", default=None, help="write the numbers as JSON here")
    ap.add_argument(
        "--uncoupled", action="store_true", help="reference without coupling, axis friction"
    )
    ap.add_argument(
        "--options", default="", help="training budget, e.g. teacher_steps=1500,window=256"
    )
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args()
    progress = Progress(5 * len(args.seeds), quiet=args.quiet, label="planar benchmark")
    done = [0]
    try:
        opts = parse_options(args.options)
    except ValueError as exc:
        ap.error(str(exc))  # exit 2
    results = {s: run_seed(s, progress, done, args.uncoupled, opts) for s in args.seeds}
    progress.update(None, "done", force=True)
    print(table(results))
    print(coupling_shares(args.seeds[0]))
    if args.out:
        with open(args.out, "w") as fh:
            json.dump({str(k): v for k, v in results.items()}, fh, indent=1)


if __name__ == "__main__":
    main()
