"""The picture HalfCar-v0's ``render()`` draws: both cars from the front on their two roads.

Pure drawing on a ``drawing.Canvas`` from the cars' bodies; nothing here moves a body.
"""

from __future__ import annotations

import math
from typing import Any

from bushenv.rigs.drawing import Canvas
from bushenv.rigs.halfcar_params import POSITIONS, SIDES

SCALE_PX_PER_M = 300.0
ORIGIN_PX = (300.0, 330.0)  # the road at rest under the car's centre plane
RED, BLUE, ROAD = (200, 40, 40), (70, 110, 210), (205, 195, 170)


def _px(x: float, y: float) -> tuple[float, float]:
    return ORIGIN_PX[0] + SCALE_PX_PER_M * x, ORIGIN_PX[1] - SCALE_PX_PER_M * y


def _world(body, local) -> tuple[float, float]:
    w = body.local_to_world(local)
    return w.x, w.y


def draw_halfcar(c: Canvas, p: Any, car: Any, twin: Any, info: dict[str, Any]) -> None:
    """Roads, the reference twin (blue outline) and the model car (grey), and each pivot's
    bushing force of the model car (red bars, +-5 force_scale_n)."""
    c.clear()
    c.text(f"HalfCar-v0  model={p.model_name}  reference={p.reference_name}", (10, 8))
    c.text(
        f"t = {info.get('time_s', 0.0):6.3f} s   a_y = "
        f"{info.get('lateral_accel_m_per_s2', 0.0):+5.2f} m/s^2   roll = "
        f"{math.degrees(info.get('roll_rad', 0.0)):+6.3f} deg",
        (10, 28),
        small=True,
    )
    for side in SIDES:
        h = info.get(f"road_{side}_m", 0.0)
        x0 = 0.35 if side == "left" else -1.25
        a, b = _px(x0, h), _px(x0 + 0.9, h)
        c.polygon([a, b, (b[0], 400), (a[0], 400)], ROAD)
    for one, col, solid in ((twin, BLUE, False), (car, (40, 40, 40), True)):
        _draw_car(c, p, one, col, solid)
    fs = 5 * p.force_scale
    for i, k in enumerate(POSITIONS):
        f = math.hypot(info.get(f"force_{k}_axial_model_n", 0.0),
                       info.get(f"force_{k}_radial_model_n", 0.0))  # fmt: skip
        c.force_bar(10, 50 + 22 * i, 150, 10, f, fs, RED, f"|F| {k} (+-{fs / 1e3:.0f} kN)")


def _draw_car(c: Canvas, p: Any, car: Any, col, solid: bool) -> None:
    ch = car.chassis
    box = [(-0.45, -0.25), (0.45, -0.25), (0.45, 0.1), (-0.45, 0.1)]
    pts = [_px(*_world(ch, (x, y))) for x, y in box]
    if solid:
        c.polygon(pts, (215, 215, 210))
    c.polygon(pts, col, 2)
    for side in SIDES:
        corner = car.corners[side]
        u = corner["upright"]
        for arm in ("lower", "upper"):
            joint = corner[f"{arm}_joint"]
            inner = _world(corner[arm], _inner_local(car, corner[arm]))
            c.line(_px(*inner), _px(*_world(corner[arm], joint.anchor_a)), col, 4)
            c.line(_px(*_world(u, joint.anchor_b)), _px(*_world(u, (0.0, 0.0))), col, 3)
        coil = corner["coil"]
        c.line(_px(*_world(ch, coil.anchor_a)), _px(*_world(corner["lower"], coil.anchor_b)),
               (60, 150, 60), 3)  # fmt: skip
        c.circle(_px(*_world(u, (0.0, 0.0))), p.r_w * SCALE_PX_PER_M, col, 3)


def _inner_local(car: Any, arm: Any) -> tuple[float, float]:
    for pivot in car.pivots:
        if pivot["arm"] is arm:
            return pivot["anchor"]
    return (0.0, 0.0)
