"""Identifying the MIMO network kinds of a bushing of several coordinates: ``MODELS``' fits.

Each fittable kind's form over C > 1 coordinates in ``bushenv.models.registry.MODELS`` names
one of the functions below (or ``linear.fit_linear`` and ``vector_boucwen.fit_boucwen``, which
identify the matrix and vector forms) and its options dataclass; ``bushenv.identify.fit`` calls
them as it calls the one-axis fits, ``fit(data, options, seed, progress) -> model``, ``data`` a
``TrainingSet`` of (T, C) records. What the card shows of an identification (evaluations, the
network gate's verdict, the certified check) is ``model.training["info"]``.

| name      | identification                                                      |
|-----------|---------------------------------------------------------------------|
| nn        | the MIMO NARX network, ``mimo_train.fit_mimo``                      |
| nn-axis   | one single-axis network per coordinate (seed 000 §4.2's kind), the same training |
| hybrid    | least-squares C x C backbone, then the MIMO network on the residual |
| hybrid-bw | the vector Bouc-Wen fit as backbone, then the MIMO network on its residual |

The networks train on every record's first 80 % and choose their weights by the free run on
every record's last 20 % (``--val-fraction``); no lag or window reaches across two records.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from bushenv.identify.data import IdentificationError, TrainingSet
from bushenv.identify.mimo_options import MimoHybridOptions, MimoOptions, record_problem
from bushenv.identify.options import option, option_like
from bushenv.identify.vector_boucwen import (
    MIN_SAMPLES,
    VectorBoucWenOptions,
    fit_vector_boucwen,
    say_of,
)
from bushenv.models.planar_base import PlanarModelError
from bushenv.progress import ProgressSpec

HYBRID_BW_FREE_RUN_STEPS = 1000  # the remainder network's free-run steps (HybridBWOptions)


@dataclass(frozen=True)
class HybridBWOptions(MimoOptions):
    """The network's options and the backbone's search (``vector_boucwen``)."""

    # the remainder's free run: at the networks' 200 steps it never beat the one-step-ahead
    # weights on the validation tails, so they were kept (studies/2026-11-combined-programme)
    free_run_steps: int = option_like(MimoOptions, "free_run_steps", HYBRID_BW_FREE_RUN_STEPS)
    evaluations: int = option(200, "shape evaluations of the bounded Powell search (after 8)")
    time_limit_s: float = option(
        0.0, "wall-time limit of the backbone's search, s (0: none, the default)"
    )
    relaxation_times: str = option_like(VectorBoucWenOptions, "relaxation_times")
    relaxation_selection: str = option_like(VectorBoucWenOptions, "relaxation_selection")
    # quasi-linear: better than the constant form in 5 of 6 fits, level in the sixth
    # (studies/2026-11-combined-programme, "The quasi-linear relaxation")
    relaxation_form: str = option_like(VectorBoucWenOptions, "relaxation_form", "qlv")
    network: str = option_like(MimoHybridOptions, "network")

    def check(self) -> None:
        super().check()
        self.backbone_options().check()
        if self.certified == "on":
            raise PlanarModelError(
                "--certified on is for nn, nn-axis and hybrid: hybrid-bw's Bouc-Wen backbone "
                "holds a hysteretic force the certified term does not model"
            )

    def backbone_options(self) -> VectorBoucWenOptions:
        return VectorBoucWenOptions(
            self.evaluations,
            time_limit_s=self.time_limit_s,
            relaxation_times=self.relaxation_times,
            relaxation_selection=self.relaxation_selection,
            relaxation_form=self.relaxation_form,
        )


def _network(kind: str):
    def fit(data: TrainingSet, options: MimoOptions, seed: int = 0, progress: ProgressSpec = True):
        from bushenv.identify.mimo_train import fit_mimo

        check_lengths(kind, options, data)
        q, f = zip(*data.histories(), strict=True)
        gated = getattr(options, "network", "always") == "if-better"
        model = fit_mimo(q, f, data.dt, kind, options.train_options(), seed, progress, gated)
        return _with_info(model, {**certified_info(model), **network_info(model)})

    fit.__name__ = fit.__qualname__ = "fit_" + kind.replace("-", "_")
    fit.__doc__ = f"Identify the MIMO {kind!r} network from ``data`` (module docstring)."
    return fit


fit_nn = _network("nn")
fit_nn_axis = _network("nn-axis")
fit_hybrid = _network("hybrid")


def fit_hybrid_bw(
    data: TrainingSet, options: HybridBWOptions, seed: int = 0, progress: ProgressSpec = True
):
    """The vector Bouc-Wen backbone (``vector_boucwen``), then the MIMO network on its
    residual, kept only if it validates better (``--network if-better``)."""
    from bushenv.identify.mimo_train import fit_mimo
    from bushenv.models.planar_hybrid_bw import compose

    check_lengths("hybrid-bw", options, data)
    histories = data.histories()
    backbone, info = fit_vector_boucwen(
        histories, data.dt, options.backbone_options(), say=say_of(progress)
    )
    q = [h[0] for h in histories]
    residual = [h[1] - backbone.simulate(h[0]) for h in histories]
    gated = options.network == "if-better"
    net = fit_mimo(q, residual, data.dt, "nn", options.train_options(), seed, progress, gated)
    info = {f"backbone {k}": v for k, v in info.items()}
    return _with_info(compose(backbone, net), {**info, **network_info(net)})


def _with_info(model: Any, info: dict[str, Any]) -> Any:
    """``model`` with ``info`` in its training log (what ``bushenv.identify.fit`` reads)."""
    model.training = {**(getattr(model, "training", None) or {}), "info": info}
    return model


def certified_info(model: Any) -> dict[str, str]:
    """The certified training's verdict on the weights kept, one line for the card."""
    check = (getattr(model, "training", None) or {}).get("certified")
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
    gate = (getattr(model, "training", None) or {}).get("network")
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


NETWORK_MIN_WINDOWS = 20  # free-run windows the training history holds at least (``mimo_train``)


def check_lengths(name: str, opts: Any, data: TrainingSet) -> None:
    """Refuse records too short for identifying ``name`` with ``opts``, naming the record and
    the fix (``IdentificationError``)."""
    lengths = {s.label: len(s) for s in data.segments}
    if name == "hybrid-bw":
        short = {k: n for k, n in lengths.items() if n < MIN_SAMPLES}
        if short:
            label, n = next(iter(short.items()))
            raise IdentificationError(
                f"{label}: {n} samples; the {name} identification needs at least "
                f"{MIN_SAMPLES} per record: give longer records"
            )
    for label, n in lengths.items():
        problem = record_problem(n, opts.val_fraction)
        if problem:
            raise IdentificationError(
                f"{label}: {problem}, as the {name} network needs: give a longer record"
            )
    need, total = NETWORK_MIN_WINDOWS * opts.window, sum(lengths.values())
    if total < need:
        shown = ", ".join(f"{k}: {n}" for k, n in lengths.items())
        raise IdentificationError(
            f"{total} training samples ({shown}); the {name} network trains on at least "
            f"{NETWORK_MIN_WINDOWS} x --window {opts.window} = {need} samples (all training "
            "records together): give longer records"
            + (f" or --window {total // NETWORK_MIN_WINDOWS}" if total >= 160 else "")
        )
