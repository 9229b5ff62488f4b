"""Corpus cases from members of the population study (studies/2026-11-training-recipes/README.md) that fail in a kind the
shipped models' cases do not show: a hold that departs, a held force of the wrong sign.

The members are kept in ``tests/regressions/models/`` (copied from a ``bushenv zoo`` run's
``models/``); each case is judged on that member and on the shipped nn, hybrid and linear
models, against the rubber, and written to ``tests/regressions/corpus/``.

    bushenv zoo --recipes teacher-forcing,free-run --models nn,hybrid --seeds 0-9 --out runs/zoo
    cd runs/zoo/models && M=../../../tests/regressions/models
    cp free-run-nn-radial-s7.npz $M/radial_nn-zoo-free-run-s7.npz
    cp teacher-forcing-nn-axial-s1.npz $M/axial_nn-zoo-teacher-forcing-s1.npz && cd -
    python studies/2026-11-training-recipes/population_cases.py
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from bushenv import excitation as ex
from bushenv.models import get_model
from bushenv.search.corpus import DEFAULT_CORPUS, make_case, model_sha, save_case, truth_reference
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.searchers import get_searcher
from bushenv.search.shrink import shrink

ROOT = Path(__file__).resolve().parents[2]
MODELS_DIR = ROOT / "tests" / "regressions" / "models"


def _models(member: str, axis: str, dt: float) -> tuple[dict, dict]:
    spec = f"../models/{member}"
    models = {spec: get_model(str(MODELS_DIR / member), axis=axis, dt=dt)}
    shas = {spec: model_sha(str(MODELS_DIR / member), axis)}
    for name in ("nn", "hybrid", "linear"):
        models[name] = get_model(name, axis=axis, dt=dt)
        shas[name] = model_sha(name, axis)
    return models, shas


def hold_departure(member: str, axis: str, searcher: str, seed: int, budget: int):
    """The first profile ``searcher`` finds on which the member's force moves in a hold
    (``self_sustained``), shrunk while that criterion still fires."""
    reference = truth_reference(axis)
    model = get_model(str(MODELS_DIR / member), axis=axis, dt=reference.dt)
    with BatchEvaluator(model, reference, "rig", axis=axis, threads=2) as ev:
        result = get_searcher(searcher).run(ev, budget, seed=seed)
        found = [c for c in result.failures if "self_sustained" in c.verdict["criteria"]]
        if not found:
            raise SystemExit(f"{member}: {searcher} found no self-sustained hold in {budget}")
        first = found[0]
        small = shrink(
            first.profile,
            ev,
            budget=200,
            still_fails=lambda row: (
                "self_sustained" in row["criteria"] and row["robustness"] < -0.1
            ),
        )
    found_by = {"searcher": searcher, "seed": seed, "model": member, "campaign_budget": budget}
    return small.profile, first.family, first.params, found_by, small.summary()


def wrong_sign_step(member: str, axis: str):
    """The papers' 4 mm step held 10 s (seed 000 §5.2), on which the member holds the wrong sign."""
    x = ex.step_hold(4e-3, 10.0, truth_reference(axis).dt, pre_s=0.5)
    return x, "step", None, {"searcher": "papers-step", "seed": 0, "model": member}, None


CASES = {
    "radial_nn-zoo-free-run-s7.npz": (
        "radial",
        lambda m, a: hold_departure(m, a, "certificate", 0, 256),
        "A member of the population study (free-run recipe, seed 7), held at rest from the "
        "start: its force drifts and then oscillates by itself, growing to about +-90 N after "
        "10 s (self_sustained at 8.7 s) -- a hold departure. Its hold certificate predicts it: "
        "at x = 0 the one fixed point has spectral radius 1.003 (unstable, oscillating). The "
        "shipped models hold.",
    ),
    "axial_nn-zoo-teacher-forcing-s1.npz": (
        "axial",
        wrong_sign_step,
        "A member of the population study (teacher forcing, the papers' recipe, seed 1): held "
        "at +4 mm it settles at a force of the wrong sign (about -335 N where the rubber holds "
        "+927 N) and stays bounded -- the papers' step, failed by the static criterion.",
    ),
}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--corpus", default=str(ROOT / DEFAULT_CORPUS))
    p.add_argument("--force", action="store_true", help="overwrite existing cases")
    args = p.parse_args(argv)
    for member, (axis, find, notes) in CASES.items():
        profile, family, params, found_by, shrunk = find(member, axis)
        reference = truth_reference(axis)
        models, shas = _models(member, axis, reference.dt)
        case = make_case(
            profile,
            env="rig",
            axis=axis,
            family=family,
            params=params,
            found_by=found_by,
            models=models,
            reference=reference,
            reference_spec="rubber",
            shas=shas,
            shrink=shrunk,
            notes=notes,
        )
        verdicts = {k: (v["diverged"], v["criterion"]) for k, v in case.expect.items()}
        if not case.expect[f"../models/{member}"]["diverged"]:
            print(f"{member}: the stored profile no longer fails {verdicts}", file=sys.stderr)
            return 1
        path = save_case(case, args.corpus, force=args.force)
        print(f"{path or case.name + ' (exists)'}: {verdicts}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
