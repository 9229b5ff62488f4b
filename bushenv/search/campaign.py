"""An adversarial campaign against one bushing model (the library behind ``bushenv attack``).

Steps (every search has the same budget in model evaluations; RL agents are capped at
``rl_budget`` episodes):

1. **target**: each searcher looks for profiles on which the model diverges;
2. **recheck**: the hybrid and the linear control run every profile that broke the target;
3. **hybrid**, 4. **control**: the same searchers against them, same budget. Divergence
   thresholds are physical constants (``bushenv/divergence.py``); the control must come out
   clean, and if it does not, the report says so;
5. **shrink**: the worst failures are shrunk to the simplest profile that still fails and kept
   as regression cases (``campaign_cases.py``).

``report.json`` in the output folder is rewritten atomically after every step, so an
interrupted campaign resumes where it stopped (``resume=True``); its layout is in
``campaign_report.py`` and docs/search.md.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.errors import BadInput
from bushenv.execution import local_cores
from bushenv.judge import ScaleFlags, build_judge
from bushenv.models import get_model
from bushenv.persist import load_profiles, save_profiles, write_json, write_text
from bushenv.progress import Progress
from bushenv.scales import stiffness_mismatch
from bushenv.search.campaign_holds import NAME as HOLD_STAGE
from bushenv.search.campaign_holds import CertificateHolds, listed_holds
from bushenv.search.campaign_models import (
    FITTED_CONTROL,
    card_displacements,
    fitted_linear,
    roles,
)
from bushenv.search.campaign_report import fresh_report, report_markdown, resumed_report
from bushenv.search.corpus import DEFAULT_CORPUS
from bushenv.search.evaluate import BatchEvaluator
from bushenv.search.searchers import SEARCHERS, get_searcher
from bushenv.search.targets import TARGETS, Target

MAX_SAVED_FAILURES = 256  # profiles per search written to failures/*.npz for the recheck


class CampaignError(BadInput):
    """Bad campaign settings or an existing report without resume/force."""


@dataclass
class CampaignConfig:
    """Everything a campaign is told; ``bushenv attack`` translates its arguments into this."""

    model: str = "nn-paper"  # name or model file under attack (default: the papers' NN)
    budget: int = 256  # model evaluations per search
    rl_budget: int = 256  # cap on episodes for RL searchers
    axis: str = "axial"
    target: str = "rig"  # a TARGETS name
    searchers: tuple[str, ...] | None = None  # default: the target's
    seed: int = 0
    out: Path = Path("runs/attack")
    reference: str | None = None  # name, file or "none"; None: rubber for a registered model
    hybrid: str | None = None  # rechecked and attacked; None: the shipped one for the rubber
    control: str | None = None  # must stay clean; None: see ``Campaign.controls``
    stroke_mm: float | None = None  # the bushing's limits, beyond what the reference gives
    max_velocity_m_per_s: float | None = None
    force_floor_n: float | None = None
    force_scale_n: float | None = None  # typical peak force, for judging without a reference
    max_shrink: int = 3
    shrink_budget: int = 200
    threads: int | None = None  # evaluation threads (default: the cores)
    save: bool = False  # add shrunk failures to the corpus
    corpus: Path = field(default_factory=lambda: DEFAULT_CORPUS)
    resume: bool = False
    force: bool = False
    plots: bool = True
    paper_step: bool = False  # also the papers' 4 mm step held 10 s
    trust_reference: bool = False  # judge with a reference that failed its vetting

    def checked(self) -> CampaignConfig:
        """The config with its searchers resolved; raises ``CampaignError`` on bad values."""
        if self.budget < 1 or self.rl_budget < 1:
            raise CampaignError(
                f"--budget and --rl-budget must be >= 1, got {self.budget}, {self.rl_budget}"
            )
        target = TARGETS[self.target]
        names = tuple(self.searchers or target.default_searchers)
        bad = [s for s in names if s not in SEARCHERS]
        if bad or not names:
            raise CampaignError(f"--searchers: unknown {bad}; known names: {SEARCHERS.names()}")
        self.searchers = names
        self.out = Path(self.out)
        self.corpus = Path(self.corpus)
        return self

    def arguments(self) -> dict[str, Any]:
        """The settings a resumed campaign must share with the one it continues."""
        return {
            "model": self.model,
            "budget": self.budget,
            "rl_budget": self.rl_budget,
            "axis": self.axis,
            "env": self.target,
            "seed": self.seed,
            "reference": self.reference,
            "hybrid": self.hybrid,
            "control": self.control,
            "max_shrink": self.max_shrink,
            "shrink_budget": self.shrink_budget,
            "trust_reference": self.trust_reference,
        }


def label(spec: str) -> str:
    """The key a model goes by in the report: a name, or a model file's stem."""
    return Path(spec).stem if spec.endswith((".npz", ".fmu")) else spec


class Campaign:
    """State of one campaign; every step updates ``self.report`` and writes it atomically."""

    def __init__(self, config: CampaignConfig, progress: Progress | None = None) -> None:
        """Resolves everything once, here: the judge (vetted), the models and their roles.
        Refuses an existing report unless ``resume`` or ``force``."""
        c = self.config = config.checked()
        self.progress = progress or Progress(quiet=True)
        self.out = c.out
        self.report_path = self.out / "report.json"
        self.t0 = time.perf_counter()
        self.target: Target = TARGETS[c.target]
        if self.report_path.exists() and not (c.resume or c.force):
            raise CampaignError(
                f"{self.report_path} exists; pass --resume to continue it or --force to start again"
            )
        target_model = get_model(c.model, axis=c.axis)
        self.dt = target_model.dt
        self.judge = build_judge(
            c.model,
            c.reference,
            axis=c.axis,
            dt=self.dt,
            target=self.target,
            flags=ScaleFlags(c.stroke_mm, c.max_velocity_m_per_s, c.force_floor_n, c.force_scale_n),
            trust_reference=c.trust_reference,
            model_object=target_model,
        )
        self.reference_spec = self.judge.reference_spec
        self.reference = self.judge.reference
        self.scales = self.judge.scales
        self.static = self.judge.static
        self.notes: list[str] = self._judge_notes()
        self.models: dict[str, Any] = {}
        self.roles: dict[str, str] = {}
        self.specs: dict[str, str] = {}
        keys = self._models()
        self.target_key: str = keys["target"]
        self.hybrid_key: str | None = keys.get("hybrid")
        self.control_key: str | None = keys.get("control")
        self.report: dict[str, Any] = {}
        self.seconds_before = 0.0

    def _judge_notes(self) -> list[str]:
        notes = []
        if self.judge.vetting is not None:
            self.progress.say(f"reference {self.reference_spec}: vetted")
            for line in self.judge.vetting.lines():
                self.progress.say(f"  {line}")
        if self.reference is not None and not self.static and self.target.judges_static:
            notes.append(
                "static not judged: the reference's model card shows no quasi-static content "
                "in its training records (no hold of 1 s, under 1 % of the displacement power "
                "at or below 1 Hz), so its held force is an extrapolation"
            )
        if self.judge.trusted_by_flag:
            notes.append(
                f"UNVETTED REFERENCE: {self.reference_spec} failed its vetting "
                f"({self.judge.vetting.summary()}); --trust-reference judged with it anyway, "
                "so every verdict below may be the reference's fault"
            )
        return notes

    # ----- set-up ------------------------------------------------------------------------------
    def prepare(self) -> None:
        """The report: fresh, or what an interrupted run finished (``resume``); written."""
        fresh = fresh_report(self)
        if self.config.resume and self.report_path.exists():
            fresh = resumed_report(self.report_path, fresh)
            self.progress.say(f"resuming {self.report_path}")
        self.report = fresh
        self.seconds_before = fresh["seconds"]
        self.progress.total = self._work_units()
        for note in self.notes:
            self.progress.say(f"note: {note}")
        self.save()

    def _models(self) -> dict[str, str]:
        """The target, the hybrid, the control and the models rechecked beside them, each
        with its role (see ``roles``), into ``models``, ``roles`` and ``specs``; the key of
        each role."""
        keys = {}
        for role, spec in roles(self.config, self.judge, self.notes):
            key = label(spec)
            keys[role] = key
            if key in self.models:  # e.g. --model hybrid: the hybrid step is the target step
                continue
            self.models[key], spec = self._resolve(spec)
            self.roles[key], self.specs[key] = role, spec
            if self.static:  # static stiffness means something only where static is known
                warning = stiffness_mismatch(self.models[key], self.reference)
                if warning:
                    self.notes.append(f"{key}: {warning}")
        return keys

    def _resolve(self, spec: str):
        """The model ``spec`` names, and the spec to record (a fitted control's saved file)."""
        c = self.config
        if spec == FITTED_CONTROL:
            records = card_displacements(self.reference_spec)
            model = fitted_linear(self.reference, self.scales, records)
            return model, str(model.save(self.out / "models" / "control-linear.npz"))
        return get_model(spec, axis=c.axis, dt=self.dt), spec

    def save(self) -> None:
        self.report["seconds"] = round(self.seconds_before + time.perf_counter() - self.t0, 3)
        write_json(self.report_path, self.report)

    def evaluator(self, key: str) -> BatchEvaluator:
        return BatchEvaluator(
            self.models[key],
            self.reference,
            target=self.target,
            threads=self.config.threads or local_cores(),
            axis=self.config.axis,
            scales=self.scales,
            static=self.static,
        )

    # ----- progress accounting -----------------------------------------------------------------
    def budget_of(self, searcher: str) -> int:
        c = self.config
        return min(c.budget, c.rl_budget) if SEARCHERS[searcher].episodes else c.budget

    def _work_units(self) -> float:
        """Work ahead in evaluation-equivalents (an RL episode costs ``cost`` evaluations)."""
        per_model = sum(self.budget_of(s) * SEARCHERS[s].cost for s in self.config.searchers)
        shrinks = (self.config.max_shrink + 2) * self.config.shrink_budget
        searched = [k for k in self.models if self.roles[k] != "also"]
        return len(searched) * per_model + shrinks

    # ----- searching ---------------------------------------------------------------------------
    def search(self, key: str) -> None:
        done = self.report["models"][key]["searchers"]
        for name in self.config.searchers:
            if name in done:
                self.progress.say(f"[{key}] {name}: done earlier (resumed)")
                self.progress.done += self.budget_of(name) * SEARCHERS[name].cost
                continue
            done[name] = self._search_one(key, name)
            self.save()

    def hold_stage(self) -> None:
        """Simulate every hold the target's certificate lists as failing (``campaign_holds``)."""
        done = self.report["models"][self.target_key]["searchers"]
        if HOLD_STAGE in done:
            self.progress.say(f"[{self.target_key}] {HOLD_STAGE}: done earlier (resumed)")
            return
        model = self.models[self.target_key]
        holds = listed_holds(model, self.reference, self.scales.stroke_m)
        if holds is None:
            self.report["hold_stage"] = {"run": False, "why": "not a NARX network (no certificate)"}
            return
        stage = CertificateHolds(holds)
        if not holds:
            self.report["hold_stage"] = {"run": True, "listed": 0, "confirmed": 0, "holds": []}
            self.progress.say(f"[{self.target_key}] {HOLD_STAGE}: the certificate lists none")
            return
        done[HOLD_STAGE] = self._search_one(self.target_key, HOLD_STAGE, stage, len(holds))
        self.report["hold_stage"] = {
            "run": True,
            "listed": len(holds),
            "confirmed": sum(v["confirmed"] for v in stage.verdicts),
            "holds": stage.verdicts,
        }
        self.save()

    def _search_one(
        self, key: str, name: str, searcher: Any = None, budget: int | None = None
    ) -> dict[str, Any]:
        budget = self.budget_of(name) if budget is None else budget
        cost = SEARCHERS[name].cost if searcher is None else 1.0
        searcher = searcher or get_searcher(name)
        self.progress.say(f"[{key}] {name}: budget {budget} evaluations ...")
        start = self.progress.done
        with self.evaluator(key) as ev:

            def report(msg: str) -> None:
                self.progress.update(start + cost * ev.n_evaluations, f"[{key}]   {msg}")

            res = searcher.run(ev, max(1, budget), seed=self.config.seed, progress=report)
        self.progress.done = start + cost * budget
        summary = res.summary()
        if res.first_failure is not None:
            summary["first_failure"] = res.first_failure.to_json()
            summary["first_failure"]["reference_in_envelope"] = self.judge.in_envelope(
                res.first_failure.profile, self.dt
            )
        outside = [self.judge.in_envelope(c.profile, self.dt) is False for c in res.failures]
        summary["failures_reference_outside_envelope"] = int(sum(outside))
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
        outcome = (
            f"DIVERGED after {summary['evaluations_to_failure']} evaluations "
            f"({summary['seconds_to_failure']:.2f} s), {res.n_failures} failing profiles"
            if res.diverged
            else f"no divergence in {res.evaluations} evaluations"
        )
        self.progress.say(
            f"[{key}] {name}: {outcome}; worst robustness {summary['worst_robustness']:.3g} "
            f"({res.seconds:.1f} s)"
        )
        return summary

    def failures_of(self, key: str) -> tuple[list[np.ndarray], list[dict]]:
        """Every failing profile the searches against ``key`` kept, with its metadata."""
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
            self.progress.say("recheck: done earlier (resumed)")
            return
        profiles, meta = self.failures_of(self.target_key)
        out: dict[str, Any] = {"profiles": len(profiles)}
        for key in self.models:
            if key == self.target_key:
                continue
            out[key] = self._recheck_one(key, profiles, meta)
            self.progress.say(
                f"recheck: {key} diverged on {out[key]['diverged']} of {len(profiles)} profiles "
                f"that broke {self.target_key}"
            )
        self.report["recheck"] = out
        self.save()

    def _recheck_one(self, key: str, profiles: list, meta: list[dict]) -> dict[str, Any]:
        entry: dict[str, Any] = {"diverged": 0, "failures": []}
        if not profiles:
            return entry
        with self.evaluator(key) as ev:
            v = ev.evaluate(profiles).verdict
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
        return entry

    # ----- the whole campaign ------------------------------------------------------------------
    def run(self) -> dict[str, Any]:
        """Every step (skipping what a resumed report holds); returns the final report."""
        from bushenv.search.campaign_cases import shrink_and_save
        from bushenv.search.campaign_plots import plot_campaign

        self.prepare()
        c = self.config
        self.progress.say(
            f"attack: {c.model} ({c.axis}, {c.target}), searchers {','.join(c.searchers)}, "
            f"budget {c.budget} (RL {min(c.budget, c.rl_budget)} episodes), seed {c.seed} "
            f"-> {self.out}"
        )
        self.search(self.target_key)
        self.hold_stage()
        self.recheck()
        for key in self.models:
            if self.roles[key] in ("hybrid", "control"):  # "also": rechecked only
                self.search(key)
        shrink_and_save(self)
        plots = plot_campaign(self) if c.plots else []
        self.report["complete"] = True
        self.save()
        write_text(self.out / "report.md", report_markdown(self.report, self.target_key, plots))
        return self.report

    def criteria(self) -> dict[str, Any]:
        """Which criteria the verdicts used, and why some did not run (the judge's)."""
        why = self.judge.why
        if self.reference is not None:
            why = f"{why} {self.reference_spec!r}"
        return {"run": list(self.judge.criteria), "why": why}

    def control_flagged(self) -> bool:
        control = self.report["models"].get(self.control_key, {}).get("searchers", {})
        return any(s["diverged"] for s in control.values())
