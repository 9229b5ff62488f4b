"""The effect contract as checks any registered effect gets (like scikit-learn's estimator
checks and Gymnasium's env checker): ``tests/diagnose/test_effect_checks.py`` runs every check
over every ``EFFECTS`` entry, so registering an effect is the one step that tests it.

Each check takes a registry name and raises ``AssertionError`` naming the effect and what
broke. The probe records are what a test machine drives: band-limited random motion with a
held step on each side, at two sample rates and lengths.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from functools import cache
from typing import Any

import numpy as np
from scipy import signal
from scipy.optimize import lsq_linear

from bushenv.diagnose.candidates import EFFECTS, get_effect
from bushenv.diagnose.effects.base import (
    Effect,
    Lasting,
    Nuisance,
    Richest,
    Scales,
    Signals,
    contract_problem,
)
from bushenv.diagnose.effects.timeshift import shift_columns

K_N_PER_M = 380e3  # the probe bushing: seed 000's axial Table 1
C_NS_PER_M = 4.4e3
EDGE_S = 0.5  # left out of the fits at both ends (a shifted force holds its end values there)
WEIGHT_RTOL = 1e-4  # of the largest true weight (k, c and the effect's own)
MISFIT_MAX = 1e-4  # of the force RMS; a fractional delay's interpolation leaves ~3e-5
MAX_SHAPES = 6  # shapes whose columns are checked (the grid's ends and middle, the example's)

Check = Callable[[str], None]


def probe_motion(seed: int, duration_s: float, dt: float, peak_m: float = 4e-3) -> np.ndarray:
    """Random motion in 0.1-15 Hz, amplitude-modulated, with a held step each side (m), (T,)."""
    rng = np.random.default_rng(seed)
    n = int(round(duration_s / dt))
    b, a = signal.butter(2, [0.1 * 2 * dt, 15 * 2 * dt], btype="band")
    x = signal.lfilter(b, a, rng.normal(size=n))
    x *= 0.3 + 0.7 * (0.5 + 0.5 * np.sin(4 * np.pi * np.arange(n) * dt / duration_s))
    x *= peak_m / np.max(np.abs(x))
    hold = n // 6
    for start, level in ((n // 3, 0.6 * peak_m), (2 * n // 3, -0.6 * peak_m)):
        x[start : start + hold] = level
    return signal.filtfilt(*signal.butter(2, 20 * 2 * dt), x)  # rounded corners


@cache
def probes() -> tuple[tuple[Signals, ...], Scales]:
    """Two probe records (204.8 Hz for 20 s, 512 Hz for 6 s) and the scales of both."""
    records = (
        Signals(probe_motion(0, 20.0, 1 / 204.8), 1 / 204.8),
        Signals(probe_motion(1, 6.0, 1 / 512), 1 / 512),
    )
    return records, Scales.of(list(records))


def _shapes_to_check(effect: Effect, scales: Scales) -> list:
    grid = effect.shapes(scales)
    picks = [grid[0], grid[len(grid) // 2], grid[-1], effect.example(scales, K_N_PER_M)[0]]
    if len(grid) <= MAX_SHAPES:
        picks = grid + picks[3:]
    return list(dict.fromkeys(picks))


def _own_force(effect: Effect, s: Signals) -> np.ndarray:
    """The probe bushing's force without the effect (a backbone brings its own spring)."""
    return C_NS_PER_M * s.v if effect.replaces_spring else K_N_PER_M * s.x + C_NS_PER_M * s.v


def _fit(effect: Effect, s: Signals, y: np.ndarray, shape: Any, scales: Scales):
    """Spring, damper and the effect's weights at ``shape`` by bounded least squares, as the
    diagnosis fits them; returns (weights, residual RMS over the force RMS)."""
    spring = [s.v] if effect.replaces_spring else [s.x, s.v]
    a = np.column_stack([*spring, effect.columns(s, shape, scales)])
    target = shift_columns(y, -effect.delay_s(shape), s.dt)
    keep = slice(int(EDGE_S / s.dt), s.x.size - int(EDGE_S / s.dt))
    a, target = a[keep], target[keep]
    norm = np.linalg.norm(a, axis=0)
    norm[norm == 0] = 1.0
    lower = np.concatenate([np.zeros(len(spring)), effect.lower(shape, scales)]) * norm
    res = lsq_linear(a / norm, target, bounds=(lower, np.inf), method="bvls", tol=1e-14)
    w = res.x / norm
    misfit = float(np.sqrt(np.mean((target - a @ w) ** 2)) / np.sqrt(np.mean(target**2)))
    return w, misfit


# ----- the checks ------------------------------------------------------------------------------
def check_name_declared_once(name: str) -> None:
    cls = EFFECTS[name]
    problem = contract_problem(name, cls)
    assert problem is None, problem
    same = [n for n, c in EFFECTS.items() if c.name == cls.name]
    assert same == [name], f"{name}: the name is declared by {same}"
    assert get_effect(name).name == name, f"{name}: an instance answers {get_effect(name).name}"


def _assert_columns(where: str, cols: np.ndarray, samples: int, p: int) -> None:
    assert cols.ndim == 2 and cols.shape == (samples, p), (
        f"{where}: columns {cols.shape} on a record of {samples} samples; columns_count says {p}"
    )
    assert np.all(np.isfinite(cols)), f"{where}: columns not finite"


def check_columns_shape_and_finite(name: str) -> None:
    effect = get_effect(name)
    records, scales = probes()
    for shape in _shapes_to_check(effect, scales):
        p = effect.columns_count(shape, scales)
        for s in records:
            cols = effect.columns(s, shape, scales)
            _assert_columns(f"{name} at {shape!r}", cols, s.x.size, p)
            assert cols.dtype == np.float64, f"{name} at {shape!r}: columns are {cols.dtype}"
            if p:
                assert np.all(np.any(cols != 0, axis=0)), f"{name} at {shape!r}: a zero column"


def check_bounds_admissible(name: str) -> None:
    """The weights' lower bounds are declared, one per column; the example keeps them; the
    example's shape is one the search can reach and its delay is a causal lag."""
    effect = get_effect(name)
    _, scales = probes()
    shape, w = effect.example(scales, K_N_PER_M)
    for sh in _shapes_to_check(effect, scales):
        lower = np.asarray(effect.lower(sh, scales), dtype=float)
        p = effect.columns_count(sh, scales)
        assert lower.shape == (p,), f"{name} at {sh!r}: {lower.shape} bounds for {p} columns"
        assert not np.any(np.isnan(lower)) and np.all(lower < np.inf), f"{name}: bad bounds"
    lower = effect.lower(shape, scales)
    assert np.shape(w) == lower.shape, f"{name}: example has {np.shape(w)} weights"
    assert np.all(np.isfinite(w)) and np.all(w >= lower), f"{name}: example weights {w}"
    assert np.any(w != 0) or effect.delay_s(shape) > 0, f"{name}: the example adds nothing"
    grid = effect.shapes(scales)
    if effect.continuous_shape:
        family = effect.shape_family(shape)
        values = [effect.shape_value(g) for g in grid if effect.shape_family(g) == family]
        v = effect.shape_value(shape)
        assert values and min(values) <= v <= max(values), f"{name}: example {shape} off the grid"
    else:
        assert shape in grid, f"{name}: example shape {shape!r} is not among {grid}"
    d = effect.delay_s(shape)
    assert np.isfinite(d) and d >= 0, f"{name}: delay {d} s"


def check_other_forms(name: str) -> None:
    """The forms the diagnosis compares an effect in -- its richest form (``rich_columns``,
    bounded by ``rich_lower``), with a stiffness lost for good beside it and its per-record
    columns -- give finite columns of the count declared, one lower bound per column."""
    effect = get_effect(name)
    records, scales = probes()
    rich = effect.rich_shapes(scales)
    picks = list(dict.fromkeys([rich[0], rich[len(rich) // 2], rich[-1]])) if rich else []
    forms = [Richest(sh) for sh in picks]
    forms += [m(sh) for sh in _shapes_to_check(effect, scales) for m in (Lasting, Nuisance)]
    for form in forms:
        p = effect.columns_count(form, scales)
        for s in records:
            cols = effect.block_columns(s, form, scales)
            _assert_columns(f"{name} at {form!r}", cols, s.x.size, p)
        lower = np.asarray(effect.block_lower(form, scales), dtype=float)
        assert lower.shape == (p,), (
            f"{name} at {form!r}: {lower.shape} bounds for {p} columns (an effect whose "
            "rich_columns differ from its columns declares their bounds in rich_lower)"
        )
        assert not np.any(np.isnan(lower)) and np.all(lower < np.inf), f"{name}: bad bounds"


def check_forward_recovers_its_parameters(name: str) -> None:
    """The forward form's output, fitted back with the effect's own regressors, gives back the
    spring, damper and weights it was made with, and the example's shape fits best."""
    effect = get_effect(name)
    (s, _), scales = probes()
    shape, w = effect.example(scales, K_N_PER_M)
    y = effect.forward(s, _own_force(effect, s), shape, w, scales)
    assert y.shape == s.x.shape and np.all(np.isfinite(y)), f"{name}: forward {y.shape}"
    got, misfit = _fit(effect, s, y, shape, scales)
    want = np.concatenate([[C_NS_PER_M] if effect.replaces_spring else [K_N_PER_M, C_NS_PER_M], w])
    err = np.max(np.abs(got - want)) / np.max(np.abs(want))
    assert misfit < MISFIT_MAX, f"{name}: its regressors leave {misfit:.2e} of its own forward form"
    assert err < WEIGHT_RTOL, f"{name}: recovered {got}, made with {want} (error {err:.1e})"
    for other in effect.shapes(scales):
        if other != shape:
            assert _fit(effect, s, y, other, scales)[1] > misfit, (
                f"{name}: shape {other!r} fits its forward form at {shape!r} as well"
            )


def check_deterministic(name: str) -> None:
    """Same input, same output, bit for bit; no state carried from one record to the next."""
    (a, b), scales = probes()
    first = get_effect(name)
    shape, w = first.example(scales, K_N_PER_M)
    once = first.columns(a, shape, scales)
    first.columns(b, shape, scales)
    assert np.array_equal(once, first.columns(a, shape, scales)), f"{name}: columns changed"
    again = get_effect(name)
    assert np.array_equal(once, again.columns(a, shape, scales)), f"{name}: not deterministic"
    f1 = first.forward(a, _own_force(first, a), shape, w, scales)
    f2 = again.forward(a, _own_force(again, a), shape, w, scales)
    assert np.array_equal(f1, f2), f"{name}: forward not deterministic"
    assert again.example(scales, K_N_PER_M)[0] == shape, f"{name}: example not deterministic"


def check_report_is_plain(name: str) -> None:
    """``parameters`` and ``describe`` give what report.json and report.md can hold."""
    from bushenv.diagnose.report_files import json_safe

    effect = get_effect(name)
    _, scales = probes()
    shape, w = effect.example(scales, K_N_PER_M)
    params = effect.parameters(shape, scales, w)
    assert isinstance(params, dict), f"{name}: parameters gave {type(params).__name__}"
    json.dumps(json_safe(params), allow_nan=False)
    assert isinstance(effect.describe(shape), str), f"{name}: describe is not text"


CHECKS: dict[str, Check] = {
    "name_declared_once": check_name_declared_once,
    "columns_shape_and_finite": check_columns_shape_and_finite,
    "bounds_admissible": check_bounds_admissible,
    "other_forms": check_other_forms,
    "forward_recovers_its_parameters": check_forward_recovers_its_parameters,
    "deterministic": check_deterministic,
    "report_is_plain": check_report_is_plain,
}


def check_effect(name: str) -> None:
    """Every check on effect ``name``."""
    for check in CHECKS.values():
        check(name)
