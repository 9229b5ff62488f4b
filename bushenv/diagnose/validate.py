"""Blind validation of the gap diagnosis on the reference rubber bushing.

    bushenv diagnose-validate --cases N --seed S --out DIR

Each case draws, from ``(seed, case index)``, a reference bushing (``bushenv.reference.rubber``)
with a hidden label -- ``none`` (backbone + noise), one effect, or two effects -- simulates a
TRAIN record and two TEST records, hands the records alone to ``diagnose`` (linear baseline)
and compares its answer with the label.

What varies beyond what the candidates assume (the diagnosis must not win by knowing the
reference's equations):

| what            | drawn                                                                        |
|-----------------|------------------------------------------------------------------------------|
| backbone        | k log-uniform 150..1500 kN/m, c = k * (4..20) ms                               |
| relaxation      | 1..5 Maxwell branches, tau log-uniform 0.01..10 s (off the candidates' grid),  |
|                 | each k_i = k * (0.08..0.4)                                                   |
| friction        | Berg or Iwan law (the candidates use Dahl elements),                          |
|                 | F_max = (4..18) % of k x_pk, x2 = (2..15) % of x_pk                            |
| hardening       | cubic, tangent or exponential (sinh) law (candidates: odd polynomial), 4..25 % |
|                 | extra force at the TEST peak                                                 |
| thermal         | heating by the reference's own dissipated power (damper, Maxwell, friction),  |
|                 | time constant 20..300 s, stiffness drop 4..20 % over TRAIN, a_c/a_k 0.5..3     |
| delay           | 0.4..8 ms, linear interpolation inside the reference (candidate: spline)      |
| inertia         | fixture mass with m (2 pi 15 Hz)^2 / k = 3..30 %, backward-difference          |
|                 | acceleration inside the reference (candidate: central)                       |
| noise           | always on: std log-uniform 0.2..3 % of the backbone force RMS                 |
| sample rate     | 204.8, 512 or 1024 Hz; in a third of the cases the TESTs run at another rate   |
| records         | TRAIN: RPC-like random n = 0.8..1.2, 20..60 s, then a held step 2..4 mm;       |
|                 | TEST 1: RPC-like random n = 1.2..1.6, 8..25 s; TEST 2: a step held 3..10 s,    |
|                 | then a sine (1..15 Hz) or a chirp (0.5..20 Hz)                               |

The case mix is balanced: three cases in four are single-class (cycling through ``none`` and the
six effects), one in four a two-effect case (a random pair).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.diagnose.candidates import EFFECTS
from bushenv.diagnose.fit import DiagnoseError, diagnose

CLASSES = ("none",) + EFFECTS
RATES_HZ = (204.8, 512.0, 1024.0)
EXAMPLE = "bushenv diagnose-validate --cases 70 --seed 0 --out validation/"


@dataclass
class Case:
    """One blind case: the hidden label, the records, and what was drawn (for the log)."""

    index: int
    label: tuple[str, ...]  # () for none
    train: Any
    tests: list[Any]
    drawn: dict[str, Any] = field(default_factory=dict)

    @property
    def label_text(self) -> str:
        return "+".join(self.label) if self.label else "none"


def case_label(index: int, rng: np.random.Generator) -> tuple[str, ...]:
    """Balanced mix: index % 4 == 3 is a random pair, the rest cycle through the 7 classes."""
    if index % 4 == 3:
        pair = rng.choice(len(EFFECTS), size=2, replace=False)
        return tuple(EFFECTS[i] for i in sorted(pair))
    single = index - (index + 1) // 4  # how many single-class cases came before
    name = CLASSES[single % len(CLASSES)]
    return () if name == "none" else (name,)


def _loguniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(np.exp(rng.uniform(np.log(lo), np.log(hi))))


def _programmes(rng: np.random.Generator, dt_train: float, dt_test: float, seed: int):
    from bushenv import excitation as ex

    n_train = rng.uniform(0.8, 1.2)
    d_train = rng.uniform(20.0, 60.0)
    step = rng.uniform(2e-3, 4e-3) * rng.choice([-1.0, 1.0])
    hold = rng.uniform(3.0, 8.0)
    x_train = ex.sequence(
        ex.random_rpc(n_train, d_train, dt_train, seed),
        ex.step_hold(step, hold, dt_train, pre_s=0.5, rise_s=0.05),
        step - ex.step_hold(step, 2.0, dt_train, pre_s=0.0, rise_s=0.05),
    )
    n_test = rng.uniform(1.2, 1.6)
    x_test1 = ex.random_rpc(n_test, rng.uniform(8.0, 25.0), dt_test, seed + 1)
    step2 = rng.uniform(2e-3, 4e-3) * rng.choice([-1.0, 1.0])
    hold2 = rng.uniform(3.0, 10.0)
    if rng.random() < 0.5:
        tail = ex.sine(rng.uniform(1.0, 15.0), rng.uniform(1e-3, 3e-3), rng.uniform(4, 10), dt_test)
        tail_name = "sine"
    else:
        tail = ex.chirp(0.5, 20.0, rng.uniform(1e-3, 2.5e-3), rng.uniform(8, 20), dt_test)
        tail_name = "chirp"
    x_test2 = ex.sequence(
        ex.step_hold(step2, hold2, dt_test, pre_s=0.5, rise_s=0.05),
        step2 - ex.step_hold(step2, 1.0, dt_test, pre_s=0.0, rise_s=0.05),
        tail,
    )
    info = {
        "train_s": round(x_train.size * dt_train, 2),
        "test_s": [round(x_test1.size * dt_test, 2), round(x_test2.size * dt_test, 2)],
        "test2": f"step {1e3 * step2:.2f} mm held {hold2:.1f} s + {tail_name}",
    }
    return x_train, [x_test1, x_test2], info


def make_case(seed: int, index: int) -> Case:
    """Draw case ``index`` of validation run ``seed``: reference bushing, records, label."""
    from bushenv.records import Record
    from bushenv.reference.rubber import RubberBushing

    rng = np.random.default_rng([seed, index])
    label = case_label(index, rng)
    rate_train = float(rng.choice(RATES_HZ))
    rate_test = float(rng.choice(RATES_HZ)) if rng.random() < 1 / 3 else rate_train
    dt_train, dt_test = 1.0 / rate_train, 1.0 / rate_test
    case_seed = int(rng.integers(0, 2**31 - 1))
    x_train, x_tests, info = _programmes(rng, dt_train, dt_test, case_seed)

    k = _loguniform(rng, 150e3, 1.5e6)
    c = k * rng.uniform(0.004, 0.02)
    x_pk = max(float(np.max(np.abs(x))) for x in x_tests)
    params: dict[str, Any] = {"k_n_per_m": k, "c_ns_per_m": c}
    drawn: dict[str, Any] = {"rate_train_hz": rate_train, "rate_test_hz": rate_test, **info}
    if "relaxation" in label:
        n = int(rng.integers(1, 6))
        params["relax_k_n_per_m"] = tuple(k * rng.uniform(0.08, 0.4) for _ in range(n))
        params["relax_tau_s"] = tuple(_loguniform(rng, 0.01, 10.0) for _ in range(n))
        drawn["relax_tau_s"] = [round(t, 4) for t in params["relax_tau_s"]]
    if "friction" in label:
        params["friction_law"] = str(rng.choice(["berg", "iwan"]))
        params["friction_fmax_n"] = rng.uniform(0.04, 0.18) * k * x_pk
        params["friction_x2_m"] = rng.uniform(0.02, 0.15) * x_pk
        drawn["friction_law"] = params["friction_law"]
    if "hardening" in label:
        law = str(rng.choice(["cubic", "tangent", "exponential"]))
        extra = rng.uniform(0.04, 0.25)  # extra force at the TEST peak
        # g(x) ~ x (1 + (x/xh)^2 / q) for small x: q = 1 cubic, 3 tangent, 6 sinh
        q = {"cubic": 1.0, "tangent": 3.0, "exponential": 6.0}[law]
        params["hardening_law"] = law
        params["hardening_x_m"] = x_pk / np.sqrt(q * extra)
        drawn["hardening_law"] = law
    if "delay" in label:
        params["delay_s"] = rng.uniform(0.4e-3, 8e-3)
    if "inertia" in label:
        params["fixture_mass_kg"] = rng.uniform(0.03, 0.3) * k / (2 * np.pi * 15.0) ** 2
    if "thermal" in label:
        v = np.gradient(x_train, dt_train)
        energy = float(np.sum(c * v * v) * dt_train)  # J dissipated in the damper over TRAIN
        tau = rng.uniform(20.0, 300.0)
        rise = rng.uniform(5.0, 30.0)  # K, roughly, at the end of TRAIN
        heat_cap = energy / rise
        drop = rng.uniform(0.04, 0.2)
        params["thermal_c_j_per_k"] = heat_cap
        params["thermal_r_k_per_w"] = tau / heat_cap
        params["thermal_ak_per_k"] = drop / rise
        params["thermal_ac_per_k"] = params["thermal_ak_per_k"] * rng.uniform(0.5, 3.0)
        drawn["thermal_tau_s"] = round(tau, 1)

    def simulate(x: np.ndarray, dt: float, noise_seed: int, with_noise: bool) -> np.ndarray:
        model = RubberBushing(
            dt=dt, seed=noise_seed, noise_std_n=noise_std if with_noise else 0.0, **params
        )
        return model.simulate(x)

    # noise relative to the backbone force RMS on TRAIN
    backbone = k * x_train + c * np.gradient(x_train, dt_train)
    noise_frac = _loguniform(rng, 0.002, 0.03)
    noise_std = noise_frac * float(np.sqrt(np.mean(backbone**2)))
    drawn["noise_fraction"] = round(noise_frac, 4)
    f_train = simulate(x_train, dt_train, case_seed + 11, True)
    train = Record.from_arrays(x_train, f_train, dt_train, name="train")
    tests = []
    for j, x in enumerate(x_tests):
        f = simulate(x, dt_test, case_seed + 12 + j, True)
        tests.append(Record.from_arrays(x, f, dt_test, name=f"test{j + 1}"))
    return Case(index, label, train, tests, drawn)


def judge_case(case: Case, result: dict[str, Any]) -> dict[str, Any]:
    named = result["effect"]
    first = named.split("+")[0]
    row = {
        "case": case.index,
        "label": case.label_text,
        "named": named,
        "top1": first,
        "top_two": result["top_two"],
        "shrink": result["shrink"],
        "gap_before": result["gap_before"],
        "gap_after": result["gap_after"],
        "drawn": case.drawn,
    }
    if len(case.label) <= 1:
        truth = case.label[0] if case.label else "none"
        row["kind"] = "single"
        row["right"] = first == truth
        row["exact"] = named == truth
    else:
        row["kind"] = "pair"
        row["right"] = set(result["top_two"]) == set(case.label) and named != "none"
        row["pair_named"] = set(named.split("+")) == set(case.label)
    return row


def summarise(rows: list[dict[str, Any]]) -> dict[str, Any]:
    singles = [r for r in rows if r["kind"] == "single"]
    pairs = [r for r in rows if r["kind"] == "pair"]
    idx = {c: i for i, c in enumerate(CLASSES)}
    confusion = np.zeros((len(CLASSES), len(CLASSES)), dtype=int)
    for r in singles:
        confusion[idx[r["label"]], idx[r["top1"]]] += 1
    right = [r for r in rows if r["right"] and r["label"] != "none"]
    return {
        "cases": len(rows),
        "single_cases": len(singles),
        "pair_cases": len(pairs),
        "single_top1_rate": float(np.mean([r["right"] for r in singles])) if singles else None,
        "single_named_exactly_rate": (
            float(np.mean([r["exact"] for r in singles])) if singles else None
        ),
        "pair_hit_rate": float(np.mean([r["right"] for r in pairs])) if pairs else None,
        "pair_named_exactly_rate": (
            float(np.mean([r["pair_named"] for r in pairs])) if pairs else None
        ),
        "median_shrink_named_right": (
            float(np.median([r["shrink"] for r in right])) if right else None
        ),
        "classes": list(CLASSES),
        "confusion": confusion.tolist(),
    }


def confusion_table(summary: dict[str, Any]) -> str:
    classes = summary["classes"]
    head = "| true \\ named | " + " | ".join(classes) + " |"
    lines = [head, "|" + "---|" * (len(classes) + 1)]
    for c, row in zip(classes, summary["confusion"], strict=True):
        lines.append(f"| {c} | " + " | ".join(str(v) for v in row) + " |")
    return "\n".join(lines)


def run_validation(
    n_cases: int, seed: int, progress=None, start: int = 0
) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """Draw, diagnose and judge ``n_cases`` cases; returns per-case rows and the summary."""
    say = progress or (lambda msg: None)
    rows = []
    for i in range(start, start + n_cases):
        t0 = time.monotonic()
        case = make_case(seed, i)
        result = diagnose(case.train, case.tests, baseline="linear")
        row = judge_case(case, result)
        row["seconds"] = round(time.monotonic() - t0, 2)
        rows.append(row)
        say(
            f"case {i + 1 - start}/{n_cases}: label {row['label']:<22} named {row['named']:<22} "
            f"{'right' if row['right'] else 'WRONG'}  shrink {100 * row['shrink']:5.1f} %  "
            f"({row['seconds']:.1f} s)"
        )
    return rows, summarise(rows)


def report_text(summary: dict[str, Any], seed: int) -> str:
    pct = lambda v: "n/a" if v is None else f"{100 * v:.1f} %"  # noqa: E731
    return "\n".join(
        [
            f"Blind validation: {summary['cases']} cases (seed {seed}), linear baseline",
            "",
            "Single-effect cases (incl. none): rows = hidden label, columns = top-1 named",
            "",
            confusion_table(summary),
            "",
            f"- top-1 on single-effect cases (incl. none): {pct(summary['single_top1_rate'])} "
            f"of {summary['single_cases']} (named exactly, no second effect added: "
            f"{pct(summary['single_named_exactly_rate'])})",
            f"- two-effect cases, both in the top two: {pct(summary['pair_hit_rate'])} of "
            f"{summary['pair_cases']} (pair named exactly: "
            f"{pct(summary['pair_named_exactly_rate'])})",
            f"- median shrink on cases named right: {pct(summary['median_shrink_named_right'])}",
            "",
        ]
    )


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--cases", type=int, default=70, help="number of blind cases (default 70)")
    parser.add_argument("--seed", type=int, default=0, help="validation seed (default 0)")
    parser.add_argument("--out", required=True, metavar="DIR", help="output folder")
    parser.add_argument("--force", action="store_true", help="write into an existing DIR")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")


def run(args: argparse.Namespace) -> int:
    from bushenv.diagnose.report import _atomic_write, check_out_dir

    if args.cases < 1:
        raise DiagnoseError(f"--cases must be >= 1, got {args.cases}")
    out = Path(args.out)
    check_out_dir(out, args.force)
    start = time.monotonic()

    def progress(msg: str) -> None:
        if not args.quiet:
            print(f"[{time.monotonic() - start:7.1f} s] {msg}", file=sys.stderr, flush=True)

    rows, summary = run_validation(args.cases, args.seed, progress)
    out.mkdir(parents=True, exist_ok=True)
    text = report_text(summary, args.seed)
    command = f"bushenv diagnose-validate --cases {args.cases} --seed {args.seed} --out {out}"
    data = {"command": command, "summary": summary, "cases": rows}
    _atomic_write(out / "validation.json", json.dumps(data, indent=2) + "\n")
    _atomic_write(out / "validation.md", f"`{command}`\n\n{text}")
    print(text)
    return 0
