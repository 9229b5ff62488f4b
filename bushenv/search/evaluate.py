"""Batched evaluation: a population of profiles -> one (T, B) run per model -> verdicts.

``BatchEvaluator(model, reference, target)`` is what every searcher calls. One call takes a
list of profiles (each (T_i,): displacement in m for the rig, road height for the quarter car),
pads them into one (T, B) array (``families.pad_batch``), has the target simulate the model and
the reference over the whole batch (``targets.py``; the compiled kernels loop over B innermost)
and judges every column with ``divergence.judge``. It counts model evaluations
(one per profile) and the wall time spent, so budgets and "evaluations to first failure" mean
the same thing for every searcher.

Parallelism: the batch is split into ``threads`` contiguous chunks evaluated by a thread pool;
each chunk uses its own copies of the models. The kernels are numba ``nogil`` and most of
``judge`` is numpy, so threads overlap without pickling anything; two worker processes measured
about the same (docs/search.md) but need the models shipped and cannot share the reference
cache. Columns are independent, so the result is the same for any ``threads`` -- bit for bit
(tested).

``dtype="float32"`` (NARX models on the rig only) runs the model in single precision
(``NarxBushing.simulate(..., dtype="float32")``, about 2.4 times the steps/s); the reference
and the judge stay float64. The bench counts how many verdicts it changes
(``campaign.nn.float32_verdict_changes``: 0 of 4096).

The reference's response to a profile does not depend on the model, so it is cached by the
profile's bytes (a campaign re-judges the same profiles on the hybrid and the linear control).
"""

from __future__ import annotations

import hashlib
import threading
import time
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from bushenv.divergence import Verdict, static_curve
from bushenv.models.base import DT_TOLERANCE, BushingModel
from bushenv.models.narx import NarxBushing
from bushenv.scales import MACHINE, BushingScales
from bushenv.search.base import SearchError
from bushenv.search.families import pad_batch
from bushenv.search.targets import Responses, Target, get_target, simulate_or_nan

REFERENCE_CACHE_SIZE = 4096
KEPT = ("static curve", "rig3 floors")  # cache entries every profile uses: never evicted


@dataclass
class BatchResult:
    """The outcome of one batch: inputs, responses and the verdict, all columns aligned."""

    x: np.ndarray  # (T, B) bushing deflection the model saw, m
    lengths: np.ndarray  # (B,)
    f_model: np.ndarray  # (T, B) N
    f_ref: np.ndarray | None  # (T, B) N; None when judged without a reference
    verdict: Verdict
    profiles: np.ndarray  # (T, B) the profiles as given (displacement or road height)

    def profile(self, b: int) -> np.ndarray:
        return self.profiles[: self.lengths[b], b].copy()


class ReferenceRuns:
    """The reference's forces on (T, B) profiles, cached by each profile's bytes (shared by the
    evaluator's threads; each thread runs its own copy of the model), and its static curve.
    ``model`` None: no reference (every force is None)."""

    def __init__(
        self,
        model: BushingModel | None,
        cache: OrderedDict,
        lock: threading.Lock,
        scales: BushingScales = MACHINE,
        static: bool = True,
    ) -> None:
        self.model, self._cache, self._lock, self.scales = model, cache, lock, scales
        self.static = static

    def static_forces(self, x: np.ndarray) -> np.ndarray | None:
        """The reference's static force at every sample's displacement (``static_curve``);
        None without a reference or when its static behaviour is not to be trusted."""
        if self.model is None or not self.static:
            return None
        with self._lock:
            if "static curve" not in self._cache:
                self._cache["static curve"] = static_curve(self.model.copy(), self.scales.stroke_m)
            xs, fs = self._cache["static curve"]
        return np.interp(x, xs, fs)

    def cached(self, key: str, make):
        """``make(model)`` once per reference (kept with the static curve), e.g. the rig3
        target's floors; None without a reference."""
        if self.model is None:
            return None
        with self._lock:
            if key not in self._cache:
                self._cache[key] = make(self.model.copy())
            return self._cache[key]

    def forces(self, x: np.ndarray, lengths: np.ndarray) -> np.ndarray | None:
        """Reference force for each column; only the first ``lengths[b]`` samples are real."""
        if self.model is None:
            return None
        keys = [hashlib.sha1(x[: lengths[b], b].tobytes()).hexdigest() for b in range(x.shape[1])]
        with self._lock:
            found = {b: self._cache.get(key) for b, key in enumerate(keys)}
        missing = [b for b, got in found.items() if got is None]
        if missing:
            fr_new = simulate_or_nan(self.model, np.ascontiguousarray(x[:, missing]))
            with self._lock:
                for j, b in enumerate(missing):
                    found[b] = fr_new[: lengths[b], j].copy()
                    self._cache[keys[b]] = found[b]
                while len(self._cache) > REFERENCE_CACHE_SIZE:
                    oldest = next(iter(self._cache))
                    curve = self._cache.pop(oldest)
                    if oldest in KEPT:  # kept: they serve every profile
                        self._cache[oldest] = curve
        out = np.empty_like(x)
        for b, cached in found.items():
            out[: lengths[b], b] = cached
            out[lengths[b] :, b] = cached[-1]  # past the profile's end: ignored by judge
        return out


class BatchEvaluator:
    """Evaluate populations of profiles on ``model`` against ``reference`` (see module doc)."""

    def __init__(
        self,
        model: BushingModel,
        reference: BushingModel | None,
        target: str | Target = "rig",
        threads: int = 1,
        axis: str = "axial",
        dtype: str = "float64",
        scales: BushingScales = MACHINE,
        static: bool = True,
    ) -> None:
        self.target = get_target(target)
        if reference is None and not self.target.reference_free:
            raise SearchError(
                f"the {self.target.name} target needs a reference (its twin runs on it)"
            )
        if reference is not None and abs(model.dt - reference.dt) > DT_TOLERANCE * model.dt:
            raise SearchError(
                f"the model runs at {1 / model.dt:.6g} Hz (dt {model.dt:.6g} s), the reference "
                f"at {1 / reference.dt:.6g} Hz (dt {reference.dt:.6g} s): a verdict needs both "
                "at one rate"
            )
        if dtype not in ("float64", "float32"):
            raise SearchError(f"dtype must be 'float64' or 'float32', got {dtype!r}")
        if dtype == "float32" and not (isinstance(model, NarxBushing) and self.target.float32):
            raise SearchError(
                f"dtype 'float32' is for NARX models (nn, hybrid) on the rig, not {model.name!r} "
                f"on the {self.target.name}"
            )
        self.dtype = dtype
        self.scales = scales
        self.model = model
        self.reference = reference
        self.dt = model.dt
        self.axis = axis
        self.threads = max(1, int(threads))
        self.n_evaluations = 0
        self.seconds = 0.0
        self._pool = ThreadPoolExecutor(self.threads) if self.threads > 1 else None
        cache: OrderedDict[str, np.ndarray] = OrderedDict()
        lock = threading.Lock()
        self._copies = [
            (
                model.copy(),
                ReferenceRuns(reference and reference.copy(), cache, lock, scales, static),
            )
            for _ in range(self.threads)
        ]

    def _run_chunk(self, k: int, x: np.ndarray, lengths: np.ndarray) -> Responses:
        model, ref = self._copies[k]
        return self.target.responses(
            model, ref, x, lengths, self.dt, self.axis, self.dtype, self.scales
        )

    def evaluate(self, profiles: list[np.ndarray]) -> BatchResult:
        """Judge every profile; counts ``len(profiles)`` model evaluations."""
        t0 = time.perf_counter()
        x, lengths = pad_batch([np.asarray(p, dtype=np.float64) for p in profiles])
        B = x.shape[1]
        n_chunks = min(self.threads, B)
        bounds = np.linspace(0, B, n_chunks + 1).astype(int)
        chunks = [(bounds[i], bounds[i + 1]) for i in range(n_chunks)]
        if self._pool is None or n_chunks == 1:
            parts = [self._run_chunk(0, x, lengths)]
        else:
            futures = [
                self._pool.submit(self._run_chunk, i, np.ascontiguousarray(x[:, a:b]), lengths[a:b])
                for i, (a, b) in enumerate(chunks)
            ]
            parts = [f.result() for f in futures]
        verdict = _merge_verdicts([p.verdict for p in parts])
        xs = np.concatenate([p.x for p in parts], axis=1)
        fm = np.concatenate([p.f_model for p in parts], axis=1)
        fr = None if parts[0].f_ref is None else np.concatenate([p.f_ref for p in parts], axis=1)
        self.n_evaluations += B
        self.seconds += time.perf_counter() - t0
        return BatchResult(xs, lengths, fm, fr, verdict, profiles=x)

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None

    def __enter__(self) -> BatchEvaluator:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def _merge_verdicts(parts: list[Verdict]) -> Verdict:
    if len(parts) == 1:
        return parts[0]
    cat = np.concatenate
    merged_extra = getattr(parts[0], "merged_extra", None)  # a target's own verdict fields
    extra = merged_extra(parts) if merged_extra else {}
    return type(parts[0])(
        diverged=cat([p.diverged for p in parts]),
        flags={k: cat([p.flags[k] for p in parts]) for k in parts[0].flags},
        first_time_s=cat([p.first_time_s for p in parts]),
        first_criterion=[c for p in parts for c in p.first_criterion],
        worst_deviation=cat([p.worst_deviation for p in parts]),
        robustness=cat([p.robustness for p in parts]),
        criterion_robustness={
            k: cat([p.criterion_robustness[k] for p in parts])
            for k in parts[0].criterion_robustness
        },
        scale_n=cat([p.scale_n for p in parts]),
        criteria_run=parts[0].criteria_run,
        reference_unusable=cat([p.reference_unusable for p in parts]),
        criterion_first_s={
            k: cat([p.criterion_first_s[k] for p in parts]) for k in parts[0].criterion_first_s
        },
        **extra,
    )
