"""Rig-level gap diagnosis over a few cases per rig (studies/2026-11-diagnosis-validation/README.md).

    python studies/2026-11-diagnosis-validation/diagnose_rigs.py [--json FILE]

Each case: a reference bushing (``RubberBushing`` preset, measurement effects off) with the
backbone and at most one effect switched on, the model side a linear bushing identified on the
reference's TRAIN record (``model="identify"``); ``bushenv.diagnose.rigs.diagnose_rig`` replays
the TRAIN and TEST profiles and names the channel and the effect. BushRig-v0 (axial): TRAIN
RPC-like n = 1, 20 s; TESTs RPC-like n = 1.5, 10 s and a 3 mm step held 4 s. QuarterCar-v0
(effect in the radial bushing, axial bushing linear): TRAIN a durability-spectrum random road,
30 mm peak, 8 s; TESTs the same at 45 mm (6 s), a 400 x 100 mm bump and a 700 x 60 mm pothole
at 30 km/h. Everything is deterministic.
"""

from __future__ import annotations

import argparse
import json
import sys
import time

from bushenv import excitation as ex
from bushenv.diagnose.rigs import diagnose_rig
from bushenv.models.base import PAPER_DT
from bushenv.reference.rubber import RubberBushing

DT = PAPER_DT
BUSHRIG_CASES = [
    ("none", {}),
    ("relaxation", {}),
    ("friction", {}),
    ("hardening", {}),
    ("hardening", {"hardening_x_m": 5e-3}),
    ("thermal", {}),
]
QUARTERCAR_CASES = [
    ("none", {}),
    ("relaxation", {}),
    ("friction", {}),
    ("hardening", {}),
    ("hardening", {"hardening_x_m": 4e-3}),
    ("thermal", {}),
]


def bushrig_profiles():
    train = ex.random_rpc(1.0, 20.0, DT, seed=0)
    tests = [
        ex.random_rpc(1.5, 10.0, DT, seed=1),
        ex.sequence(
            ex.step_hold(3e-3, 4.0, DT, rise_s=0.05),
            ex.ramp(0.0, 0.05, DT, start_m=3e-3, hold_s=1.0),
        ),
    ]
    return train, tests


def road_profiles():
    train = ex.random_band(8.0, DT, seed=0, peak_m=0.03, spectrum="durability")
    tests = [
        ex.random_band(6.0, DT, seed=1, peak_m=0.045, spectrum="durability"),
        ex.bump(0.4, 0.1, 30 / 3.6, DT, pre_s=0.3, post_s=1.5),
        ex.pothole(0.7, 0.06, 30 / 3.6, DT, pre_s=0.3, post_s=1.5),
    ]
    return train, tests


def reference(axis: str, effect: str, overrides: dict):
    effects = () if effect == "none" else (effect,)
    return RubberBushing.preset(axis, effects=effects, measurement=False, **overrides)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", help="also write the rows to this file")
    ap.add_argument(
        "--raw-x",
        action="store_true",
        help="BushRig-v0: give the diagnosis the raw x_k instead of each step's midpoint",
    )
    args = ap.parse_args(argv)
    rows = []
    runs = [("BushRig-v0", c) for c in BUSHRIG_CASES]
    runs += [("QuarterCar-v0", c) for c in QUARTERCAR_CASES]
    for i, (env_id, (effect, overrides)) in enumerate(runs):
        t0 = time.perf_counter()
        if env_id == "BushRig-v0":
            train, tests = bushrig_profiles()
            ref = reference("axial", effect, overrides)
            r = diagnose_rig(
                env_id, "identify", ref, train, tests, axis="axial", midpoint=not args.raw_x
            )
        else:
            train, tests = road_profiles()
            ref = {
                "radial": reference("radial", effect, overrides),
                "axial": reference("axial", "none", {}),
            }
            r = diagnose_rig(env_id, "identify", ref, train, tests)
        gap_of = {c["channel"]: c["gap"] for c in r["channels"]}
        withheld = effect + "".join(f" ({k} {v:g})" for k, v in overrides.items())
        row = {
            "rig": env_id,
            "withheld": withheld,
            "channel": r["channel"],
            "rig_gap": r["rig_gap"],
            "force_channel": r["force_channel"],
            "force_gap": gap_of[r["force_channel"]],
            "axis": r["axis"],
            "effect": r["effect"],
            "record_alone": r["bushing_effect"],
            "runner_up": r["top_two"][1],
            "bushing_gap": r["gap_before"],
            "shrink": r["shrink"],
            "seconds": time.perf_counter() - t0,
        }
        rows.append(row)
        print(f"[{i + 1}/{len(runs)}] {env_id} {withheld}: {r['effect']}", file=sys.stderr)
    print(
        "| rig | effect withheld | channel named (gap) | force channel (gap) | axis "
        "| effect named | record alone | runner-up | bushing gap | shrink |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    for w in rows:
        print(
            f"| {w['rig']} | {w['withheld']} | {w['channel']} ({100 * w['rig_gap']:.2f} %) "
            f"| {w['force_channel']} ({100 * w['force_gap']:.2f} %) | {w['axis']} "
            f"| **{w['effect']}** | {w['record_alone']} | {w['runner_up']} "
            f"| {100 * w['bushing_gap']:.2f} % | {100 * w['shrink']:.1f} % |"
        )
    total = sum(w["seconds"] for w in rows)
    print(f"\n{len(rows)} cases, {total:.1f} s")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
