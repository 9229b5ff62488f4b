"""The quarter car's verdict, whatever the arm bushing's number of coordinates C (two one-axis
bushings, radial and axial, or one bushing carrying axial, radial and the arm's rotation):
where the judge judges, the prefix of a model's own error, why sampled forces or a moment cannot
be applied, where the twin's bushing judges beyond its calibrated range, the physical bounds,
and an episode's end from both cars (``divergence.force_termination``)."""

from __future__ import annotations

import math

import numpy as np

from bushenv.divergence import force_termination
from bushenv.judge import Where

CAR = Where("QuarterCar-v0", reference_free=False, judges_static=False)  # for the judge

MODEL_ERROR_PREFIX = "model error: "  # a sample whose model raised (not a divergence)


def force_reason(fr: float, fa: float, limit_n: float) -> str:
    """Why a car's sampled bushing forces cannot be applied ("" if they can): the first axis
    whose force is not finite or beyond ``limit_n``."""
    for axis, f in (("radial", fr), ("axial", fa)):
        if not math.isfinite(f):
            return f"{axis} bushing force {f!r} N is not finite"
        if abs(f) > limit_n:
            return f"|{axis} bushing force| = {abs(f):.6g} N exceeds {limit_n:.6g} N"
    return ""


def moment_reason(moment_nm: float, limit_nm: float) -> str:
    """Why a sampled bushing moment cannot be applied ("" if it can)."""
    if not math.isfinite(moment_nm):
        return f"bushing moment {moment_nm!r} N m is not finite"
    if abs(moment_nm) > limit_nm:
        return f"|bushing moment| = {abs(moment_nm):.6g} N m exceeds {limit_nm:.6g} N m"
    return ""


def reference_range_reason(reference, theta: float) -> str:
    """Why the twin's arm bushing judges by extrapolation at rotation ``theta`` ("" if it does
    not): beyond the rotation its law is calibrated for (a reference's
    ``calibrated_rotation_rad``, when it states one)."""
    r = getattr(reference, "calibrated_rotation_rad", None)
    if r is not None and abs(theta) > r:
        return (
            f"the reference arm bushing's rotation {theta:+.3g} rad is beyond its calibrated "
            f"+-{r:g} rad: its forces there are an extrapolation"
        )
    return ""


def beyond_bounds(p, yc, yw, xr, xa):
    """Whether a car's state left its physical bounds: chassis and wheel heights ``yc``, ``yw``
    and bushing deflections ``xr``, ``xa`` (m; floats or (N,) arrays) not finite, a deflection
    beyond ``max_bushing_deflection_m``, travel beyond ``max_suspension_travel_m`` or a body
    beyond ``max_body_displacement_m``."""
    with np.errstate(invalid="ignore"):
        finite = np.isfinite(yc) & np.isfinite(yw) & np.isfinite(xr) & np.isfinite(xa)
        deflection = (np.abs(xr) > p.max_deflection) | (np.abs(xa) > p.max_deflection)
        travel = np.abs(yw - yc) > p.max_travel
        body = (np.abs(yc) > p.max_body) | (np.abs(yw) > p.max_body)
    return ~finite | deflection | travel | body


def car_verdict(p, forces_model, forces_reference, bounds_model, bounds_reference):
    """(terminated, truncated) of the model car beside its twin.

    ``forces_*``: (2,) or (2, N) radial and axial bushing forces, N (with an arm bushing that
    carries the rotation (3,) or (3, N), the moment last, N m, judged by
    ``arm_moment_limit_nm``); ``bounds_*``: the
    cars' ``beyond_bounds``. The force criteria are ``divergence.force_termination``'s (not
    finite, or beyond ``force_limit_n`` while the twin's is within); the twin beyond its own
    bounds or force limit truncates (the road is too harsh to judge), and that comes first."""
    limit = p.force_limit
    if len(forces_model) == 3:  # the rotation carried too: radial, axial, moment
        limit = np.array([p.force_limit, p.force_limit, p.moment_limit])
        limit = limit[:, None] if np.ndim(forces_model) == 2 else limit
    non_finite, model_over, reference_over = force_termination(
        forces_model, forces_reference, limit
    )
    twin_out = reference_over.any(axis=0) | bounds_reference
    model_out = non_finite.any(axis=0) | model_over.any(axis=0) | bounds_model
    return model_out & ~twin_out, twin_out


def out_of_bounds(p, yc, yw, xr, xa, fr, fa) -> str:
    """Why a car's state left its physical bounds ("" if it did not)."""
    values = (yc, yw, xr, xa, fr, fa)
    if not all(math.isfinite(v) for v in values):
        return "state or bushing force is not finite"
    if abs(fr) > p.force_limit or abs(fa) > p.force_limit:
        return f"|bushing force| = {max(abs(fr), abs(fa)):.6g} N exceeds {p.force_limit:.6g} N"
    if abs(xr) > p.max_deflection or abs(xa) > p.max_deflection:
        return (
            f"bushing deflection {max(abs(xr), abs(xa)) * 1e3:.4g} mm exceeds "
            f"{p.max_deflection * 1e3:.4g} mm"
        )
    if abs(yw - yc) > p.max_travel:
        return f"suspension travel {abs(yw - yc):.4g} m exceeds {p.max_travel:.4g} m"
    if abs(yc) > p.max_body or abs(yw) > p.max_body:
        return f"body displacement {max(abs(yc), abs(yw)):.4g} m exceeds {p.max_body:.4g} m"
    return ""
