"""``HalfCarBatch``'s tables: the pymunk half car (``halfcar_car.HalfCar``) read into arrays for
``halfcar_batch_kernels``, so the batch steps the very bodies, anchors, rest lengths and
element order the env builds (nothing of the geometry is written twice)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pymunk

from bushenv.rigs.halfcar_batch_kernels import (
    ANG,
    COS,
    LATERAL,
    PX,
    PY,
    ROTARY,
    SIN,
    SPRING,
    TYRE,
    VX,
    VY,
    W,
    zero_state,
)
from bushenv.rigs.halfcar_car import HalfCar
from bushenv.rigs.halfcar_params import SIDES, HalfCarParameters

# the state's body columns; the kernel's bushing motion reads body 0 as the chassis
BODIES = ("chassis",) + tuple(
    f"{part}_{side}" for side in SIDES for part in ("lower", "upper", "upright", "road")
)
COORDS = ("axial", "radial", "rotation")
UPRIGHT = {side: BODIES.index(f"upright_{side}") for side in SIDES}
ROAD = {side: BODIES.index(f"road_{side}") for side in SIDES}


@dataclass
class Layout:
    """One car role's element table (E elements in the pymunk space's order) and the bodies'
    inverse masses and rest state."""

    kind: np.ndarray  # (E,) SPRING, ROTARY, TYRE or LATERAL
    ia: np.ndarray  # (E,) body indices in BODIES
    ib: np.ndarray
    side: np.ndarray  # (E,) 0 left, 1 right for the tyres, else 0
    anchors: np.ndarray  # (E, 4) local anchors a, b (m)
    rest: np.ndarray  # (E,) rest length m (rest angle rad) at design, nothing held
    stiff: np.ndarray  # (E,) N/m, N m/rad
    damp: np.ndarray  # (E,) physical damping N s/m, N m s/rad (implicit Euler in the kernel)
    m_inv: np.ndarray  # (9,) 1/kg, 0 for the kinematic roads
    i_inv: np.ndarray  # (9,) 1/(kg m^2)
    state: np.ndarray  # (8, 9) the rest state of one car
    bushing_rows: np.ndarray  # (4, 3) element of each pivot's axial, radial, rotation spring
    pivot_arm: np.ndarray  # (4,) the arm's body index
    pivot_sign: np.ndarray  # (4,) +1 left, -1 right
    pivot_anchor_arm: np.ndarray  # (4, 2) the pivot in the arm's frame
    pivot_anchor_chassis: np.ndarray  # (4, 2) ... in the chassis' frame
    split: np.ndarray  # (4, 2, 3) each pivot's (k_in, c_in) per coordinate


def layout(p: HalfCarParameters, role: str) -> Layout:
    """The element table of the car ``role`` ("model" or "reference": their pivots' split
    stiffness and damping may differ) built from a pymunk ``HalfCar``."""
    car = HalfCar(p, role)
    index = {id(car.bodies[name]): i for i, name in enumerate(BODIES)}
    damping: dict[int, tuple[int, float]] = {}  # id(constraint) -> (kind, physical c)
    bushing_ids = []
    for pv in car.pivots:
        ids = []
        for c in COORDS:
            split = pv[c]
            damping[id(split.spring)] = (ROTARY if c == "rotation" else SPRING, split.c_in)
            ids.append(id(split.spring))
        bushing_ids.append(ids)
    for i, side in enumerate(SIDES):
        corner = car.corners[side]
        damping[id(corner["coil"])] = (SPRING, p.c_s)
        damping[id(corner["lower_joint"])] = (SPRING, p.c_bj)
        damping[id(corner["upper_joint"])] = (SPRING, p.c_bj)
        damping[id(corner["tyre"])] = (TYRE, p.c_t)
        damping[id(corner["lateral"])] = (LATERAL, p.c_y)
        for key in ("tyre", "lateral"):
            damping[id(corner[key])] += (i,)
    rows = []
    position = {}
    for e, con in enumerate(car.space.constraints):
        entry = damping[id(con)]
        kind, c = entry[0], entry[1]
        side = entry[2] if len(entry) > 2 else 0
        a, b = index[id(con.a)], index[id(con.b)]
        if isinstance(con, pymunk.DampedRotarySpring):
            anchors, rest = (0.0, 0.0, 0.0, 0.0), con.rest_angle
        else:
            anchors, rest = (*con.anchor_a, *con.anchor_b), con.rest_length
        rows.append((kind, a, b, side, anchors, rest, con.stiffness, c))
        position[id(con)] = e
    kind, ia, ib, side, anchors, rest, stiff, damp = zip(*rows, strict=True)
    bodies = [car.bodies[name] for name in BODIES]
    dynamic = pymunk.Body.DYNAMIC
    state = zero_state(1)[:, :, 0]
    for i, body in enumerate(bodies):
        state[PX, i], state[PY, i] = body.position
        state[ANG, i], state[W, i] = body.angle, body.angular_velocity
        state[VX, i], state[VY, i] = body.velocity
        state[COS, i], state[SIN, i] = np.cos(body.angle), np.sin(body.angle)
    return Layout(
        kind=np.array(kind, dtype=np.int64),
        ia=np.array(ia, dtype=np.int64),
        ib=np.array(ib, dtype=np.int64),
        side=np.array(side, dtype=np.int64),
        anchors=np.array(anchors, dtype=np.float64),
        rest=np.array(rest, dtype=np.float64),
        stiff=np.array(stiff, dtype=np.float64),
        damp=np.array(damp, dtype=np.float64),
        m_inv=np.array([1.0 / b.mass if b.body_type == dynamic else 0.0 for b in bodies]),
        i_inv=np.array([1.0 / b.moment if b.body_type == dynamic else 0.0 for b in bodies]),
        state=state,
        bushing_rows=np.array([[position[i] for i in ids] for ids in bushing_ids], dtype=np.int64),
        pivot_arm=np.array([index[id(pv["arm"])] for pv in car.pivots], dtype=np.int64),
        pivot_sign=np.array([pv["sign"] for pv in car.pivots]),
        pivot_anchor_arm=np.array([pv["anchor"] for pv in car.pivots]),
        pivot_anchor_chassis=np.array([pv["axial"].anchor_a for pv in car.pivots]),
        split=np.array(
            [[[pv[c].k_in for c in COORDS], [pv[c].c_in for c in COORDS]] for pv in car.pivots]
        ),  # fmt: skip
    )


__all__ = ["BODIES", "ROAD", "UPRIGHT", "Layout", "layout"]
