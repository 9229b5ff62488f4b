"""``bushenv attack``: an adversarial campaign against one bushing model.

    bushenv attack --model nn --budget 256 [--axis axial] [--env rig|quartercar]
                   [--searchers random,cma,ppo,sac] [--seed S] [--out DIR] [--save]

Steps (every search has the same budget in model evaluations; RL agents are capped at
``--rl-budget`` episodes, printed in the table):

1. **target**: each searcher looks for profiles on which ``--model`` diverges;
2. **recheck**: the hybrid (``--hybrid``) and the linear control run every profile that broke
   the target (batched);
3. **hybrid**: the same searchers look for the hybrid's own worst case, same budget;
4. **control**: the same searchers against the linear Table-1 model. Divergence thresholds are
   physical constants (``divergence.py``); the control must come out clean, and if it does not,
   the table says so;
5. **shrink**: the worst failures (one per family, up to ``--max-shrink``, plus any hybrid or
   control failure) are shrunk to the simplest profile that still fails and judged on all three
   models; ``--save`` adds them to the regression corpus (``tests/regressions/corpus``).

Outputs in ``DIR`` (default ``runs/attack``): ``report.json`` (rewritten atomically after every
step, see docs/search.md for its fields), ``plots/*.png`` (worst profiles and responses),
``failures/*.npz`` (the profiles each search found), ``cases/*.json`` (the shrunk failures in
corpus format). An existing report is refused unless ``--resume`` (finish what is missing;
finished steps are kept, every step is seeded so the result is the same) or ``--force`` (start
again).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

EXAMPLE = "bushenv attack --model nn --budget 256 --searchers random,cma,ppo,sac --out runs/attack"
REPORT_FORMAT = "bushenv-attack-report"
REPORT_VERSION = 1
DEFAULT_SEARCHERS = {"rig": "random,cma,ppo,sac", "quartercar": "random,cma"}
RL_SEARCHERS = ("ppo", "sac")
MAX_SAVED_FAILURES = 256  # profiles per search written to failures/*.npz for the recheck


class CampaignError(ValueError):
    """Bad campaign arguments or an existing report without --resume/--force."""


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--model", default="nn", help="model under attack: name or .npz (default nn)")
    p.add_argument("--budget", type=int, default=256, help="model evaluations per search")
    p.add_argument(
        "--rl-budget", type=int, default=256, help="cap on episodes for ppo/sac (default 256)"
    )
    p.add_argument("--axis", default="axial", choices=("axial", "radial"))
    p.add_argument("--env", default="rig", choices=("rig", "quartercar"))
    p.add_argument(
        "--searchers",
        default=None,
        help="comma list of random,cma,ppo,sac (default: all for rig, random,cma for quartercar)",
    )
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default="runs/attack", help="output directory (default runs/attack)")
    p.add_argument("--hybrid", default="hybrid", help="the model rechecked on the failures")
    p.add_argument("--control", default="linear", help="the control that must stay clean")
    p.add_argument("--max-shrink", type=int, default=3, help="failures to shrink (default 3)")
    p.add_argument("--shrink-budget", type=int, default=200, help="evaluations per shrink")
    p.add_argument("--threads", type=int, default=None, help="evaluation threads (default: cores)")
    p.add_argument("--save", action="store_true", help="add shrunk failures to the corpus")
    p.add_argument("--corpus", default="tests/regressions/corpus", help="corpus directory")
    p.add_argument("--resume", action="store_true", help="continue an interrupted campaign")
    p.add_argument("--force", action="store_true", help="overwrite an existing report/cases")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    p.add_argument(
        "--paper-step",
        action="store_true",
        help="also judge the papers' 4 mm step held 10 s (seed 000 §5.2) and keep it as a case",
    )


# ----- small helpers ---------------------------------------------------------------------------
def write_json_atomic(path: Path, obj: Any) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "w") as fh:
            json.dump(obj, fh, indent=1, default=_json_default)
            fh.write("\n")
        os.chmod(tmp, 0o644)  # mkstemp makes 0600; these are ordinary shared files
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _json_default(o: Any) -> Any:
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def save_profiles(path: Path, profiles: list[np.ndarray], meta: list[dict]) -> None:
    """Profiles of any lengths in one npz (padded + lengths) with JSON metadata; atomic."""
    path.parent.mkdir(parents=True, exist_ok=True)
    n = len(profiles)
    T = max((p.size for p in profiles), default=1)
    arr = np.zeros((T, max(n, 1)))
    lengths = np.zeros(max(n, 1), dtype=np.int64)
    for i, p in enumerate(profiles):
        arr[: p.size, i] = p
        lengths[i] = p.size
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez_compressed(
                fh,
                profiles=arr,
                lengths=lengths,
                count=np.array(n),
                meta=np.array(json.dumps(meta, default=_json_default)),
            )
        os.chmod(tmp, 0o644)  # mkstemp makes 0600; these are ordinary shared files
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def load_profiles(path: Path) -> tuple[list[np.ndarray], list[dict]]:
    with np.load(path, allow_pickle=False) as z:
        n = int(z["count"])
        arr, lengths = z["profiles"], z["lengths"]
        meta = json.loads(str(z["meta"]))
    return [arr[: lengths[i], i].copy() for i in range(n)], meta


def _model_identity(spec: str, model, axis: str) -> dict[str, Any]:
    from bushenv.models import file_hash, model_file
    from bushenv.search.corpus import params_sha

    path = model_file(spec, axis)
    if path is not None and not path.is_file():
        path = None
    return {
        "spec": spec,
        "class": type(model).__name__,
        "file": str(path) if path else None,
        "sha256": file_hash(path) if path and path.is_file() else None,
        "params_sha256": params_sha(model),
    }


class _Throttled:
    """Progress lines at most every ``every_s`` seconds."""

    def __init__(self, log, prefix: str, every_s: float) -> None:
        self.log, self.prefix, self.every_s, self.last = log, prefix, every_s, 0.0

    def __call__(self, msg: str) -> None:
        now = time.perf_counter()
        if now - self.last > self.every_s:
            self.last = now
            self.log(self.prefix + msg)


def _near(a: np.ndarray, b: np.ndarray) -> bool:
    """Same length and within 5 % of the larger peak everywhere: one case is enough."""
    if a.size != b.size:
        return False
    peak = max(float(np.max(np.abs(a))), float(np.max(np.abs(b))), 1e-9)
    return float(np.max(np.abs(a - b))) <= 0.05 * peak


def _label(spec: str) -> str:
    return Path(spec).stem if spec.endswith(".npz") else spec


class Campaign:
    """State of one campaign; every step updates ``self.report`` and writes it atomically."""

    def __init__(self, args: argparse.Namespace, log=print) -> None:
        self.args = args
        self.log = log
        self.out = Path(args.out)
        self.report_path = self.out / "report.json"
        self.t0 = time.perf_counter()

    # ----- set-up ------------------------------------------------------------------------------
    def prepare(self) -> None:
        a = self.args
        if a.budget < 1 or a.rl_budget < 1:
            raise CampaignError(
                f"--budget and --rl-budget must be >= 1, got {a.budget}, {a.rl_budget}"
            )
        searchers = [s.strip() for s in (a.searchers or DEFAULT_SEARCHERS[a.env]).split(",")]
        known = ("random", "cma", *RL_SEARCHERS)
        bad = [s for s in searchers if s not in known]
        if bad or not searchers:
            raise CampaignError(f"--searchers: unknown {bad}; choose from {list(known)}")
        self.searchers = searchers
        if self.report_path.exists() and not (a.resume or a.force):
            raise CampaignError(
                f"{self.report_path} exists; pass --resume to continue it or --force to start again"
            )
        from bushenv.models import get_model
        from bushenv.search.corpus import params_sha, truth_reference

        self.reference = truth_reference(a.axis)
        roles = [("target", a.model), ("hybrid", a.hybrid), ("control", a.control)]
        self.models: dict[str, Any] = {}
        self.roles: dict[str, str] = {}
        for role, spec in roles:
            key = _label(spec)
            if key in self.models:  # e.g. --model hybrid: the hybrid step is the target step
                continue
            self.models[key] = get_model(spec, axis=a.axis, dt=self.reference.dt)
            self.roles[key] = role
        self.specs = {_label(spec): spec for _, spec in roles}
        self.target = _label(a.model)
        self.hybrid = _label(a.hybrid)
        self.control = _label(a.control)
        fresh = {
            "format": REPORT_FORMAT,
            "version": REPORT_VERSION,
            "arguments": {
                k: getattr(a, k)
                for k in (
                    "model",
                    "budget",
                    "rl_budget",
                    "axis",
                    "env",
                    "seed",
                    "hybrid",
                    "control",
                    "max_shrink",
                    "shrink_budget",
                )
            },
            "searchers": self.searchers,
            "reference": {
                "name": "rubber",
                "measurement": False,
                "params_sha256": params_sha(self.reference),
            },
            "models": {
                key: {
                    "role": self.roles[key],
                    **_model_identity(self.specs[key], m, a.axis),
                    "searchers": {},
                }
                for key, m in self.models.items()
            },
            "recheck": {},
            "shrunk": [],
            "corpus": [],
            "complete": False,
            "seconds": 0.0,
        }
        if a.resume and self.report_path.exists():
            try:
                old = json.loads(self.report_path.read_text(encoding="utf-8"))
            except (UnicodeDecodeError, json.JSONDecodeError) as exc:
                raise CampaignError(
                    f"{self.report_path}: corrupt or half-written report ({exc}); "
                    "use --force to start again"
                ) from None
            if not isinstance(old, dict) or old.get("format") != REPORT_FORMAT:
                raise CampaignError(f"{self.report_path}: not a bushenv attack report")
            if old.get("arguments") != fresh["arguments"] or old.get("searchers") != searchers:
                raise CampaignError(
                    f"{self.report_path} was made with other arguments "
                    f"({old.get('arguments')}, searchers {old.get('searchers')}); "
                    "use another --out or --force"
                )
            for key, entry in old.get("models", {}).items():
                if key in fresh["models"]:
                    shas = (entry.get("sha256"), fresh["models"][key]["sha256"])
                    if shas[0] != shas[1]:
                        raise CampaignError(
                            f"{self.report_path}: model {key} changed since the interrupted "
                            "run (sha256 differs); use --force"
                        )
                    fresh["models"][key]["searchers"] = entry.get("searchers", {})
            fresh["recheck"] = old.get("recheck", {})
            fresh["shrunk"] = old.get("shrunk", [])
            fresh["corpus"] = old.get("corpus", [])
            fresh["seconds"] = old.get("seconds", 0.0)
            self.log(f"resuming {self.report_path}")
        self.report = fresh
        self.seconds_before = fresh["seconds"]
        self.save()

    def save(self) -> None:
        self.report["seconds"] = round(self.seconds_before + time.perf_counter() - self.t0, 3)
        write_json_atomic(self.report_path, self.report)

    def evaluator(self, key: str):
        from bushenv.execution import local_cores
        from bushenv.search.evaluate import BatchEvaluator

        threads = self.args.threads or local_cores()
        return BatchEvaluator(
            self.models[key],
            self.reference,
            target=self.args.env,
            threads=threads,
            axis=self.args.axis,
        )

    # ----- searching ---------------------------------------------------------------------------
    def search(self, key: str) -> None:
        from bushenv.search.searchers import get_searcher

        done = self.report["models"][key]["searchers"]
        for name in self.searchers:
            if name in done:
                self.log(f"[{key}] {name}: done earlier (resumed)")
                continue
            budget = (
                min(self.args.budget, self.args.rl_budget)
                if name in RL_SEARCHERS
                else (self.args.budget)
            )
            self.log(f"[{key}] {name}: budget {budget} evaluations ...")
            progress = _Throttled(self.log, f"[{key}]   ", every_s=2.0)

            with self.evaluator(key) as ev:
                res = get_searcher(name).run(ev, budget, seed=self.args.seed, progress=progress)
            summary = res.summary()
            if res.first_failure is not None:
                summary["first_failure"] = res.first_failure.to_json()
            if res.worst is not None:
                summary["worst"] = res.worst.to_json()
            kept = res.failures[:MAX_SAVED_FAILURES]
            profiles = [c.profile for c in kept]
            meta = [c.to_json() for c in kept]
            if res.worst is not None:
                profiles.append(res.worst.profile)
                meta.append({**res.worst.to_json(), "worst": True})
            path = self.out / "failures" / f"{key}-{name}.npz"
            save_profiles(path, profiles, meta)
            summary["profiles_file"] = str(path.relative_to(self.out))
            done[name] = summary
            self.save()
            self.log(
                f"[{key}] {name}: "
                + (
                    f"DIVERGED after {summary['evaluations_to_failure']} evaluations "
                    f"({summary['seconds_to_failure']:.2f} s), {res.n_failures} failing profiles"
                    if res.diverged
                    else f"no divergence in {res.evaluations} evaluations"
                )
                + f"; worst robustness {summary['worst_robustness']:.3g} ({res.seconds:.1f} s)"
            )

    def _failures_of(self, key: str) -> tuple[list[np.ndarray], list[dict]]:
        profiles, meta = [], []
        for name, summary in self.report["models"][key]["searchers"].items():
            f = summary.get("profiles_file")
            if not f:
                continue
            ps, ms = load_profiles(self.out / f)
            for p, m in zip(ps, ms, strict=True):
                if m.get("diverged"):
                    profiles.append(p)
                    meta.append({**m, "searcher": name})
        return profiles, meta

    def recheck(self) -> None:
        """Run the hybrid and the control on every profile that broke the target."""
        if self.report["recheck"]:
            self.log("recheck: done earlier (resumed)")
            return
        profiles, meta = self._failures_of(self.target)
        out: dict[str, Any] = {"profiles": len(profiles)}
        for key in self.models:
            if key == self.target:
                continue
            entry: dict[str, Any] = {"diverged": 0, "failures": []}
            if profiles:
                with self.evaluator(key) as ev:
                    batch = ev.evaluate(profiles)
                v = batch.verdict
                entry["diverged"] = int(v.diverged.sum())
                entry["worst_robustness"] = float(np.min(v.robustness))
                entry["worst_deviation"] = float(np.max(v.worst_deviation))
                for b in np.flatnonzero(v.diverged)[:20]:
                    entry["failures"].append(
                        {
                            **v.row(int(b)),
                            "family": meta[b]["family"],
                            "searcher": meta[b]["searcher"],
                            "index": int(b),
                        }
                    )
            out[key] = entry
            self.log(
                f"recheck: {key} diverged on {entry['diverged']} of {len(profiles)} profiles "
                f"that broke {self.target}"
            )
        self.report["recheck"] = out
        self.save()

    # ----- shrinking and the corpus --------------------------------------------------------------
    def _shrink_choices(self) -> list[tuple[str, np.ndarray, dict]]:
        """Worst failure per family of the target (up to --max-shrink) + any hybrid/control."""
        picks: list[tuple[str, np.ndarray, dict]] = []
        profiles, meta = self._failures_of(self.target)
        best: dict[str, int] = {}
        for i, m in enumerate(meta):
            fam = m["family"]
            if (
                fam not in best
                or m["verdict"]["robustness"] < meta[best[fam]]["verdict"]["robustness"]
            ):
                best[fam] = i
        order = sorted(best.values(), key=lambda i: meta[i]["verdict"]["robustness"])
        picks += [(self.target, profiles[i], meta[i]) for i in order[: self.args.max_shrink]]
        for key in self.models:
            if key == self.target:
                continue
            ps, ms = self._failures_of(key)
            if ps:  # honesty: a hybrid or control failure is always shrunk and reported
                i = int(np.argmin([m["verdict"]["robustness"] for m in ms]))
                picks.append((key, ps[i], ms[i]))
            rc = self.report["recheck"].get(key, {})
            if rc.get("failures"):
                tp, tm = self._failures_of(self.target)
                j = rc["failures"][0]["index"]
                picks.append((key, tp[j], {**tm[j], "found_on": self.target}))
        return picks

    def shrink_and_save(self) -> None:
        from bushenv.search.corpus import make_case, model_sha, save_case
        from bushenv.search.shrink import shrink

        if self.report["shrunk"]:
            self.log("shrink: done earlier (resumed)")
            return
        shrunk = []
        seen: list[np.ndarray] = []
        for i, (key, profile, meta) in enumerate(self._shrink_choices()):
            with self.evaluator(key) as ev:
                try:
                    res = shrink(profile, ev, budget=self.args.shrink_budget)
                except ValueError as exc:
                    self.log(f"shrink {i}: {exc}")
                    continue
            if any(_near(res.profile, other) for other in seen):
                # two failures shrank to (nearly) the same simplest profile: keep one
                self.log(f"shrink: {key}/{meta['family']} shrank to a profile already kept")
                continue
            seen.append(res.profile)
            shas = {k: model_sha(self.specs[k], self.args.axis) for k in self.models}
            case = make_case(
                res.profile,
                env=self.args.env,
                axis=self.args.axis,
                family=meta["family"],
                params=meta.get("params"),
                found_by={
                    "searcher": meta.get("searcher"),
                    "seed": self.args.seed,
                    "model": self.specs[key],
                    "model_sha256": shas.get(key),
                    "campaign_budget": self.args.budget,
                },
                models={self.specs[k]: m for k, m in self.models.items()},
                reference=self.reference,
                shas={self.specs[k]: shas[k] for k in self.models},
                shrink=res.summary(),
            )
            path = save_case(case, self.out / "cases", force=True)
            entry = {
                "failed_model": key,
                "family": meta["family"],
                "searcher": meta.get("searcher"),
                "shrink": res.summary(),
                "verdicts": case.expect,
                "case_file": str(path.relative_to(self.out)),
                "name": case.name,
            }
            shrunk.append(entry)
            verdicts = ", ".join(
                f"{m} {'DIVERGES' if e['diverged'] else 'bounded'}" for m, e in case.expect.items()
            )
            self.log(
                f"shrink: {key}/{meta['family']} {res.original} -> {res.final} "
                f"(segments, samples, peak um) in {res.evaluations} evaluations: {verdicts}"
            )
            if self.args.save and not case.expect[self.specs[key]]["diverged"]:
                self.log(f"corpus: {case.name} not saved: {key} no longer fails once stored")
            elif self.args.save:
                saved = save_case(case, Path(self.args.corpus), force=self.args.force)
                if saved is None:
                    self.log(f"corpus: {case.name} already there (kept; --force to overwrite)")
                else:
                    self.log(f"corpus: added {saved}")
                    self.report["corpus"].append(str(saved))
        if self.args.paper_step and self.args.env == "rig":
            shrunk.append(self._paper_step(shas_fn=model_sha))
        self.report["shrunk"] = shrunk
        self.save()

    def _paper_step(self, shas_fn) -> dict[str, Any]:
        """The papers' own case: a 4 mm step held 10 s, NN said to diverge after 7.3 s."""
        from bushenv import excitation as ex
        from bushenv.search.corpus import make_case, save_case

        x = ex.step_hold(4e-3, 10.0, self.reference.dt, pre_s=0.5)
        shas = {k: shas_fn(self.specs[k], self.args.axis) for k in self.models}
        case = make_case(
            x,
            env="rig",
            axis=self.args.axis,
            family="step",
            params={"size_m": 4e-3, "hold_s": 10.0, "pre_s": 0.5, "rise_s": 0.0},
            found_by={
                "searcher": "paper (seed 000 §5.2)",
                "seed": None,
                "model": self.specs[self.target],
                "model_sha256": shas[self.target],
            },
            models={self.specs[k]: m for k, m in self.models.items()},
            reference=self.reference,
            shas={self.specs[k]: shas[k] for k in self.models},
            notes="seed 000 §5.2: the papers' NN diverges after 7.3 s of this step; the "
            "verdicts recorded here are what the shipped models do",
        )
        path = save_case(case, self.out / "cases", force=True)
        verdicts = ", ".join(
            f"{m} {'DIVERGES' if e['diverged'] else 'bounded'}" for m, e in case.expect.items()
        )
        self.log(f"paper step (4 mm, 10 s hold): {verdicts}")
        if self.args.save:
            saved = save_case(case, Path(self.args.corpus), force=self.args.force)
            if saved is not None:
                self.log(f"corpus: added {saved}")
                self.report["corpus"].append(str(saved))
        return {
            "failed_model": None,
            "family": "step",
            "searcher": "paper",
            "shrink": None,
            "verdicts": case.expect,
            "case_file": str(path.relative_to(self.out)),
            "name": case.name,
        }

    # ----- plots and table ------------------------------------------------------------------
    def plots(self) -> None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        plot_dir = self.out / "plots"
        plot_dir.mkdir(parents=True, exist_ok=True)
        dt = self.reference.dt
        for key in self.models:
            rows = []
            for name, summary in self.report["models"][key]["searchers"].items():
                f = summary.get("profiles_file")
                if f:
                    ps, ms = load_profiles(self.out / f)
                    worst = [(p, m) for p, m in zip(ps, ms, strict=True) if m.get("worst")]
                    if worst:
                        rows.append((name, *worst[0]))
            if not rows:
                continue
            fig, axes = plt.subplots(len(rows), 2, figsize=(12, 2.6 * len(rows)), squeeze=False)
            with self.evaluator(key) as ev:
                batch = ev.evaluate([p for _, p, _ in rows])
            for r, (name, p, m) in enumerate(rows):
                n = p.size
                t = np.arange(n) * dt
                ax = axes[r, 0]
                xs = batch.x[:n, r]
                ax.plot(t, xs * 1e3, "k", lw=0.8)
                ax.set_ylabel("deflection [mm]")
                v = m["verdict"]
                ax.set_title(
                    f"{key} / {name}: worst {m['family']}, robustness {v['robustness']:.3g}"
                    + (
                        f", {v['first_criterion']} at {v['first_time_s']:.2f} s"
                        if v["diverged"]
                        else ", bounded"
                    ),
                    fontsize=9,
                )
                ax = axes[r, 1]
                ax.plot(t, batch.f_ref[:n, r], "b", lw=0.8, label="reference (rubber)")
                ax.plot(t, batch.f_model[:n, r], "r", lw=0.8, label=key)
                if v.get("first_time_s") is not None:
                    for a_ in axes[r]:
                        a_.axvline(v["first_time_s"], color="m", ls="--", lw=0.8)
                ax.set_ylabel("force [N]")
                ax.legend(fontsize=7, loc="upper right")
            for a_ in axes[-1]:
                a_.set_xlabel("time [s]")
            fig.tight_layout()
            fig.savefig(plot_dir / f"worst-{key}.png", dpi=90)
            plt.close(fig)
        for i, entry in enumerate(self.report["shrunk"]):
            from bushenv.search.corpus import load_case

            case = load_case(self.out / entry["case_file"])
            p = case.profile
            t = np.arange(p.size) * dt
            fig, axes = plt.subplots(2, 1, figsize=(9, 5), sharex=True)
            axes[0].plot(t, p * (1e3 if self.args.env == "rig" else 1e3), "k")
            axes[0].set_ylabel("deflection [mm]" if self.args.env == "rig" else "road [mm]")
            axes[0].set_title(f"shrunk failure {case.name}", fontsize=9)
            ref_done = False
            for key in self.models:
                with self.evaluator(key) as ev:
                    b = ev.evaluate([p])
                if not ref_done:
                    axes[1].plot(t, b.f_ref[:, 0], "b", lw=1.0, label="reference")
                    ref_done = True
                e = case.expect[self.specs[key]]
                axes[1].plot(
                    t,
                    b.f_model[:, 0],
                    lw=0.9,
                    label=f"{key} ({'diverges' if e['diverged'] else 'bounded'})",
                )
            axes[1].set_ylabel("force [N]")
            axes[1].set_xlabel("time [s]")
            axes[1].legend(fontsize=8)
            fig.tight_layout()
            fig.savefig(plot_dir / f"shrunk-{i}.png", dpi=90)
            plt.close(fig)

    def table(self) -> str:
        head = (
            f"{'model':<10} {'role':<8} {'searcher':<8} {'evals':>6} {'diverged':>8} "
            f"{'evals->fail':>11} {'s->fail':>8} {'worst dev':>9} {'robustness':>10} "
            f"{'failing family (criterion)'}"
        )
        lines = [head, "-" * len(head)]
        for key, entry in self.report["models"].items():
            for name, s in entry["searchers"].items():
                ff = s.get("first_failure") or {}
                fam = (
                    f"{ff.get('family')} ({ff.get('verdict', {}).get('first_criterion')})"
                    if s["diverged"]
                    else "-"
                )
                wd = s.get("worst_deviation")
                stf = f"{s['seconds_to_failure']:.2f}" if s["diverged"] else "-"
                wds = f"{wd:.3g}" if wd is not None else "-"
                lines.append(
                    f"{key:<10} {entry['role']:<8} {name:<8} {s['evaluations']:>6} "
                    f"{'YES' if s['diverged'] else 'no':>8} "
                    f"{s['evaluations_to_failure'] or '-':>11} "
                    f"{stf:>8} "
                    f"{wds:>9} "
                    f"{s['worst_robustness']:>10.3g} {fam}"
                )
        rc = self.report.get("recheck", {})
        if rc:
            lines.append("")
            lines.append(
                f"recheck on the {rc.get('profiles', 0)} profiles that broke {self.target}:"
            )
            for key, e in rc.items():
                if key == "profiles":
                    continue
                lines.append(f"  {key:<10} diverged on {e['diverged']}")
        if self.report.get("shrunk"):
            lines.append("")
            lines.append("shrunk failures (segments, samples, peak um) and verdicts:")
            for e in self.report["shrunk"]:
                if e["shrink"] is None:
                    v = ", ".join(
                        f"{m}: {'DIVERGES' if x['diverged'] else 'bounded'}"
                        for m, x in e["verdicts"].items()
                    )
                    lines.append(f"  the papers' 4 mm step held 10 s: {v}")
                    continue
                fin = e["shrink"]["final"]
                v = ", ".join(
                    f"{m}: {'DIVERGES' if x['diverged'] else 'bounded'}"
                    for m, x in e["verdicts"].items()
                )
                lines.append(
                    f"  {e['failed_model']}/{e['family']:<11} -> {fin['segments']} seg, "
                    f"{fin['samples']} samples, {fin['peak_um'] / 1e3:.2f} mm peak; {v}"
                )
        return "\n".join(lines)

    def run(self) -> int:
        self.prepare()
        a = self.args
        self.log(
            f"attack: {a.model} ({a.axis}, {a.env}), searchers {','.join(self.searchers)}, "
            f"budget {a.budget} (RL {min(a.budget, a.rl_budget)} episodes), seed {a.seed} "
            f"-> {self.out}"
        )
        for key in [self.target]:
            self.search(key)
        self.recheck()
        for key in self.models:
            if key != self.target:
                self.search(key)
        self.shrink_and_save()
        if not a.no_plots:
            self.plots()
        self.report["complete"] = True
        self.save()
        self.log("")
        self.log(self.table())
        self.log(f"\nreport: {self.report_path}  ({self.report['seconds']:.1f} s in total)")
        control = self.report["models"].get(self.control, {}).get("searchers", {})
        if any(s["diverged"] for s in control.values()):
            self.log(
                f"WARNING: the control ({self.control}) was flagged: the divergence criteria or "
                "the coupling are at fault, not only the model under attack"
            )
        return 0


def run(args: argparse.Namespace) -> int:
    import torch

    torch.set_num_threads(1)
    from bushenv.cli import CliError

    def log(msg: str) -> None:
        print(msg, flush=True)

    try:
        return Campaign(args, log=log).run()
    except CampaignError as exc:
        raise CliError(str(exc)) from None


if __name__ == "__main__":  # pragma: no cover
    from bushenv.cli import main

    sys.exit(main(["attack", *sys.argv[1:]]))
