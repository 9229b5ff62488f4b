"""Arithmetic-only ``|a| ** n`` (and its log/exp) that LLVM can vectorise inside numba loops.

``abs(z) ** n`` in a numba kernel is one libm ``pow`` call per element (~20 ns here, never
vectorised: numba's SVML path needs a patched LLVM that PyPI's llvmlite does not have). The
Bouc-Wen kernel evaluates it twice per right-hand side, so it dominated the kernel's time.
``pow_abs`` below is exp(n log a) with its own log and exp made of integer bit operations,
multiply/add and one divide -- no calls -- so a loop over profiles compiles to SIMD vectors.

Method. log: a = m 2^e with m in [sqrt(1/2), sqrt(2)) read from the IEEE bits (subnormals
rescaled first), log m = 2 atanh(s), s = (m - 1)/(m + 1), |s| <= 0.1716, as an odd series to
s^23 (truncation < 1e-18 relative), plus e ln2 with ln2 split in a 32-bit-exact high part and
a low part. exp: y = k ln2 + r, |r| <= ln2/2, degree-13 Taylor polynomial (truncation
< 5e-18), times 2^k built from bits in two halves (so results down to the subnormal range and
overflow to inf come out right).

Accuracy (``tests/models/test_fastpow.py``): ``log_pos`` within 2.5e-16 absolute for
log a in [-1, 1] and 2.5e-16 relative elsewhere; ``exp_`` within 4e-16 relative; ``pow_abs``
within (|n log a| + 4) * 2.3e-16 relative of libm's pow -- the error of y = n log a in
float64, which libm avoids with extra precision. For the Bouc-Wen kernel's range
(|z| >= 1e-12 m, n <= 3) that is below 2e-14.

Special values follow C99 ``pow(|a|, n)``: n == 0 gives 1 (even for NaN a); NaN a gives NaN;
a == 0 gives 0 for n > 0 and inf for n < 0; a == inf gives inf for n > 0 and 0 for n < 0;
NaN n gives NaN unless a == 1. Underflow goes to 0 (or a subnormal), overflow to inf.

Kernels that call it must be compiled with ``error_model="numpy"`` (see fastmath.py).
"""

from __future__ import annotations

import numba as nb
from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic

LN2_HI = 0.693147180369123816490  # 32 significant bits: e * LN2_HI is exact for |e| < 2^20
LN2_LO = 1.90821492927058770002e-10  # ln 2 - LN2_HI
LOG2E = 1.4426950408889634
SQRT2 = 1.4142135623730951
MANT_MASK = (1 << 52) - 1
ONE_BITS = 1023 << 52
TWO54 = 18014398509481984.0  # 2^54: rescales subnormals into the normal range
SMALLEST_NORMAL = 2.2250738585072014e-308
EXP_CLAMP_LO = -760.0  # exp below this is 0 in float64 (e^-745.2 is the smallest subnormal)
EXP_CLAMP_HI = 720.0  # exp above 709.8 overflows to inf
INF = float("inf")
FLT_MAX = 1.7976931348623157e308


@intrinsic
def _f64_bits(typingctx, x):
    """Reinterpret a float64's bits as int64 (LLVM bitcast; vectorises)."""
    if not isinstance(x, types.Float):
        return None
    sig = types.int64(types.float64)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return sig, codegen


@intrinsic
def _bits_f64(typingctx, i):
    """Reinterpret an int64's bits as float64 (LLVM bitcast; vectorises)."""
    if not isinstance(i, types.Integer):
        return None
    sig = types.float64(types.int64)

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return sig, codegen


@nb.njit(cache=True, inline="always", error_model="numpy")
def log_pos(a):  # pragma: no cover - compiled
    """Natural log of a finite a > 0 (no checks: 0, inf, NaN and negatives give garbage)."""
    sub = a < SMALLEST_NORMAL
    a = a * TWO54 if sub else a
    bits = _f64_bits(a)
    e = (bits >> 52) - 1023
    m = _bits_f64((bits & MANT_MASK) | ONE_BITS)  # [1, 2)
    big = m > SQRT2
    m = 0.5 * m if big else m
    e = e + 1 if big else e
    ef = float(e) - (54.0 if sub else 0.0)
    f = m - 1.0
    s = f / (2.0 + f)
    s2 = s * s
    # q = sum_k s2^k / (2k + 3), k = 0..10, by Estrin's scheme (short dependency chains)
    s4 = s2 * s2
    s8 = s4 * s4
    q01 = 1.0 / 3.0 + s2 * (1.0 / 5.0)
    q23 = 1.0 / 7.0 + s2 * (1.0 / 9.0)
    q45 = 1.0 / 11.0 + s2 * (1.0 / 13.0)
    q67 = 1.0 / 15.0 + s2 * (1.0 / 17.0)
    q89 = 1.0 / 19.0 + s2 * (1.0 / 21.0)
    q = (q01 + s4 * q23) + s8 * ((q45 + s4 * q67) + s8 * (q89 + s4 * (1.0 / 23.0)))
    # 2 atanh(s) = 2 s + 2 s^3 q; f - f s = 2 s exactly-ish: write 2 s = f - s f to keep the
    # leading term's rounding small
    log_m = (f - s * f) + 2.0 * s * s2 * q
    return ef * LN2_HI + (ef * LN2_LO + log_m)


@nb.njit(cache=True, inline="always", error_model="numpy")
def exp_(y):  # pragma: no cover - compiled
    """e^y for finite y (clamped: 0 below -760, inf above 720; NaN gives garbage)."""
    y = EXP_CLAMP_LO if y < EXP_CLAMP_LO else y
    y = EXP_CLAMP_HI if y > EXP_CLAMP_HI else y
    kf = y * LOG2E
    kf = kf + 0.5 if kf >= 0.0 else kf - 0.5
    k = int(kf)  # round half away from zero; |k| <= 1097
    r = (y - float(k) * LN2_HI) - float(k) * LN2_LO
    # degree-13 Taylor polynomial: 1 + r + r^2 Q(r), Q by Estrin's scheme (short chains)
    r2 = r * r
    r4 = r2 * r2
    r8 = r4 * r4
    e23 = 0.5 + r * (1.0 / 6.0)
    e45 = 1.0 / 24.0 + r * (1.0 / 120.0)
    e67 = 1.0 / 720.0 + r * (1.0 / 5040.0)
    e89 = 1.0 / 40320.0 + r * (1.0 / 362880.0)
    eab = 1.0 / 3628800.0 + r * (1.0 / 39916800.0)
    ecd = 1.0 / 479001600.0 + r * (1.0 / 6227020800.0)
    q = (e23 + r2 * e45) + r4 * (e67 + r2 * e89) + r8 * (eab + r2 * ecd)
    p = 1.0 + (r + r2 * q)
    k1 = k >> 1
    k2 = k - k1
    s1 = _bits_f64((k1 + 1023) << 52)
    s2 = _bits_f64((k2 + 1023) << 52)
    return (p * s1) * s2


@nb.njit(cache=True, inline="always", error_model="numpy")
def pow_abs(a, n):  # pragma: no cover - compiled
    """|a| ** n with C99 pow's special values (see the module docstring)."""
    aa = abs(a)
    ok = aa > 0.0 and aa <= FLT_MAX  # finite and nonzero (NaN fails both)
    safe = aa if ok else 1.0
    r = exp_(n * log_pos(safe))
    zero_or_inf = (0.0 if n > 0.0 else (INF if n < 0.0 else n)) if aa == 0.0 else r
    r = zero_or_inf if aa == 0.0 else r
    r = (INF if n > 0.0 else (0.0 if n < 0.0 else n)) if aa > FLT_MAX else r
    r = (aa + n) if aa != aa else r  # NaN a -> NaN
    r = (n + 0.0 * aa) if n != n else r  # NaN n -> NaN (aa NaN or not)
    r = 1.0 if aa == 1.0 else r
    r = 1.0 if n == 0.0 else r
    return r
