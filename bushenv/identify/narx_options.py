"""The options of the NARX training ("nn" and "hybrid"): one dataclass, each field a flag of
``bushenv fit``. Kept apart from the training (``neural.py``) so reading them imports no torch.
"""

from __future__ import annotations

from dataclasses import dataclass

from bushenv.identify.data import IdentificationError
from bushenv.identify.options import option
from bushenv.models.narx import HIDDEN, N_PAST_F, N_PAST_X

ENGINES = ("numba", "torch")
RECIPES = ("free-run", "teacher-forcing")
INPUT_BASES = ("auto", "lags", "differences")
EARLY_STOPS = ("training", "stage")
SWITCH = ("off", "on")
CHOOSE_NETWORKS = ("9x5", "18x5", "9x10")  # units x lags; docs/fit.md: why these
SET_BY_CHOICE = ("hidden", "n_past_x", "n_past_f")  # giving one of these turns the choice off


@dataclass(frozen=True)
class NarxOptions:
    """Options of the NARX training ("nn" and "hybrid"); each is a flag of ``bushenv fit``."""

    recipe: str = option(
        "free-run",
        "free-run: one step ahead, then free-run fine-tuning on windows of the records; "
        "teacher-forcing: one step ahead only (the papers' recipe, seed 000 §4.2)",
        choices=RECIPES,
    )
    choose: str = option(
        "on",
        "on: the network (units and lags) chosen on the validation parts among "
        "--choose-networks, each trained with --choose-share of the iterations, the best then "
        "in full; off: --hidden, --n-past-x, --n-past-f as given (giving one turns it off)",
        choices=SWITCH,
    )
    choose_networks: tuple[str, ...] = option(
        CHOOSE_NETWORKS, "candidate networks, UNITSxLAGS (one tanh layer; n-past-x = n-past-f)"
    )
    choose_share: float = option(
        0.2, "share of the iteration counts each candidate trains with before the choice"
    )
    hidden: tuple[int, ...] = option(
        HIDDEN, "tanh units per hidden layer, one or two layers (seed 001: 10,9); --choose off"
    )
    n_past_x: int = option(
        N_PAST_X, "past displacements fed to the net (besides the current); --choose off"
    )
    n_past_f: int = option(N_PAST_F, "past own forces fed to the net; --choose off")
    val_fraction: float = option(0.2, "last part of each record kept for validation")
    teacher_steps: int = option(2000, "full-batch Adam steps one step ahead")
    teacher_lr: float = option(1e-2, "learning rate one step ahead (cosine decay to 0)")
    window_lengths: tuple[int, ...] = option(
        (20, 100, 400, 800, 1600), "free-run window lengths, samples, one stage each"
    )
    iters_per_length: tuple[int, ...] = option(
        (1200, 1200, 1200, 1200, 1200), "free-run iterations of each stage"
    )
    batch_windows: int = option(16, "windows per free-run iteration")
    free_run_lr: float = option(1e-2, "free-run learning rate")
    free_run_lr_final: float = option(
        1.0, "free-run learning rate at the end, as a fraction of --free-run-lr (cosine)"
    )
    input_basis: str = option(
        "auto",
        "variables the first layer trains in: lags, or the current value and lag differences "
        "(same network, exported in lags); auto: lags under teacher-forcing (the papers' "
        "network), differences under free-run",
        choices=INPUT_BASES,
    )
    engine: str = option(
        "numba", "free-run unroll in training: numba (compiled) or torch", choices=ENGINES
    )
    grad_clip: float = option(1.0, "gradient norm clip in the free-run stage")
    weight_decay: float = option(0.0, "L2 weight on the hidden-layer weights (a loss term)")
    certified: str = option(
        "off",
        "on: a loss term holding every fixed point of the held network, over the stroke, "
        "within a band of the records' static force and below a spectral radius, and every "
        "held run after a step settled (certified.py; docs/fit.md)",
        choices=SWITCH,
    )
    certified_weight: float = option(1.0, "weight of the certified-hold term")
    certified_low: float = option(
        0.8, "held force at least this fraction of the records' static estimate, same sign"
    )
    certified_high: float = option(
        1.9, "held force at most this multiple of the records' static estimate"
    )
    certified_radius: float = option(
        0.98, "spectral radius of a held fixed point above which the term grows"
    )
    certified_stroke_m: float = option(
        0.0125, "holds span +-this displacement, m (the test machine's stroke)"
    )
    certified_holds: int = option(24, "holds per training step, denser near rest")
    eval_every: int = option(25, "iterations between two validations")
    patience: int = option(8, "validations without improvement before a stop")
    early_stop: str = option(
        "stage",
        "what patience ends in the free run: the current window stage, or the training",
        choices=EARLY_STOPS,
    )
    threads: int = option(1, "torch threads")
    time_limit_s: float = option(
        0.0,
        "wall-time limit, s; 0: none. Iteration counts decide when training ends, so a seed "
        "reproduces the weights; a limit that stops it early is reported and on the card",
    )
    progress_every_s: float = option(3.0, "seconds between progress lines")

    @staticmethod
    def implied(given: dict) -> dict:
        """Options as given, with ``choose="off"`` when a size or lag is given without it."""
        if "choose" not in given and any(k in given for k in SET_BY_CHOICE):
            return {**given, "choose": "off"}
        return given

    def networks(self) -> list[tuple[int, int]]:
        """The candidates of ``choose_networks`` as (units, lags)."""
        out = []
        for text in self.choose_networks:
            units, _, lags = text.partition("x")
            if not (units.strip().isdigit() and lags.strip().isdigit()):
                raise IdentificationError(
                    f"choose_networks: {text!r} is not UNITSxLAGS (e.g. 9x5: 9 tanh units, "
                    "5 past displacements and 5 past forces)"
                )
            if int(units) < 1 or int(lags) < 1:
                raise IdentificationError(f"choose_networks: {text!r} needs units and lags >= 1")
            out.append((int(units), int(lags)))
        if not out:
            raise IdentificationError("choose_networks: give at least one UNITSxLAGS")
        return out

    def basis(self) -> str:
        """The input basis training uses ("auto" resolved by the recipe)."""
        if self.input_basis != "auto":
            return self.input_basis
        return "lags" if self.recipe == "teacher-forcing" else "differences"

    def check(self) -> None:
        if len(self.window_lengths) != len(self.iters_per_length):
            raise IdentificationError(
                f"window_lengths {self.window_lengths} and iters_per_length "
                f"{self.iters_per_length} must have the same length"
            )
        if not 0.0 < self.val_fraction < 0.9:
            raise IdentificationError(f"val_fraction must be in (0, 0.9), got {self.val_fraction}")
        if min(self.window_lengths, default=1) < 1:
            raise IdentificationError(f"window_lengths must be >= 1, got {self.window_lengths}")
        if len(self.hidden) not in (1, 2) or min(self.hidden, default=0) < 1:
            raise IdentificationError(
                f"hidden must be one or two positive sizes, got {self.hidden}"
            )
        self.networks()
        if not 0.0 < self.choose_share <= 1.0:
            raise IdentificationError(f"choose_share must be in (0, 1], got {self.choose_share}")
        if self.time_limit_s < 0:
            raise IdentificationError(f"time_limit_s must be >= 0, got {self.time_limit_s}")
        for name in ("n_past_x", "n_past_f", "eval_every", "patience", "batch_windows"):
            if getattr(self, name) < 1:
                raise IdentificationError(f"{name} must be >= 1, got {getattr(self, name)}")
        if self.teacher_steps < 0 or min(self.iters_per_length, default=0) < 0:
            raise IdentificationError("teacher_steps and iters_per_length must be >= 0")
        self._check_certified()

    def _check_certified(self) -> None:
        if not 0.0 <= self.certified_low < 1.0 < self.certified_high:
            raise IdentificationError(
                "certified_low and certified_high must satisfy 0 <= low < 1 < high, got "
                f"{self.certified_low} and {self.certified_high}"
            )
        if not 0.0 < self.certified_radius < 1.0:
            raise IdentificationError(
                f"certified_radius must be in (0, 1), got {self.certified_radius}"
            )
        if not (self.certified_stroke_m > 0.0 and self.certified_weight >= 0.0):
            raise IdentificationError(
                "certified_stroke_m must be > 0 and certified_weight >= 0, got "
                f"{self.certified_stroke_m} and {self.certified_weight}"
            )
        if self.certified_holds < 2:
            raise IdentificationError(f"certified_holds must be >= 2, got {self.certified_holds}")


@dataclass(frozen=True)
class HybridOptions(NarxOptions):
    """The hybrid's options: the NN's, but its network is not chosen unless asked (its
    backbone carries the bulk of the force; its 9x5 network fits the bushings measured in
    docs/fit.md within 3.2 %)."""

    choose: str = option(
        "off",
        "on: the network (units and lags) chosen on the validation parts among "
        "--choose-networks, each trained with --choose-share of the iterations, the best then "
        "in full; off: --hidden, --n-past-x, --n-past-f as given (giving one turns it off)",
        choices=SWITCH,
    )
