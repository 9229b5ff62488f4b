"""Identifying three-axis models from 3-axis records: the identifications ``MODELS`` names.

Each fittable kind's three-coordinate ``Form`` in ``bushenv.models.registry.MODELS`` names one
of the functions below and its options dataclass, whose fields are flags of ``bushenv fit`` as
the one-axis options are (``bushenv.identify.options``). ``fit_planar(records, name, options,
seed)`` runs one; records are ``(q (T, 3), f (T, 3))`` pairs at one sample time.

| name      | identification                                                      |
|-----------|---------------------------------------------------------------------|
| linear    | least squares of f on [q, v] (3x3 K and C)                          |
| nn        | the MIMO NARX network, ``train.fit_planar_network``                 |
| nn-axis   | three single-axis networks (seed 000 §4.2's kind), the same training |
| hybrid    | least-squares 3x3 backbone, then the MIMO network on the residual (noisy feedback) |
| boucwen   | variable projection: bounded Powell on the shape, least squares K, C, G, h |
| hybrid-bw | the boucwen fit as backbone, then the MIMO network on its residual  |

The networks train on every record's first 80 % and choose their weights by the free run on
every record's last 20 % (``--val-fraction``); no lag or window reaches across two records.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from bushenv.identify.options import option, option_like, options_of
from bushenv.models.planar_base import PlanarModel, PlanarModelError
from bushenv.models.registry import MODELS, names_for
from bushenv.planar.boucwen_fit import PlanarBoucWenOptions, fit_planar_boucwen
from bushenv.planar.train_options import (
    PlanarHybridOptions,
    PlanarNetworkOptions,
    record_problem,
)

History = tuple[np.ndarray, np.ndarray]


@dataclass(frozen=True)
class PlanarHybridBWOptions(PlanarNetworkOptions):
    """The network's options and the backbone's search (``boucwen_fit``)."""

    evaluations: int = option(200, "shape evaluations of the bounded Powell search (after 8)")
    time_limit_s: float = option(
        0.0, "wall-time limit of the backbone's search, s (0: none, the default)"
    )
    relaxation_times: str = option_like(PlanarBoucWenOptions, "relaxation_times")
    relaxation_selection: str = option_like(PlanarBoucWenOptions, "relaxation_selection")
    network: str = option_like(PlanarHybridOptions, "network")

    def check(self) -> None:
        super().check()
        self.backbone_options().check()
        if self.certified == "on":
            raise PlanarModelError(
                "--certified on is for nn, nn-axis and hybrid: hybrid-bw's Bouc-Wen backbone "
                "holds a hysteretic force the certified term does not model"
            )

    def backbone_options(self) -> PlanarBoucWenOptions:
        return PlanarBoucWenOptions(
            self.evaluations,
            time_limit_s=self.time_limit_s,
            relaxation_times=self.relaxation_times,
            relaxation_selection=self.relaxation_selection,
        )


@dataclass
class PlanarFitResult:
    model: PlanarModel
    name: str
    options: Any
    seed: int
    seconds: float
    info: dict[str, Any] = field(default_factory=dict)


def fit_linear(histories, dt, opts, seed, say):
    from bushenv.models.base import velocity_of
    from bushenv.models.planar_linear import fit_linear

    q = np.vstack([h[0] for h in histories])
    v = np.vstack([velocity_of(h[0], dt) for h in histories])
    return fit_linear(q, v, np.vstack([h[1] for h in histories]), dt), {}


def _network(kind: str):
    def fit(histories, dt, opts, seed, say):
        from bushenv.planar.train import fit_planar_network

        q, f = [h[0] for h in histories], [h[1] for h in histories]
        gated = getattr(opts, "network", "always") == "if-better"
        model = fit_planar_network(
            q, f, dt, kind, opts.train_options(), seed, quiet=say is None, may_drop=gated
        )
        return model, {**certified_info(model), **network_info(model)}

    return fit


def certified_info(model: Any) -> dict[str, str]:
    """The certified training's verdict on the weights kept, one line for the card."""
    check = getattr(model, "training", {}).get("certified")
    if check is None:
        return {}
    verdict = "admitted" if check["admitted"] else "NOT admitted (best of all weights kept)"
    return {
        "certified": (
            f"{verdict}: {check['holds']} holds, {check['unstable']} unstable and "
            f"{check['out_of_band']} out-of-band fixed points, max spectral radius "
            f"{check['max_spectral_radius']:.3f}, {check['unsettled_holds']} unsettled holds, "
            f"{check['holds_without_one_fixed_point']} holds without exactly one fixed point"
        )
    }


def network_info(model: Any) -> dict[str, str]:
    """Whether a hybrid kept its network, and the validation figures that chose, for the card."""
    gate = getattr(model, "training", {}).get("network")
    if gate is None:
        return {}
    if gate.get("gated") is False:
        return {"network": "kept without the gate: --certified on keeps the best admitted weights"}
    verdict = "DROPPED (the backbone alone is the model)" if gate["dropped"] else "kept"
    alone, net = gate["backbone_alone"], gate["with_network"]
    return {
        "network": (
            f"{verdict}: on the training records' validation tails the network "
            + (
                f"adds {100 * (net - alone) / alone:.1f} % to"
                if net >= alone
                else f"takes {100 * (alone - net) / alone:.1f} % off"
            )  # fmt: skip
            + " the error of the backbone alone (sum over "
            f"the axes of the free run's RMS ratio to what the network is trained on, the force "
            f"or a backbone's residual: {net:.4f} with it, {alone:.4f} without)"
        )
    }


fit_nn = _network("nn")
fit_nn_axis = _network("nn-axis")
fit_hybrid = _network("hybrid")


def fit_boucwen(histories, dt, opts, seed, say):
    return fit_planar_boucwen(histories, dt, opts, say=say)


def fit_hybrid_bw(histories, dt, opts, seed, say):
    from bushenv.models.planar_hybrid_bw import compose
    from bushenv.planar.train import fit_planar_network

    backbone, info = fit_planar_boucwen(histories, dt, opts.backbone_options(), say=say)
    q = [h[0] for h in histories]
    residual = [h[1] - backbone.simulate(h[0]) for h in histories]
    gated = opts.network == "if-better"
    net = fit_planar_network(
        q, residual, dt, "nn", opts.train_options(), seed, quiet=say is None, may_drop=gated
    )
    info = {f"backbone {k}": v for k, v in info.items()}
    return compose(backbone, net), {**info, **network_info(net)}


def options_class(name: str) -> type:
    """The options dataclass of the three-axis identification of ``name``."""
    return MODELS[name].options_class(3)


BOUCWEN_MIN_SAMPLES = 20  # per record (``boucwen_fit``)
NETWORK_MIN_WINDOWS = 20  # free-run windows the training history holds at least (``train``)


def length_problem(name: str, options: Any, lengths: dict[str, int]) -> str | None:
    """What is too short for identifying ``name`` from records of ``lengths`` (label ->
    samples), with the fix; None when they are long enough."""
    opts = options_of(options_class(name), options, name)
    if name in ("boucwen", "hybrid-bw"):
        short = {k: n for k, n in lengths.items() if n < BOUCWEN_MIN_SAMPLES}
        if short:
            label, n = next(iter(short.items()))
            return (
                f"{label}: {n} samples; the {name} identification needs at least "
                f"{BOUCWEN_MIN_SAMPLES} per record: give longer records"
            )
    if isinstance(opts, PlanarNetworkOptions):
        for label, n in lengths.items():
            problem = record_problem(n, opts.val_fraction)
            if problem:
                return f"{label}: {problem}, as the {name} network needs: give a longer record"
        need, total = NETWORK_MIN_WINDOWS * opts.window, sum(lengths.values())
        if total < need:
            shown = ", ".join(f"{k}: {n}" for k, n in lengths.items())
            return (
                f"{total} training samples ({shown}); the {name} network trains on at least "
                f"{NETWORK_MIN_WINDOWS} x --window {opts.window} = {need} samples (all training "
                "records together): give longer records"
                + (f" or --window {total // NETWORK_MIN_WINDOWS}" if total >= 160 else "")
            )
    return None


def fit_planar(
    histories: Sequence[History],
    name: str,
    options: Any = None,
    dt: float | None = None,
    seed: int = 0,
    say: Callable[[str], None] | None = None,
) -> PlanarFitResult:
    """Identify the planar model ``name`` from ``histories`` at sample time ``dt``."""
    form = MODELS[name].form(3)
    if form.fit is None:
        raise PlanarModelError(
            f"model {name} has no 3-axis identification; for 3-axis records choose one of: "
            f"{', '.join(names_for(3, fittable=True))}"
        )
    if dt is None or not dt > 0:
        raise PlanarModelError(f"fit_planar: dt must be a positive number of seconds, got {dt!r}")
    opts = options_of(form.options_class(), options, name)
    t0 = time.perf_counter()
    model, info = form.fit_function()(list(histories), dt, opts, seed, say)
    return PlanarFitResult(model, name, opts, seed, time.perf_counter() - t0, info)
