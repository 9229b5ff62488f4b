"""The arithmetic of one ``BushRig3-v0`` step around the two models, compiled.

A step of the single env is a handful of (1, 3) arrays: as numpy calls that is ~25 calls of
~1 us each, ten times the two models. These two kernels do the same per column, once.
"""

from __future__ import annotations

import numba as nb

from bushenv.models.kernels import JIT


@nb.njit(**JIT)
def rig3_motion(action, q, rate_dt, limit, dt, q1, v1):  # pragma: no cover - compiled
    """q <- clip(q + clip(a, -1, 1) rate dt, -limit, limit) (NaN action as 0); q1[0] = the new
    q, v1[0] = (new q - old q) / dt. ``action``, ``q`` (B, 3); ``q1``, ``v1`` (1, B, 3)."""
    B = q.shape[0]
    for b in range(B):
        for i in range(3):
            a = action[b, i]
            a = 0.0 if a != a else min(max(a, -1.0), 1.0)
            x = min(max(q[b, i] + a * rate_dt[i], -limit[i]), limit[i])
            v1[0, b, i] = (x - q[b, i]) / dt
            q1[0, b, i] = x
            q[b, i] = x


@nb.njit(**JIT)
def rig3_outcome(
    q, fm, fr, limit, force_limit, force_scale, cap, obs, reward
):  # pragma: no cover - compiled
    """Reward min(sum_i |fm_i - fr_i| / force_scale_i, cap) (NaN as the cap), the observation
    history shifted by one and the newest column q / limit, fm / force_limit, fr / force_limit
    clipped to [-1, 1] (NaN as 0). Returns whether every force of every column is finite and
    within its limit (then no episode ends on force; else the caller asks
    ``divergence.force_termination``). ``obs`` (B, 3, 3, H) float32."""
    B = q.shape[0]
    H = obs.shape[3]
    calm = True
    for b in range(B):
        total = 0.0
        for i in range(3):
            m, r = fm[b, i], fr[b, i]
            total += abs(m - r) / force_scale[i]
            if not (abs(m) <= force_limit[i] and abs(r) <= force_limit[i]):
                calm = False
            for j in range(3):
                for h in range(H - 1, 0, -1):
                    obs[b, j, i, h] = obs[b, j, i, h - 1]
            for j, val in enumerate((q[b, i] / limit[i], m / force_limit[i], r / force_limit[i])):
                obs[b, j, i, 0] = 0.0 if val != val else min(max(val, -1.0), 1.0)
        reward[b] = cap if total != total else min(total, cap)
    return calm
