"""The pictures ``render()`` draws: the bushing test rig and the quarter car with its twin.

Pure drawing on a ``drawing.Canvas`` from the state an env passes in; nothing here moves a body.
"""

from __future__ import annotations

import math
from typing import Any

from bushenv.rigs.drawing import Canvas, Trace, plot_traces

RED, BLUE, GREEN, GREY = (200, 40, 40), (40, 70, 200), (60, 150, 60), (120, 120, 120)


# ----- BushRig-v0 --------------------------------------------------------------------------------
def draw_bushrig(c: Canvas, p: Any, title: str, t_s: float, last, trace: Trace | None) -> None:
    """The rig at displacement ``last[0]`` (m) with forces ``last[1:]`` (model, reference, N)
    of its first coordinate (``p.axis``).

    ``p`` is the rig's ``RigParameters``; the stroke +-x_max spans +-60 px (the inner sleeve's
    motion is exaggerated)."""
    x, f_m, f_r = last
    x_max, force_scale = float(p.max_x[0]), float(p.force_scale[0])
    c.clear()
    c.text(f"{title}  axis={p.axis}  model={p.model_name}  reference={p.reference_name}", (10, 8))
    c.text(f"t = {t_s:6.3f} s   x = {x * 1e3:+7.3f} mm", (10, 28), small=True)
    y, xc = 130.0, 150.0
    _draw_rig_hardware(c, y, xc, xc + x * 60.0 / x_max)
    # force arrows on the load cell (the force the bushing puts on the ground)
    scale = 50.0 / force_scale
    for f, col, dy in ((f_m, RED, -6), (f_r, BLUE, 6)):
        if math.isfinite(f):
            fx = max(-100.0, min(100.0, f * scale))
            c.arrow((56, y + dy), (56 + fx, y + dy), col, 3)
    fs = 2 * force_scale  # bars and traces span +-2 force_scale_n
    c.force_bar(330, 70, 250, 16, f_m, fs, RED, f"F model (+-{fs / 1e3:.1f} kN)")
    c.force_bar(330, 110, 250, 16, f_r, fs, BLUE, "F reference")
    c.force_bar(330, 150, 250, 16, x, x_max, GREEN, "displacement")
    c.text(f"{f_m / 1e3:+8.3f} kN", (500, 52), RED, small=True)
    c.text(f"{f_r / 1e3:+8.3f} kN", (500, 92), BLUE, small=True)
    if trace is not None:
        colors, labels = (GREEN, RED, BLUE), ("x / x_max", "F model", "F reference")
        plot_traces(c, (20, 230, 560, 150), trace, (x_max, fs, fs), colors, labels)


def _draw_rig_hardware(c: Canvas, y: float, xc: float, bushing_x: float) -> None:
    """Ground wall, load cell, bushing (inner sleeve at ``bushing_x`` px), actuator, groove."""
    c.rect(20, y - 60, 16, 120, GREY)
    for k in range(8):
        c.line((20, y - 60 + 15 * k), (8, y - 48 + 15 * k), GREY, 2)
    c.rect(36, y - 22, 40, 44, (70, 110, 160))
    c.text("load cell", (30, y + 26), small=True)
    c.line((76, y), (xc - 36, y), (60, 60, 60), 6)
    c.rect(xc - 36, y - 36, 72, 72, (40, 40, 40), 4)
    c.rect(xc - 32, y - 32, 64, 64, (60, 60, 60))
    c.rect(bushing_x - 14, y - 14, 28, 28, (200, 200, 200))
    c.line((bushing_x, y), (bushing_x + 150, y), (90, 90, 90), 8)
    c.rect(bushing_x + 150, y - 26, 70, 52, (190, 140, 60))
    c.line((xc + 150 - 60, y + 40), (xc + 150 + 140, y + 40), GREY, 3)
    c.text("actuator on groove", (xc + 150, y + 46), small=True)
    for sgn in (-1, 1):  # stroke marks: where the inner sleeve sits at x = -+x_max
        c.line((xc + sgn * 60, y - 48), (xc + sgn * 60, y - 40), (200, 0, 0), 2)
    c.text("stroke", (xc - 18, y - 62), (200, 0, 0), small=True)


# ----- QuarterCar-v0 -----------------------------------------------------------------------------
QC_SCALE_PX_PER_M = 260.0
QC_ORIGIN_PX = (90.0, 215.0)  # the bushing centre at ride height


def _to_px(x: float, y: float) -> tuple[float, float]:
    return QC_ORIGIN_PX[0] + QC_SCALE_PX_PER_M * x, QC_ORIGIN_PX[1] - QC_SCALE_PX_PER_M * y


def draw_quartercar(c: Canvas, p: Any, title: str, state: dict[str, Any]) -> None:
    """Both cars on the road. ``state``: ``t_s``, ``road_m``, ``info`` (the last step's),
    ``trace`` (or None), ``car`` and ``twin`` (``car.Car`` objects); ``p``: ``CarParameters``."""
    info = state["info"]
    c.clear()
    c.text(f"{title}  model={p.model_name}  reference={p.reference_name}", (10, 8))
    c.text(
        f"t = {state['t_s']:6.3f} s   road = {state['road_m'] * 1e3:+7.1f} mm   "
        f"chassis = {info.get('chassis_y_m', 0.0) * 1e3:+7.2f} mm",
        (10, 28),
        small=True,
    )
    _draw_road(c, p, state["road_m"], state["trace"])
    _draw_car(c, p, state["twin"], False, (70, 110, 210))
    _draw_car(c, p, state["car"], True, (40, 40, 40))
    _draw_bushing_forces(c, p, state["car"].chassis.position.y, info)
    c.text("model car (grey), reference car (blue)", (10, 48), small=True)
    fs = 5 * p.force_scale
    bars = (
        ("force_radial_model_n", RED, f"radial F, model car (+-{fs / 1e3:.0f} kN)"),
        ("force_radial_reference_n", BLUE, "radial F, reference car"),
        ("force_axial_model_n", RED, "axial F, model car"),
        ("force_axial_reference_n", BLUE, "axial F, reference car"),
    )
    for i, (key, col, label) in enumerate(bars):
        c.force_bar(330, 60 + 35 * i, 250, 14, info.get(key, 0.0), fs, col, label)
    if state["trace"] is not None:
        plot_traces(
            c,
            (330, 215, 250, 150),
            state["trace"],
            (p.max_road, fs, fs),
            ((90, 70, 40), RED, BLUE),
            ("road", "F radial model", "reference"),
        )


def _draw_road(c: Canvas, p: Any, road_m: float, trace: Trace | None) -> None:
    """Past road heights left of the contact point (2 px per step), filled below."""
    r_px = p.r_w * QC_SCALE_PX_PER_M
    x_w = _to_px(p.L, 0.0)[0]
    hist = [road_m]
    if trace is not None and trace.count > 0:
        hist = list(trace.ordered()[0][-120:])
    pts = [
        (x_w - 2 * (len(hist) - 1 - i), QC_ORIGIN_PX[1] - QC_SCALE_PX_PER_M * hv + r_px)
        for i, hv in enumerate(hist)
    ]
    pts = [(0.0, pts[0][1])] + pts + [(320.0, pts[-1][1]), (320.0, 400.0), (0.0, 400.0)]
    c.polygon(pts, (205, 195, 170))


def _draw_car(c: Canvas, p: Any, car: Any, solid: bool, col) -> None:
    """Body, coil-over tower, arm, spring, wheel and bushing (inner sleeve offset 10x)."""
    cy = car.chassis.position.y
    tl, br = _to_px(-0.3, cy + p.H + 0.08), _to_px(0.05, cy + 0.06)
    if solid:
        c.rect(tl[0], tl[1], br[0] - tl[0], br[1] - tl[1], (215, 215, 210))
    c.rect(tl[0], tl[1], br[0] - tl[0], br[1] - tl[1], col, 2)
    c.line(_to_px(0.05, cy + p.H), _to_px(p.mount * p.L + 0.03, cy + p.H), col, 5)
    c.line(_to_px(0.0, cy + 0.06), _to_px(0.0, cy), col, 3)  # bushing bracket
    inner = car.unsprung.local_to_world(car.arm_inner)
    outer = car.unsprung.local_to_world(car.wheel_centre)
    mount = car.unsprung.local_to_world(car.arm_mount)
    c.line(_to_px(inner.x, inner.y), _to_px(outer.x, outer.y), col, 6 if solid else 2)
    top, bot = _to_px(p.mount * p.L, cy + p.H), _to_px(mount.x, mount.y)
    zig = [
        (top[0] + (7 if k % 2 else -7) * (0 < k < 11), top[1] + (bot[1] - top[1]) * k / 11)
        for k in range(12)
    ]
    c.lines(zig, col, 2)
    w = _to_px(outer.x, outer.y)
    r_px = p.r_w * QC_SCALE_PX_PER_M
    c.circle(w, r_px, col, 12 if solid else 2)  # the tyre, open so the coil shows
    if solid:
        c.circle(w, r_px * 0.5, (160, 160, 160), 4)
        c.circle(w, 5, col)
    b = _to_px(0.0, cy)
    c.circle(b, 14, col, 3)
    dx, dy = inner.x, inner.y - cy
    c.circle((b[0] + 10 * QC_SCALE_PX_PER_M * dx, b[1] - 10 * QC_SCALE_PX_PER_M * dy), 5, col)


def _draw_bushing_forces(c: Canvas, p: Any, chassis_y_m: float, info: dict[str, Any]) -> None:
    """Bushing forces on the arm as arrows (model red, reference blue), force_scale -> 60 px."""
    b = _to_px(0.0, chassis_y_m)
    k = 60.0 / p.force_scale
    for side, col in (("model", RED), ("reference", BLUE)):
        fr = info.get(f"force_radial_{side}_n", 0.0)
        fa = info.get(f"force_axial_{side}_n", 0.0)
        if math.isfinite(fr) and math.isfinite(fa):
            dx = max(-90.0, min(90.0, -k * fa))
            dy = max(-90.0, min(90.0, k * fr))
            c.arrow(b, (b[0] + dx, b[1] + dy), col, 3)
