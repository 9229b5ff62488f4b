"""``HalfCarBatch``'s sub-steps compiled for its one element table: the scheme of
``halfcar_batch_kernels`` (its docstring), written out element by element from the layout's
kinds and bodies, so that one loop over cars holds a car's whole sub-step.

Why generated: with every row of the chunk's array a constant, the compiler knows that no two
rows overlap and vectorises the loop over cars with no run-time overlap checks; and a loop that
carries a car through every element keeps the bodies' velocities in registers through a whole
damper sweep, where a loop per element reads and writes them from memory once per element. The
arithmetic per car is the scheme's, operation for operation and in its order, with no term
fused or reordered (the same numbers, bit for bit, a car alone or in any batch, any vector
width). The source depends only on the element table's integers
(kinds, bodies, sides, which bodies move), the sweeps and the chunk width; it is written once
to the generated kernels' folder (``narx_kernels.cache_dir``), so that numba's cache keeps the
compiled code between runs (the first use compiles for some seconds).
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

import llvmlite.binding as llvm
import numpy as np
from numba import types
from numba.core.compiler_lock import global_compiler_lock

from bushenv.models.narx_kernels import cache_dir
from bushenv.persist import write_text
from bushenv.rigs.halfcar_batch_kernels import (
    ANG,
    COS,
    LATERAL,
    N_ROWS,
    PX,
    PY,
    ROTARY,
    SIN,
    SPRING,
    TYRE,
    VX,
    VY,
    W,
)

WIDTH = 8  # cars per chunk: a chunk's rows stay in L1; the loop over cars is one vector
N_SCRATCH = 7  # per element: nx, ny, c1, c2, 1 / k, v_coef, the damper's target velocity
_KERNELS: dict[str, Any] = {}
_F, _I = types.float64, types.int64
SIGNATURE = types.none(
    types.Array(_F, 3, "C"), *[types.Array(_F, 2, "C")] * 4, *[types.Array(_F, 1, "C")] * 2, _I,
    types.Array(_F, 2, "C"), *[types.Array(_F, 1, "C")] * 2, *[_F] * 5, _I, _I,
)  # fmt: skip


def _rows(n_body: int, n_el: int) -> dict[str, int]:
    o_h = N_ROWS * n_body
    o_par = o_h + 4  # the step, the load, the two contacts; then rest, stiffness, damping
    return {"h": o_h, "g": o_h + 1, "ct": o_h + 2, "par": o_par, "sc": o_par + 3 * n_el,
            "end": o_par + 3 * n_el + N_SCRATCH * n_el}  # fmt: skip


def _impulse(a: int, b: int) -> list[str]:
    """The lines that apply impulse j along (nx, ny) between bodies a and b (lever arms c1,
    c2; inverse masses ma, inverse inertias ja)."""
    return [
        f"vx{a} -= j * nx * ma{a}",
        f"vy{a} -= j * ny * ma{a}",
        f"w{a} -= j * c1 * ja{a}",
        f"vx{b} += j * nx * ma{b}",
        f"vy{b} += j * ny * ma{b}",
        f"w{b} += j * c2 * ja{b}",
    ]


def kernel_source(kind, ia, ib, side, moving, iterations: int, width: int = WIDTH) -> str:
    """The numba source of the sub-step kernel for one element table (``Layout``'s ``kind``,
    ``ia``, ``ib``, ``side``; ``moving`` (bodies,) bool: the bodies the lateral load moves)."""
    kind, ia, ib, side = (np.asarray(x, dtype=np.int64) for x in (kind, ia, ib, side))
    n_el, n_body = len(kind), len(moving)
    o = _rows(n_body, n_el)

    def at(row: int) -> str:  # row ``row`` of the chunk, car i
        return f"L[{row * width} + i]"

    def st(r: int, k: int) -> str:
        return at(r * n_body + k)

    def par(e: int, r: int) -> str:
        return at(o["par"] + 3 * e + r)

    def sc(e: int, r: int) -> str:
        return at(o["sc"] + N_SCRATCH * e + r)

    head, pre, sweep = [], [], []
    for k in range(n_body):
        head.append(f"    ma{k} = m_inv[{k}]; ja{k} = i_inv[{k}]")
    landed: set[int] = set()
    for e in range(n_el):
        a, b, kd = int(ia[e]), int(ib[e]), int(kind[e])
        if kd == ROTARY:
            head.append(f"    moment{e} = ja{a} + ja{b}; nmass{e} = 1.0 / moment{e}")
            pre += [
                f"{sc(e, 5)} = 1.0 - 1.0 / (1.0 + {par(e, 2)} * h * moment{e})",
                f"{sc(e, 6)} = 0.0",
                f"j = ((ang{a} - ang{b}) - {par(e, 0)}) * {par(e, 1)} * h",
                f"w{a} -= j * ja{a}",
                f"w{b} += j * ja{b}",
            ]  # fmt: skip
            sweep += [
                f"wr = w{a} - w{b}",
                f"wd = ({sc(e, 6)} - wr) * {sc(e, 5)}",
                f"{sc(e, 6)} = wr + wd",
                f"j = wd * nmass{e}",
                f"w{a} += j * ja{a}",
                f"w{b} -= j * ja{b}",
            ]  # fmt: skip
            continue
        head.append(f"    ax{e}, ay{e}, bx{e}, by{e} = anchors[{e}, 0], anchors[{e}, 1], "
                    f"anchors[{e}, 2], anchors[{e}, 3]")  # fmt: skip
        pre += [
            f"r1x = co{a} * ax{e} - si{a} * ay{e}",
            f"r1y = si{a} * ax{e} + co{a} * ay{e}",
            f"r2x = co{b} * bx{e} - si{b} * by{e}",
            f"r2y = si{b} * bx{e} + co{b} * by{e}",
            f"dx = (px{b} + r2x) - (px{a} + r1x)",
            f"dy = (py{b} + r2y) - (py{a} + r1y)",
            "dist = math.sqrt(dx * dx + dy * dy)",
            "inv = 0.0 if dist == 0.0 else 1.0 / dist",
            "nx, ny = dx * inv, dy * inv",
            "c1 = r1x * ny - r1y * nx",
            "c2 = r2x * ny - r2y * nx",
            f"k = ma{a} + ma{b} + c1 * c1 * ja{a} + c2 * c2 * ja{b}",
        ]  # fmt: skip
        s = int(side[e])
        if kd == SPRING:
            pre += [f"f = ({par(e, 0)} - dist) * {par(e, 1)}",
                    f"vcoef = 1.0 - 1.0 / (1.0 + {par(e, 2)} * h * k)"]  # fmt: skip
        elif kd == TYRE:
            pre += [
                f"was = ct{s}",
                f"f = k_tyre * ({par(e, 0)} - dist)",
                "now = 1.0 if f > lift else 0.0",
                f"landed{s} = 1.0 if now > was else 0.0",
                f"ct{s} = now",
                "f = f if now > 0.0 else lift",
                "x = c_tyre * was * h * k",
            ]  # fmt: skip
            landed.add(s)
        elif kd == LATERAL:
            if s not in landed:
                raise ValueError(f"element {e}: a lateral tyre before its tyre (side {s})")
            pre += [
                f"on = ct{s}",
                f"r0 = abs(dx) if landed{s} > 0.0 else {par(e, 0)}",
                f"{par(e, 0)} = r0",
                "f = (r0 - dist) * k_lat * on",
                "x = c_lat * on * h * k",
            ]  # fmt: skip
        else:
            raise ValueError(f"element {e}: unknown kind {kd}")
        if kd in (TYRE, LATERAL):  # 1 - exp(-x): halfcar_batch_kernels' polynomial
            pre.append("vcoef = x * (1.0 - x * (0.5 - x * (1.0 / 6 - x * (1.0 / 24 - x * "
                       "(1.0 / 120 - x / 720)))))")  # fmt: skip
        pre += [
            "j = f * h",
            f"{sc(e, 0)}, {sc(e, 1)}, {sc(e, 2)}, {sc(e, 3)} = nx, ny, c1, c2",
            f"{sc(e, 4)} = 1.0 / k",
            f"{sc(e, 5)} = vcoef",
            f"{sc(e, 6)} = 0.0",
            *_impulse(a, b),
        ]  # fmt: skip
        sweep += [
            f"nx, ny, c1, c2 = {sc(e, 0)}, {sc(e, 1)}, {sc(e, 2)}, {sc(e, 3)}",
            f"vrn = (vx{b} - vx{a}) * nx + (vy{b} - vy{a}) * ny",
            f"vrn += w{b} * c2 - w{a} * c1",
            f"vd = ({sc(e, 6)} - vrn) * {sc(e, 5)}",
            f"{sc(e, 6)} = vrn + vd",
            f"j = vd * {sc(e, 4)}",
            *_impulse(a, b),
        ]  # fmt: skip
    sides = sorted(landed)
    velocities = [(f"{n}{k}", st(r, k)) for k in range(n_body)
                  for n, r in (("vx", VX), ("vy", VY), ("w", W))]  # fmt: skip
    load_v = [f"{name} = {ref}" for name, ref in velocities]
    store_v = [f"{ref} = {name}" for name, ref in velocities]
    step = [f"h = {at(o['h'])}"] + load_v + [f"ct{s} = {at(o['ct'] + s)}" for s in sides]
    for k in range(n_body):  # positions; the rotation's cos, sin by their Taylor series
        step += [
            f"px{k} = {st(PX, k)} + h * vx{k}",
            f"py{k} = {st(PY, k)} + h * vy{k}",
            f"x = h * w{k}",
            f"ang{k} = {st(ANG, k)} + x",
            "x2 = x * x",
            "cw = 1.0 - x2 * (0.5 - x2 * (1.0 / 24 - x2 / 720))",
            "sw = x * (1.0 - x2 * (1.0 / 6 - x2 * (1.0 / 120 - x2 / 5040)))",
            f"c, s = {st(COS, k)}, {st(SIN, k)}",
            f"co{k} = c * cw - s * sw",
            f"si{k} = s * cw + c * sw",
            f"{st(PX, k)}, {st(PY, k)}, {st(ANG, k)} = px{k}, py{k}, ang{k}",
            f"{st(COS, k)}, {st(SIN, k)} = co{k}, si{k}",
        ]  # fmt: skip
    step += pre
    step += [f"vx{k} += {at(o['g'])} * h" for k in range(n_body) if moving[k]]
    step += store_v + [f"{at(o['ct'] + s)} = ct{s}" for s in sides]
    sweep = load_v + sweep + store_v
    body = "\n".join(
        [
            f"# compiled with one vector of {width} cars per row (halfcar_batch_lanes)",
            "import math",
            "import numba as nb",
            "import numpy as np",
            "",
            "",
            '@nb.njit(cache=True, nogil=True, error_model="numpy")',
            "def kernel(S, rest, stiff, damp, contact, gx, h_car, n_sub, anchors, m_inv, i_inv,",
            "           k_tyre, lift, c_tyre, k_lat, c_lat, b_lo, b_hi):  # pragma: no cover",
            *head,
            f"    L = np.empty({o['end'] * width})",
            f"    for i in range({o['end'] * width}):  # np.zeros warns when forced",
            "        L[i] = 0.0",
            "    n = b_hi",
            f"    for b0 in range(b_lo, n, {width}):",
            f"        for i in range({width}):",
            "            b = b0 + i if b0 + i < n else b0",
            f"            L[{o['h'] * width} + i] = h_car[b] if b0 + i < n else 0.0",
            f"            L[{o['g'] * width} + i] = gx[b]",
            *(f"            L[{(o['ct'] + s) * width} + i] = contact[{s}, b]" for s in sides),
            f"            for r in range({N_ROWS}):",
            f"                for k in range({n_body}):",
            f"                    L[(r * {n_body} + k) * {width} + i] = S[r, k, b]",
            f"            for e in range({n_el}):",
            f"                L[({o['par']} + 3 * e) * {width} + i] = rest[e, b]",
            f"                L[({o['par']} + 3 * e + 1) * {width} + i] = stiff[e, b]",
            f"                L[({o['par']} + 3 * e + 2) * {width} + i] = damp[e, b]",
            "        for _ in range(n_sub):",
            f"            for i in range({width}):",
            *("                " + line for line in step),
            f"            for _it in range({iterations}):",
            f"                for i in range({width}):",
            *("                    " + line for line in sweep),
            f"        for i in range(min({width}, n - b0)):",
            "            b = b0 + i",
            *(f"            contact[{s}, b] = L[{(o['ct'] + s) * width} + i]" for s in sides),
            f"            for r in range({N_ROWS}):",
            f"                for k in range({n_body}):",
            f"                    S[r, k, b] = L[(r * {n_body} + k) * {width} + i]",
            f"            for e in range({n_el}):",
            f"                rest[e, b] = L[({o['par']} + 3 * e) * {width} + i]",
            "",
        ]
    )  # fmt: skip
    return body


def lanes_kernel(kind, ia, ib, side, moving, iterations: int, width: int = WIDTH):
    """The compiled kernel of ``kernel_source`` (one per distinct source in a process):
    ``kernel(S, rest, stiff, damp, contact, gx, h_car, n_sub, anchors, m_inv, i_inv, k_tyre,
    lift, c_tyre, k_lat, c_lat, b_lo, b_hi)``: advance the cars ``b_lo`` to ``b_hi - 1``
    (columns of ``S``; the others untouched, so two threads may step two ranges) by ``n_sub``
    sub-steps of ``h_car`` (N,) s (0 holds a car still); the arrays as ``HalfCarBatch`` holds
    them (``Layout``'s ``anchors``, ``m_inv``, ``i_inv``; the tyres' law in the scalars)."""
    source = kernel_source(kind, ia, ib, side, moving, iterations, width)
    key = hashlib.sha256(source.encode()).hexdigest()[:16]
    if key in _KERNELS:
        return _KERNELS[key]
    name = f"halfcar_lanes_{key}"
    path = _place(name, source)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # numba's cache finds the kernel's globals by module name
    spec.loader.exec_module(module)
    kernel = module.kernel
    # one vector of ``width`` cars per row: the compiler's cost model picks half of that on
    # AVX-512 machines, twice the instructions for the same numbers. The option is LLVM's,
    # process-wide, so it is set only while this kernel compiles (under numba's lock: no other
    # function compiles meanwhile); a cached kernel loads as it was compiled
    with global_compiler_lock:
        llvm.set_option("", f"-force-vector-width={width}")
        try:
            kernel.compile(SIGNATURE)
        finally:
            llvm.set_option("", "-force-vector-width=0")
    kernel.disable_compile()  # other argument types would compile without the option
    _KERNELS[key] = kernel
    return kernel


def _place(name: str, source: str) -> Path:
    """``source`` as ``name``.py in the generated kernels' folder (``narx_kernels.cache_dir``;
    a per-user temporary folder if that cannot be written), written only when absent or
    different, so that numba's cache (keyed by the file's time) stays valid."""
    user = getattr(os, "getuid", lambda: "user")()
    for folder in (cache_dir(), Path(tempfile.gettempdir()) / f"bushenv-kernels-{user}"):
        path = folder / f"{name}.py"
        try:
            if path.is_file() and path.read_text() == source:
                return path
            return write_text(path, source)  # atomic: another process may write it too
        except OSError:
            continue
    raise OSError(f"cannot write the half car kernel {name}.py in {cache_dir()} nor a temp folder")
