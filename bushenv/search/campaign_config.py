"""What an attack is told: ``CampaignConfig`` (``bushenv attack`` translates its arguments into
this); every stage of ``campaign.py`` takes it as it is, frozen."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from bushenv.errors import BadInput
from bushenv.judge import ScaleFlags
from bushenv.search.case_file import DEFAULT_CORPUS
from bushenv.search.searchers import SEARCHERS
from bushenv.search.targets import TARGETS


class CampaignError(BadInput):
    """Bad campaign settings or an existing report without resume/force."""


@dataclass(frozen=True)
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
    control: str | None = None  # must stay clean; None: see ``campaign_models.roles``
    stroke_mm: float | None = None  # the bushing's limits, beyond what the reference gives
    max_velocity_m_per_s: float | None = None
    rotation_mrad: float | None = None  # three-axis targets: the rotation's range, +-mrad
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
        return replace(self, searchers=names, out=Path(self.out), corpus=Path(self.corpus))

    @property
    def flags(self) -> ScaleFlags:
        """The bushing's limits given on the command line."""
        return ScaleFlags(
            self.stroke_mm,
            self.max_velocity_m_per_s,
            self.force_floor_n,
            self.force_scale_n,
            self.rotation_mrad,
        )

    def budget_of(self, searcher: str) -> int:
        """Evaluations one search by ``searcher`` gets (RL agents: at most ``rl_budget``)."""
        if SEARCHERS[searcher].episodes:
            return min(self.budget, self.rl_budget)
        return self.budget

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
            "stroke_mm": self.stroke_mm,
            "max_velocity_m_per_s": self.max_velocity_m_per_s,
            "rotation_mrad": self.rotation_mrad,
            "force_floor_n": self.force_floor_n,
            "force_scale_n": self.force_scale_n,
        }
