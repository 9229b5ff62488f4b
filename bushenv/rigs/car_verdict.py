"""What the quarter car's verdict shares between its one-axis and three-axis arm bushings:
where the judge judges, the prefix of a model's own error, and why sampled forces cannot be
applied."""

from __future__ import annotations

import math

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
