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
}


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


RUNS = {
    "attack": attack_run,
    "attack_rl": attack_rl_run,
    "attack_road": attack_road_run,
    "reproduce": reproduce_run,
    "diagnose": diagnose_run,
    "corpus": lambda out: corpus_run(),
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
