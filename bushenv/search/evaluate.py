"""Batched evaluation: a population of profiles -> one (T, B) free run per model -> verdicts.

``BatchEvaluator(model, reference)`` is what every searcher calls. One call takes a list of
profiles (each (T_i,) displacement in m for the rig, or road height for the quarter car), pads
them into one (T, B) array (``families.pad_batch``), runs ``model.simulate`` and
``reference.simulate`` once each over the whole batch (the compiled kernels loop over B
innermost) and judges every column with ``divergence.judge``. It counts model evaluations
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

from bushenv.divergence import Verdict, judge
from bushenv.models.base import BushingModel
from bushenv.models.narx import NarxBushing
from bushenv.search.families import pad_batch

REFERENCE_CACHE_SIZE = 4096


@dataclass
class BatchResult:
    """The outcome of one batch: inputs, responses and the verdict, all columns aligned."""

    x: np.ndarray  # (T, B) bushing deflection the model saw, m
    lengths: np.ndarray  # (B,)
    f_model: np.ndarray  # (T, B) N
    f_ref: np.ndarray  # (T, B) N
    verdict: Verdict
    road: np.ndarray | None = None  # (T, B) road height for quarter-car batches

    def profile(self, b: int) -> np.ndarray:
        src = self.road if self.road is not None else self.x
        return src[: self.lengths[b], b].copy()


class BatchEvaluator:
    """Evaluate populations of profiles on ``model`` against ``reference`` (see module doc)."""

    def __init__(
        self,
        model: BushingModel,
        reference: BushingModel,
        env: str = "rig",
        threads: int = 1,
        axis: str = "axial",
        dtype: str = "float64",
    ) -> None:
        if abs(model.dt - reference.dt) > 1e-9 * model.dt:
            raise ValueError(
                f"model dt {model.dt:.6g} s differs from the reference's {reference.dt:.6g} s"
            )
        if env not in ("rig", "quartercar"):
            raise ValueError(f"env must be 'rig' or 'quartercar', got {env!r}")
        if dtype not in ("float64", "float32"):
            raise ValueError(f"dtype must be 'float64' or 'float32', got {dtype!r}")
        if dtype == "float32" and not (isinstance(model, NarxBushing) and env == "rig"):
            raise ValueError(
                f"dtype 'float32' is for NARX models (nn, hybrid) on the rig, not {model.name!r} "
                f"on the {env}"
            )
        self.dtype = dtype
        self.model = model
        self.reference = reference
        self.dt = model.dt
        self.env = env
        self.axis = axis
        self.threads = max(1, int(threads))
        self.n_evaluations = 0
        self.seconds = 0.0
        self._pool = ThreadPoolExecutor(self.threads) if self.threads > 1 else None
        self._copies = [(model.copy(), reference.copy()) for _ in range(self.threads)]
        self._ref_cache: OrderedDict[str, np.ndarray] = OrderedDict()
        self._lock = threading.Lock()

    # ----- one chunk --------------------------------------------------------------------------
    def _run_chunk(self, k: int, x: np.ndarray, lengths: np.ndarray):
        model, ref = self._copies[k]
        if self.env == "rig":
            if self.dtype == "float32":
                fm = model.simulate(x, dtype="float32").astype(np.float64)
            else:
                fm = simulate_or_nan(model, x)
            fr = self._reference_rig(ref, x, lengths)
            return judge(x, fm, fr, self.dt, lengths=lengths), x, fm, fr, None
        from bushenv.search.roads import quarter_car_responses

        return quarter_car_responses(model, ref, x, lengths, self.dt, self.axis)

    def _reference_rig(self, ref: BushingModel, x: np.ndarray, lengths: np.ndarray) -> np.ndarray:
        """Reference force for each column; only the first ``lengths[b]`` samples are real."""
        keys = [hashlib.sha1(x[: lengths[b], b].tobytes()).hexdigest() for b in range(x.shape[1])]
        with self._lock:
            found = {b: self._ref_cache.get(key) for b, key in enumerate(keys)}
        missing = [b for b, got in found.items() if got is None]
        if missing:
            fr_new = ref.simulate(np.ascontiguousarray(x[:, missing]))
            with self._lock:
                for j, b in enumerate(missing):
                    found[b] = fr_new[: lengths[b], j].copy()
                    self._ref_cache[keys[b]] = found[b]
                while len(self._ref_cache) > REFERENCE_CACHE_SIZE:
                    self._ref_cache.popitem(last=False)
        out = np.empty_like(x)
        for b, cached in found.items():
            out[: lengths[b], b] = cached
            out[lengths[b] :, b] = cached[-1]  # past the profile's end: ignored by judge
        return out

    # ----- the public call --------------------------------------------------------------------
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
        verdict = _merge_verdicts([p[0] for p in parts])
        xs = np.concatenate([p[1] for p in parts], axis=1)
        fm = np.concatenate([p[2] for p in parts], axis=1)
        fr = np.concatenate([p[3] for p in parts], axis=1)
        road = x if self.env == "quartercar" else None
        self.n_evaluations += B
        self.seconds += time.perf_counter() - t0
        return BatchResult(xs, lengths, fm, fr, verdict, road=road)

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None

    def __enter__(self) -> BatchEvaluator:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def simulate_or_nan(model: BushingModel, x: np.ndarray) -> np.ndarray:
    """``model.simulate(x)`` for (T, B) ``x``; a model that refuses (raises ValueError, e.g.
    Bouc-Wen's step-size control) gives NaN from the sample it refused on, in the histories that
    made it refuse -- a non-finite output, which ``judge`` calls a divergence."""
    try:
        return model.simulate(x)
    except ValueError:
        pass
    from bushenv.models.base import velocity_of

    out = np.empty_like(x)
    for b in range(x.shape[1]):
        col = np.ascontiguousarray(x[:, b])
        try:
            out[:, b] = model.simulate(col)
            continue
        except ValueError:
            pass
        v = velocity_of(col, model.dt)  # the velocity simulate would have used
        model.reset(1)
        out[:, b] = np.nan
        for t in range(col.size):
            try:
                out[t, b] = model.step(col[t], v[t])
            except ValueError:
                break
    return out


def _merge_verdicts(parts: list[Verdict]) -> Verdict:
    if len(parts) == 1:
        return parts[0]
    cat = np.concatenate
    return Verdict(
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
    )
