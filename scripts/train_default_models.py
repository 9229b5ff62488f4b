"""Identify the default nn, hybrid and boucwen models shipped in bushenv/data/models/.

For each axis: the identification record is the reference rubber preset (with the load cell's
delay, inertia and noise) driven by an n = 1 RPC-like random record (40 s, seed IDENT_SEED);
the verification record is n = 1.5 (20 s, seed VERIFY_SEED), never seen in training (seed 000
§4.2, seed 001 §4). Each model is fitted with ``bushenv.identify.fit_model`` (the options in
``OPTIONS``: the NARX models train with the certified-hold term, ``--certified on``, see
docs/fit.md) and saved as ``{axis}_{name}.npz``. Printed per model: training time, free-run RMS
ratio / ESR / max error on the n = 1.5 record, the free response to the 4 mm step held 10 s
(seed 000 §5.2): whether it settles (last 2 s within 1 % of the peak force, all finite) and
where it ends next to the reference; for nn and hybrid the hold certificate over +-12.5 mm
(``bushenv certify``: folds, holds that do not settle stably, wrong-sign and off-band static
forces). The numbers are reported as they come: nothing here is tuned to make a model look
good or bad.

    python scripts/train_default_models.py                   # both axes, all three models
    python scripts/train_default_models.py --axes radial --models nn --out-dir /tmp/models
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from bushenv.identify import fit_model
from bushenv.machine import random_test, step_test
from bushenv.metrics import esr, max_error, max_error_ratio, rms_ratio
from bushenv.models import AXES, default_model_path
from bushenv.models import MODELS as REGISTRY
from bushenv.models.kernels import warm_up
from bushenv.reference.rubber import RubberBushing

IDENT_SEED = 0
VERIFY_SEED = 1
MODELS = tuple(n for n in REGISTRY.names() if REGISTRY[n].shipped)  # the files the package ships
# The papers' models as the seeds made them: teacher forcing (one step ahead only, seed 000
# §4.2), five past displacements and forces into one hidden layer of nine tanh units (seed 000
# §4.2, the paper whose NN departs after the 4 mm step), no certified-hold term.
# Trained once with the fixed seed below, not chosen after looking at what the attack finds.
PAPER_OPTIONS = {
    "recipe": "teacher-forcing",
    "hidden": (9,),
    "n_past_x": 5,
    "n_past_f": 5,
    "certified": "off",
    "choose": "off",
}
# The NARX models train with the certified-hold term; iteration counts end every training (no
# wall-time limit: the default), so a seed reproduces the files on any machine.
NARX_OPTIONS = {"certified": "on"}
OPTIONS = {
    "nn": NARX_OPTIONS,
    "hybrid": NARX_OPTIONS,
    "boucwen": {},
    "nn-paper": PAPER_OPTIONS,
    "hybrid-paper": PAPER_OPTIONS,
}
SETTLE_WINDOW_S = 2.0
SETTLE_TOLERANCE = 0.01


def step_behaviour(model, reference) -> dict[str, float | bool]:
    """Free response to the papers' 4 mm step held 10 s, next to the reference's."""
    rec = step_test(reference)
    x = rec.displacement
    f_ref = rec.force
    f = model.simulate(x)
    n_tail = int(round(SETTLE_WINDOW_S / model.dt))
    finite = bool(np.all(np.isfinite(f)))
    peak = float(np.max(np.abs(f))) if finite else float("inf")
    tail = f[-n_tail:]
    settles = finite and float(np.ptp(tail)) <= SETTLE_TOLERANCE * peak
    return {
        "finite": finite,
        "settles": bool(settles),
        "tail_ptp_n": float(np.ptp(tail)) if finite else float("inf"),
        "peak_n": peak,
        "final_n": float(f[-1]),
        "reference_final_n": float(f_ref[-1]),
        "reference_peak_n": float(np.max(np.abs(f_ref))),
    }


def hold_certificate(model, axis: str) -> dict | None:
    """The hold part of ``bushenv certify`` (201 holds over +-12.5 mm against the rubber)."""
    from bushenv.certify import CertifyError, certify
    from bushenv.models import get_reference

    try:
        cert = certify(model, get_reference("rubber", axis=axis, dt=model.dt))
    except CertifyError:
        return None  # not a NARX model
    s = cert.document["summary"]
    keys = (
        "passes_holds",
        "folds",
        "holds",
        "holds_settling_stably",
        "wrong_sign_holds",
        "static_off_holds",
        "max_reached_spectral_radius",
    )
    return {k: s[k] for k in keys}


def train_axis(axis: str, models: tuple[str, ...], out_dir: Path | None, seed: int) -> list[dict]:
    reference = RubberBushing.preset(axis)
    ident = random_test(reference, 1.0, seed=IDENT_SEED)
    verify = random_test(reference, 1.5, seed=VERIFY_SEED)
    print(
        f"== {axis}: identification n=1 ({len(ident.force)} samples, seed {IDENT_SEED}), "
        f"verification n=1.5 ({len(verify.force)} samples, seed {VERIFY_SEED})",
        flush=True,
    )
    rows = []
    for name in models:
        t0 = time.perf_counter()
        kind = REGISTRY[name].kind or name  # nn-paper: an nn network trained another way
        model = fit_model(
            kind, ident.displacement, ident.force, reference.dt, seed=seed, **OPTIONS[name]
        )
        seconds = time.perf_counter() - t0
        pred = model.simulate(verify.displacement)
        row = {
            "axis": axis,
            "model": name,
            "train_seconds": round(seconds, 1),
            "rms_ratio_n15": rms_ratio(verify.force, pred),
            "esr_n15": esr(verify.force, pred),
            "max_error_n15_n": max_error(verify.force, pred),
            "max_error_ratio_n15": max_error_ratio(verify.force, pred),
            "rms_ratio_n1_ident": rms_ratio(ident.force, model.simulate(ident.displacement)),
            "step": step_behaviour(model, reference),
            "certificate": hold_certificate(model, axis),
        }
        path = out_dir / f"{axis}_{name}.npz" if out_dir else default_model_path(name, axis)
        model.save(path)
        row["file"] = str(path)
        print(
            f"   {axis} {name}: {seconds:.1f} s; n=1.5 free run RMS ratio "
            f"{row['rms_ratio_n15']:.4f}, ESR {row['esr_n15']:.4f}, max error "
            f"{row['max_error_n15_n']:.1f} N ({row['max_error_ratio_n15']:.1%}); "
            f"step settles: {row['step']['settles']} (ends {row['step']['final_n']:.1f} N, "
            f"reference {row['step']['reference_final_n']:.1f} N) -> {path}",
            flush=True,
        )
        if row["certificate"] is not None:
            print(f"   {axis} {name} hold certificate: {row['certificate']}", flush=True)
        rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--axes", nargs="+", default=list(AXES), choices=AXES)
    parser.add_argument("--models", nargs="+", default=list(MODELS), choices=MODELS)
    parser.add_argument(
        "--out-dir", type=Path, default=None, help="default: the package's data/models"
    )
    parser.add_argument("--seed", type=int, default=0, help="training seed")
    parser.add_argument("--json", type=Path, default=None, help="also write the results here")
    args = parser.parse_args(argv)
    warm_up()
    rows = []
    for axis in args.axes:
        rows += train_axis(axis, tuple(args.models), args.out_dir, args.seed)
    print(
        "\naxis    model    train s  RMS ratio n=1.5  ESR     max err N  step settles  certificate"
    )
    for r in rows:
        cert = r["certificate"]
        verdict = "-" if cert is None else "passes" if cert["passes_holds"] else "FAILS"
        print(
            f"{r['axis']:7s} {r['model']:12s} {r['train_seconds']:7.1f}  "
            f"{r['rms_ratio_n15']:15.4f}  {r['esr_n15']:.4f}  {r['max_error_n15_n']:9.1f}  "
            f"{str(r['step']['settles']):12s}  {verdict}"
        )
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
