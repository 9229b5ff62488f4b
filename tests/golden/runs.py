"""Golden runs: small, seeded versions of the project's main outputs, with timings removed.

Recorded once before the architecture refactor (``python -m tests.golden.runs --write``) and
compared by ``tests/golden/test_golden.py`` ever since: the refactor must not change what
``bushenv attack``, ``bushenv reproduce``, ``bushenv diagnose`` and the corpus replay say.
Where behaviour changes on purpose later, rerun ``--write`` and say why in the commit.

Each golden names the registry entries it was recorded on (models, effects, searchers), so
registering a new one changes no golden file.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

GOLDEN = Path(__file__).parent
# Keys whose values are wall-clock times or machine paths: never part of the behaviour.
VOLATILE = {
    "seconds",
    "seconds_to_failure",
    "identification_s",
    "verification_s",
    "file",
    "case_file",
    "profiles_file",
    "elapsed_s",
    "time_s",
    "files",
    "backbone wall_time_s",
}


def relative(obj: Any, out: Path) -> Any:
    """``obj`` with the run's temporary folder written as ``<out>`` in every string (keys
    too: a case's verdicts are keyed by the model's file)."""
    if isinstance(obj, dict):
        return {relative(k, out): relative(v, out) for k, v in obj.items()}
    if isinstance(obj, list):
        return [relative(v, out) for v in obj]
    return obj.replace(str(out), "<out>") if isinstance(obj, str) else obj


# The entries the goldens were recorded on; registering another must not change them.
ATTACK_SEARCHERS = "random,cma"
RL_SEARCHERS = "ppo,sac"
REPRODUCE_MODELS = ("linear", "nn", "hybrid", "boucwen")
DIAGNOSE_EFFECTS = ("relaxation", "friction", "hardening", "thermal", "delay", "inertia")


def strip(obj: Any) -> Any:
    """``obj`` without volatile keys (timings, paths), recursively."""
    if isinstance(obj, dict):
        return {k: strip(v) for k, v in obj.items() if k not in VOLATILE}
    if isinstance(obj, list):
        return [strip(v) for v in obj]
    return obj


def _attack(out: Path, name: str, extra: list[str]) -> dict[str, Any]:
    from bushenv.cli import main

    args = ["attack", "--model", "nn", "--threads", "1", "--no-plots", "--out", str(out / name)]
    code = main(args + extra)
    if code != 0:
        raise RuntimeError(f"attack exited {code}")
    report = json.loads((out / name / "report.json").read_text())
    for entry in report["models"].values():
        entry.pop("sha256", None)  # the shipped file's hash is checked by the corpus tests
    return strip(report)


def attack_run(out: Path) -> dict[str, Any]:
    """A short default-like attack: random and CMA-ES on the NN, the hybrid and the control."""
    extra = ["--budget", "48", "--searchers", ATTACK_SEARCHERS, "--max-shrink", "1"]
    return _attack(out, "attack", extra + ["--shrink-budget", "40"])


def attack_rl_run(out: Path) -> dict[str, Any]:
    """PPO and SAC through the vector env, a few episodes each."""
    extra = ["--budget", "12", "--rl-budget", "12", "--searchers", RL_SEARCHERS]
    return _attack(out, "attack_rl", extra + ["--max-shrink", "1", "--shrink-budget", "20"])


def attack_road_run(out: Path) -> dict[str, Any]:
    """Road searches through the batched quarter car."""
    extra = ["--env", "quartercar", "--budget", "16", "--searchers", ATTACK_SEARCHERS]
    return _attack(out, "attack_road", extra + ["--max-shrink", "1", "--shrink-budget", "20"])


def reproduce_run(out: Path) -> dict[str, Any]:
    """``bushenv reproduce`` on the shipped models (radial), short records."""
    from bushenv.progress import Progress
    from bushenv.reproduce import reproduce

    (out / "reproduce").mkdir(parents=True)
    reproduce(
        out / "reproduce",
        ["radial"],
        seed=0,
        ident_s=6.44,
        verif_s=6.44,
        shipped=True,
        progress=Progress(quiet=True),
        models=REPRODUCE_MODELS,
    )
    return strip(json.loads((out / "reproduce" / "report.json").read_text()))


def diagnose_run(out: Path) -> dict[str, Any]:
    """``bushenv diagnose`` (linear baseline) on two measured records of the reference rubber."""
    from bushenv.cli import main
    from bushenv.machine import random_test
    from bushenv.records import save_csv
    from bushenv.reference.rubber import RubberBushing

    paths = []
    for seed, name in ((1, "train"), (2, "test")):
        rec = random_test(RubberBushing.preset("axial", seed=seed), 1.0, duration_s=20.0, seed=seed)
        paths.append(str(save_csv(rec, out / f"{name}.csv")))
    effects = ",".join(DIAGNOSE_EFFECTS)
    code = main(
        ["diagnose", *paths, "--effects", effects, "--out", str(out / "diagnose"), "--quiet"]
    )
    if code != 0:
        raise RuntimeError(f"diagnose exited {code}")
    return strip(json.loads((out / "diagnose" / "report.json").read_text()))


def corpus_run() -> dict[str, Any]:
    """Every corpus case replayed: each model's verdict row."""
    from bushenv.search.corpus import case_files, load_case, replay

    corpus = GOLDEN.parent / "regressions" / "corpus"
    rows = {}
    for path in case_files(corpus):
        case = load_case(path)
        rows[case.name] = {r.model: r.row for r in replay(case)}
    return rows


# The three-axis side, recorded before it became a dimension of the one-axis code: the same
# commands must say the same on the same records.
PLANAR_NET = ["--teacher-steps", "40", "--free-run-steps", "20"]


def _planar_records(out: Path) -> list[str]:
    from bushenv.cli import main

    code = main(["measure", "--axes", "3", "--programme", "random", "--duration", "8",
                 "--out", str(out / "rec3"), "--quiet", "--force"])  # fmt: skip
    if code != 0:
        raise RuntimeError(f"measure exited {code}")
    return _record_paths(out)


def _record_paths(out: Path) -> list[str]:
    return [
        str(out / "rec3" / f"random_{k}_n1_8s_seed0.csv") for k in ("independent", "correlated")
    ]


def _planar_fit(out: Path, model: str, extra: list[str]) -> dict[str, Any]:
    from bushenv.cli import main
    from bushenv.identify.card import card_paths

    train, held = _record_paths(out) if (out / "rec3").exists() else _planar_records(out)
    path = out / f"{model}3.npz"
    code = main(["fit", train, "--validate", held, "--model", model, "--out", str(path),
                 "--no-plots", "--quiet", "--force", *extra])  # fmt: skip
    if code != 0:
        raise RuntimeError(f"fit exited {code}")
    card = json.loads(card_paths(path)[0].read_text())
    for key in ("model_sha256", "params_sha256", "created", "bushenv_version"):
        card.pop(key, None)
    for rec in card.get("records", []):
        rec.pop("sha256", None)
    card.get("source", {}).pop("wall_time_s", None)
    return relative(strip(card), out)


def planar_fit_run(out: Path) -> dict[str, Any]:
    """``bushenv fit`` on 3-axis records: linear, a short MIMO network, a short hybrid-bw."""
    return {
        "linear": _planar_fit(out, "linear", []),
        "nn": _planar_fit(out, "nn", PLANAR_NET),
        # the form recorded (hybrid-bw's default is qlv since studies/2026-11-combined-programme)
        "hybrid-bw": _planar_fit(
            out, "hybrid-bw", ["--evaluations", "12", "--relaxation-form", "constant", *PLANAR_NET]
        ),
    }


def planar_attack_run(out: Path) -> dict[str, Any]:
    """``bushenv attack --env rig3`` on a fitted network judged by a fitted hybrid-bw."""
    from bushenv.cli import main

    planar_fit_run(out)
    args = ["attack", "--env", "rig3", "--model", str(out / "nn3.npz"), "--reference",
            str(out / "hybrid-bw3.npz"), "--trust-reference", "--budget", "16", "--max-shrink",
            "1", "--shrink-budget", "20", "--threads", "1", "--no-plots", "--quiet", "--force",
            "--out", str(out / "att3")]  # fmt: skip
    if main(args) != 0:
        raise RuntimeError("attack --env rig3 failed")
    report = json.loads((out / "att3" / "report.json").read_text())
    for entry in report.get("models", {}).values():
        if isinstance(entry, dict):
            entry.pop("sha256", None)
    return relative(strip(report), out)


def planar_certificate_run(out: Path) -> dict[str, Any]:
    """A three-axis network's holds over its range and the linear fit's passivity matrix."""
    from bushenv.certify.passivity import passivity
    from bushenv.certify.range_holds import range_holds
    from bushenv.models import load_model

    planar_fit_run(out)
    nn = load_model(out / "nn3.npz")
    holds = range_holds(nn, np.array([0.004, 0.004, 0.05]))
    holds.pop("seconds", None)
    lin = load_model(out / "linear3.npz")
    rep = passivity(lin, np.zeros(3), np.array([1.0, 5.0, 20.0]))
    rows = {k: (v if isinstance(v, str) else np.asarray(v).tolist()) for k, v in vars(rep).items()}
    return strip({"holds": holds, "passivity": rows})


def planar_reproduce_run(out: Path) -> dict[str, Any]:
    """``bushenv reproduce --planar only``'s table, the linear model on short records."""
    from bushenv.models.base import PAPER_DT
    from bushenv.reproduce import coupled_table

    return strip(coupled_table(0, 6.0, 6.0, PAPER_DT, models=("linear",)))


RUNS = {
    "attack": attack_run,
    "attack_rl": attack_rl_run,
    "attack_road": attack_road_run,
    "reproduce": reproduce_run,
    "diagnose": diagnose_run,
    "corpus": lambda out: corpus_run(),
    "planar_fit": planar_fit_run,
    "planar_attack": planar_attack_run,
    "planar_certificate": planar_certificate_run,
    "planar_reproduce": planar_reproduce_run,
}


def _plain(o: Any) -> Any:
    if isinstance(o, np.generic):
        return o.item()
    raise TypeError(type(o))


def normalised(obj: Any) -> Any:
    """JSON round trip: tuples become lists, numpy scalars plain numbers."""
    return json.loads(json.dumps(obj, default=_plain))


def golden_path(name: str) -> Path:
    return GOLDEN / f"{name}.json"


def main(argv: list[str]) -> int:
    names = [a for a in argv if not a.startswith("-")] or list(RUNS)
    if "--write" not in argv:
        print("usage: python -m tests.golden.runs --write [attack reproduce diagnose corpus]")
        return 2
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            result = normalised(RUNS[name](Path(tmp)))
            golden_path(name).write_text(json.dumps(result, indent=1, sort_keys=True) + "\n")
            print(f"wrote {golden_path(name)}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
