"""The MIMO networks' training options, one list: the flags of ``bushenv fit`` on 3-axis
records (``MODELS``' three-coordinate forms name them) and what ``mimo_train.fit_mimo`` takes.
No torch here: the command line reads them.
"""

from __future__ import annotations

from dataclasses import dataclass

from bushenv.identify.narx_options import SWITCH, NarxOptions
from bushenv.identify.options import option, option_like
from bushenv.models.planar_base import PlanarModelError
from bushenv.models.planar_narx import N_PAST_F, N_PAST_Q, STRUCTURES

VAL_MIN_SAMPLES = 10  # a validation tail shorter than this says nothing (as bushenv.identify)


def record_problem(samples: int, val_fraction: float) -> str | None:
    """Why a record of ``samples`` cannot be split for a network's training, or None."""
    n_val, lags = int(val_fraction * samples), max(N_PAST_Q, N_PAST_F)
    if n_val < VAL_MIN_SAMPLES or samples - n_val <= lags:
        return (
            f"{samples} samples cannot be split into a training part longer than the {lags} "
            f"lags and a validation tail of at least {VAL_MIN_SAMPLES} samples "
            f"({val_fraction:.0%} of each record)"
        )
    return None


@dataclass(frozen=True)
class MimoOptions:
    """Options of the MIMO network training: the flags of ``bushenv fit`` and what
    ``mimo_train.fit_mimo`` takes."""

    hidden: int = option(27, "hidden tanh units (the per-axis kind: a third per axis)")
    teacher_steps: int = option(400, "Adam steps one step ahead")
    teacher_lr: float = option(1e-2, "learning rate one step ahead (cosine decay to 0)")
    free_run_steps: int = option(200, "Adam steps on free-run windows")
    free_run_lr: float = option(2e-3, "free-run learning rate")
    window: int = option(64, "samples per free-run window")
    windows: int = option(32, "free-run windows per step")
    val_fraction: float = option(0.2, "last part of each training record kept for validation")
    eval_every: int = option(25, "free-run steps between two validations")
    teacher_batch: int = option(
        0, "samples per one-step-ahead step, drawn at random (0: the full batch)"
    )
    feedback_noise: float = option(
        0.0, "std of the noise on the fed-back scaled past outputs one step ahead (0: none)"
    )
    certified: str = option(
        "off",
        "on: a loss term holding every fixed point of the held network, over the rig3 box "
        "(single coordinates, pairs, all three), within a band of the records' static force per "
        "coordinate and below a spectral radius, and every held run after a step settled "
        "(identify/mimo_certified.py; studies/2026-11-planar-certified)",
        choices=SWITCH,
    )
    # the same as the one-axis network's term (``identify.narx_options``)
    certified_weight: float = option_like(NarxOptions, "certified_weight")
    certified_low: float = option_like(NarxOptions, "certified_low")
    certified_high: float = option_like(NarxOptions, "certified_high")
    certified_radius: float = option_like(NarxOptions, "certified_radius")
    certified_holds: int = option(24, "holds per training step")
    certified_stroke_m: float = option(
        0.0125, "holds span +-this deflection, m (axial and radial; BushRig3-v0's stroke)"
    )
    certified_rotation_rad: float = option(0.15, "holds span +-this rotation, rad (BushRig3-v0's)")
    structure: str = option(
        "free",
        "weights tied by construction (nn, hybrid): mirror (odd in each coordinate, diagonal "
        "backbone), rate (displacement as increments: one held fixed point), mirror-rate "
        "(identify/mimo_structure.py; studies/2026-11-planar-certified)",
        choices=STRUCTURES,
    )

    def check(self) -> None:
        small = [n for n in ("hidden", "teacher_steps", "window", "windows", "eval_every")
                 if getattr(self, n) < 1]  # fmt: skip
        self._check_certified()
        if small or self.free_run_steps < 0 or not 0 < self.val_fraction < 0.9:
            raise PlanarModelError(
                f"MIMO network options: {small or 'free_run_steps / val_fraction'} out of "
                "range (counts >= 1, free_run_steps >= 0, 0 < val_fraction < 0.9)"
            )
        if self.teacher_batch < 0 or not 0 <= self.feedback_noise < 10:
            raise PlanarModelError(
                f"MIMO network options: teacher_batch {self.teacher_batch} and feedback_noise "
                f"{self.feedback_noise} out of range (teacher_batch >= 0, 0 <= feedback_noise < 10)"
            )
        if self.hidden % 3:
            raise PlanarModelError(f"hidden must be a multiple of 3 (one group per axis), got "
                                   f"{self.hidden}")  # fmt: skip

    def _check_certified(self) -> None:
        bad = []
        if not 0.0 <= self.certified_low < 1.0 < self.certified_high:
            bad.append(f"certified_low {self.certified_low} and certified_high "
                       f"{self.certified_high} (need 0 <= low < 1 < high)")  # fmt: skip
        if not 0.0 < self.certified_radius < 1.0:
            bad.append(f"certified_radius {self.certified_radius} (need 0 < radius < 1)")
        if not (self.certified_stroke_m > 0 and self.certified_rotation_rad > 0):
            bad.append("certified_stroke_m and certified_rotation_rad (need > 0)")
        if self.certified_weight < 0 or self.certified_holds < 1:
            bad.append("certified_weight >= 0 and certified_holds >= 1")
        if bad:
            raise PlanarModelError(f"MIMO network options: {'; '.join(bad)}")

    def train_options(self) -> MimoOptions:
        """The training's options alone (a subclass's other fields dropped)."""
        return MimoOptions(**{k: getattr(self, k) for k in MimoOptions.__dataclass_fields__})

    def certified_term(self):
        """The certified-hold term the options ask for, or None."""
        if self.certified != "on":
            return None
        from bushenv.identify.mimo_certified import MimoCertifiedHolds

        return MimoCertifiedHolds(
            weight=self.certified_weight,
            low=self.certified_low,
            high=self.certified_high,
            radius=self.certified_radius,
            stroke=(self.certified_stroke_m, self.certified_stroke_m, self.certified_rotation_rad),
            holds=self.certified_holds,
        )


# the hybrid's accurate recipe (studies/2026-11-planar-fit-unseen, "The matrix-backbone
# hybrid"): twice
# the units, 6000 mini-batch steps one step ahead with noise on the fed-back outputs, about 1.4x
# the plain fit's time; 3x as accurate on unseen records, but at some holds inside its training
# range more than one fixed point (docs/planar.md, "Passivity"), so not the default
NOISY_FEEDBACK_TRAINING = {
    "hidden": 54,
    "teacher_steps": 6000,
    "teacher_lr": 3e-3,
    "teacher_batch": 2048,
    "feedback_noise": 0.1,
}
HYBRID_TRAININGS = ("plain", "noisy-feedback")
NETWORK_KEPT = ("if-better", "always")


@dataclass(frozen=True)
class MimoHybridOptions(MimoOptions):
    """The matrix-backbone hybrid's network: the plain recipe, or the accurate one."""

    training: str = option(
        "plain",
        "plain: the networks' own training (one stable fixed point at every hold of the "
        "training range where measured); noisy-feedback: 54 units, 6000 mini-batch steps one "
        "step ahead with noise 0.1 on the fed-back outputs, 3x as accurate on unseen records "
        "but with more than one fixed point at some holds (the card warns); flags given win",
        choices=HYBRID_TRAININGS,
    )
    network: str = option(
        "if-better",
        "if-better: the network is kept only if its free run on the training records' "
        "validation tails beats the backbone alone, else the model is the backbone with a "
        "network that adds exactly zero (the card says which); always: keep the best network",
        choices=NETWORK_KEPT,
    )

    @staticmethod
    def implied(given: dict) -> dict:
        """``training="noisy-feedback"``: its settings, where not given."""
        if given.get("training") == "noisy-feedback":
            return {**NOISY_FEEDBACK_TRAINING, **given}
        return given


def default_options(kind: str) -> MimoOptions:
    """The training options a network ``kind`` gets when none are given: the same for all."""
    return MimoOptions()
