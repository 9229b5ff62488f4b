"""The pymunk half car of HalfCar-v0: one roll-plane front axle in its own space (``HalfCar``)
and a model car beside its reference twin (``HalfCarPair``).

Every force element is a spring (chipmunk keeps no impulse of a spring between steps), so a car
rebuilt from its snapshot goes on bit for bit: the four inner pivots are ``coupling``'s split
bushings (axial and radial a ``SplitBushing`` each, the rotation a ``SplitRotation``), the ball
joints stiff zero-length springs, the coil-overs and tyres ``DampedSpring`` s; every damper is
made implicit Euler (``coupling.implicit_euler_damping``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pymunk

from bushenv.rigs.coupling import (
    LONG_ARM_M,
    SplitBushing,
    SplitRotation,
    implicit_euler_damping,
    inverse_mass_along,
    space_stepper,
)
from bushenv.rigs.halfcar_params import POSITIONS, SIDES, HalfCarParameters, bar_inertia

# rad: the dampers' implicit-Euler coefficients are recomputed once a body turned this far since
# the last time. The effective masses they use move by under 1 % at 0.02 rad here: at the arms'
# inner ends the rotation enters as (r sin theta)^2 / I beside 1 / m (the quarter car, whose
# swing arm carries the wheel, uses 0.005).
DAMPING_ANGLE_STEP = 0.02
SIGN = {"left": 1.0, "right": -1.0}


class HalfCar:
    """One half car in its own pymunk space (no gravity: motion about static equilibrium; the
    space's gravity carries the lateral inertial load -a_y on every body instead).

    Bodies: the chassis (free: lateral, vertical, roll), and per side the lower and upper arm
    (uniform bars), the upright with its wheel (centre of mass at the wheel centre) and a
    kinematic road body under the contact point. Elements per side: the two inner pivots'
    bushings (chassis frame: axial lateral, outboard positive; radial vertical; rotation of the
    arm relative to the chassis, wheel-up positive -- the right side mirrored), two ball joints,
    the coil-over (chassis to lower arm), the tyre's vertical spring-damper at the contact point
    (unilateral: the wheel lifts off below -static load, its damper and the lateral tyre then
    off) and its lateral spring-damper to the road.
    """

    def __init__(self, p: HalfCarParameters, role: str = "model") -> None:
        self.p = p
        self.role = role
        self.space = space = pymunk.Space()
        pts = p.pts
        self.chassis = pymunk.Body(p.m_s, p.i_s)
        self.chassis.position = (0.0, p.h_cg)
        space.add(self.chassis)
        self.bodies = {"chassis": self.chassis}
        self.pivots: list[dict[str, Any]] = []  # POSITIONS order
        self.corners: dict[str, dict[str, Any]] = {}
        split = p.split.get(role)
        split = np.broadcast_to(np.stack([p.k_in, p.c_in]), (4, 2, 3)) if split is None else split
        for side in SIDES:
            s = SIGN[side]

            def at(name: str, s=s) -> tuple[float, float]:
                return (s * float(pts[name][0]), float(pts[name][1]))

            arms = {}
            for arm, m in (("lower", p.m_lower), ("upper", p.m_upper)):
                a, b = np.array(at(f"{arm}_arm_inner_m")), np.array(at(f"{arm}_arm_outer_m"))
                body = pymunk.Body(m, bar_inertia(m, a, b))
                body.position = tuple((a + b) / 2)
                arms[arm] = body
            upright = pymunk.Body(p.m_w, p.i_w)
            upright.position = at("wheel_centre_m")
            road = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
            road.position = (at("wheel_centre_m")[0], 0.0)
            space.add(*arms.values(), upright, road)
            self.bodies.update({f"lower_{side}": arms["lower"], f"upper_{side}": arms["upper"]})
            self.bodies.update({f"upright_{side}": upright, f"road_{side}": road})
            for arm, body in list(arms.items()):
                (k_in, c_in) = split[len(self.pivots)]
                inner = at(f"{arm}_arm_inner_m")
                a_loc, b_loc = self.chassis.world_to_local(inner), body.world_to_local(inner)
                self.pivots.append({
                    "arm": body, "sign": s, "anchor": tuple(b_loc),
                    "axial": SplitBushing(space, self.chassis, body, a_loc, b_loc, (s, 0.0),
                                          k_in[0], c_in[0], p.h),
                    "radial": SplitBushing(space, self.chassis, body, a_loc, b_loc, (0.0, 1.0),
                                           k_in[1], c_in[1], p.h),
                    "rotation": SplitRotation(space, self.chassis, body, k_in[2], c_in[2], p.h),
                })  # fmt: skip
                outer = at(f"{arm}_arm_outer_m")
                joint = pymunk.DampedSpring(
                    body, upright, body.world_to_local(outer), upright.world_to_local(outer),
                    0.0, p.k_bj, p.c_bj,
                )  # fmt: skip
                space.add(joint)
                arms[f"{arm}_joint"] = joint
            coil_top, coil_bottom = at("spring_chassis_m"), at("spring_arm_m")
            coil = pymunk.DampedSpring(
                self.chassis, arms["lower"], self.chassis.world_to_local(coil_top),
                arms["lower"].world_to_local(coil_bottom),
                math.dist(coil_top, coil_bottom), p.k_s, p.c_s,
            )  # fmt: skip
            contact = (0.0, -p.r_w)
            tyre = pymunk.DampedSpring(
                road, upright, (0.0, -LONG_ARM_M), contact, LONG_ARM_M, p.k_t, p.c_t
            )
            lateral = pymunk.DampedSpring(
                road, upright, (-s * LONG_ARM_M, 0.0), contact, LONG_ARM_M, p.k_y, p.c_y
            )
            space.add(coil, tyre, lateral)  # the tyre before its lateral spring: see _tyre_law
            corner = {"upright": upright, "road": road, "coil": coil, "tyre": tyre,
                      "lateral": lateral, "contact": True, **arms}  # fmt: skip
            tyre.force_func = self._tyre_law(corner)
            self.corners[side] = corner
        self._turning = tuple(b for k, b in self.bodies.items() if not k.startswith("road"))
        self._damping_angles = [0.0] * len(self._turning)
        self._steps = space_stepper(space)
        self.update_damping(force=True)

    def _tyre_law(self, corner: dict[str, Any]):
        """The vertical tyre: k_t compression, never pulling beyond the static load. When the
        wheel lifts or lands, the tyre's damper and the lateral spring switch (from the next
        sub-step); on landing the lateral spring's rest length takes the new contact point."""
        p = self
        k_t, lift = self.p.k_t, -self.p.tyre_static_n

        def force(spring, dist):
            f = k_t * (LONG_ARM_M - dist)
            touching = f > lift
            if touching != corner["contact"]:
                p._switch_contact(corner, touching)
            return f if touching else lift

        return force

    def _switch_contact(self, corner: dict[str, Any], touching: bool) -> None:
        corner["contact"] = touching
        q = self.p
        corner["tyre"].damping = q.c_t if touching else 0.0
        lateral = corner["lateral"]
        lateral.stiffness = q.k_y if touching else 0.0
        lateral.damping = q.c_y if touching else 0.0
        if touching:
            road, upright = corner["road"], corner["upright"]
            far = road.local_to_world(lateral.anchor_a)
            lateral.rest_length = abs(upright.local_to_world((0.0, -q.r_w)).x - far.x)

    def update_damping(self, force: bool = False) -> None:
        """Implicit-Euler dampers for the current configuration (the effective masses change with
        the bodies' angles: recomputed once any turned by ``DAMPING_ANGLE_STEP``)."""
        angles = [b.angle for b in self._turning]
        if not force and all(
            abs(a - b) < DAMPING_ANGLE_STEP
            for a, b in zip(angles, self._damping_angles, strict=True)
        ):
            return
        self._damping_angles = angles
        p = self.p
        for pivot in self.pivots:
            pivot["axial"].update_damping()
            pivot["radial"].update_damping()
        for corner in self.corners.values():
            coil = corner["coil"]
            a, b = (
                self.chassis.local_to_world(coil.anchor_a),
                corner["lower"].local_to_world(coil.anchor_b),
            )
            n = math.dist(a, b)
            direction = ((b.x - a.x) / n, (b.y - a.y) / n)
            k = inverse_mass_along(self.chassis, corner["lower"], coil.anchor_a, coil.anchor_b,
                                   direction)  # fmt: skip
            coil.damping = implicit_euler_damping(p.c_s, p.h, k)
            for arm in ("lower", "upper"):
                joint = corner[f"{arm}_joint"]
                k = max(
                    inverse_mass_along(corner[arm], corner["upright"], joint.anchor_a,
                                       joint.anchor_b, d)
                    for d in ((1.0, 0.0), (0.0, 1.0))
                )  # fmt: skip
                joint.damping = implicit_euler_damping(p.c_bj, p.h, k)

    # ----- state -------------------------------------------------------------------------------
    def bushing_motion(self) -> tuple[np.ndarray, np.ndarray]:
        """(q, v): (4, 3) deflections and their rates of the pivots in ``POSITIONS`` order, in
        each bushing's coordinates (axial m, radial m, rotation rad; the right side mirrored):
        the arm's inner end relative to the chassis, in the chassis frame."""
        c = self.chassis
        cx, cy = c.position
        cvx, cvy = c.velocity
        phi, w = c.angle, c.angular_velocity
        cos, sin = math.cos(phi), math.sin(phi)
        q = np.empty((4, 3))
        v = np.empty((4, 3))
        for i, pivot in enumerate(self.pivots):
            arm, s = pivot["arm"], pivot["sign"]
            ax, ay = pivot["anchor"]
            (bx, by), (bvx, bvy) = arm.position, arm.velocity
            ca, sa, wa = math.cos(arm.angle), math.sin(arm.angle), arm.angular_velocity
            rx, ry = ca * ax - sa * ay, sa * ax + ca * ay
            px, py = bx + rx, by + ry  # the arm's anchor, world
            vx = bvx - wa * ry - (cvx - w * (py - cy))  # relative to the chassis' point there
            vy = bvy + wa * rx - (cvy + w * (px - cx))
            a0 = pivot["axial"].anchor_a
            dx = px - (cx + cos * a0[0] - sin * a0[1])
            dy = py - (cy + sin * a0[0] + cos * a0[1])
            q[i] = (s * (cos * dx + sin * dy), -sin * dx + cos * dy, s * (arm.angle - phi))
            v[i] = (s * (cos * vx + sin * vy), -sin * vx + cos * vy, s * (wa - w))
        return q, v

    def hold(self, forces: np.ndarray, q: np.ndarray, v: np.ndarray) -> None:
        """Hold the remainders of the sampled (4, 3) bushing forces for the coming step."""
        for i, pivot in enumerate(self.pivots):
            s = pivot["sign"]
            pivot["axial"].hold(forces[i, 0], q[i, 0], v[i, 0])
            pivot["radial"].hold(forces[i, 1], q[i, 1], v[i, 1])
            pivot["rotation"].hold(s * forces[i, 2], s * q[i, 2], s * v[i, 2])

    def integrate(self, roads0, roads, a0: float, a1: float) -> None:
        """``physics_substeps`` pymunk steps, each road moving linearly from ``roads0`` to
        ``roads`` (left, right; m), the lateral load at the step's mean acceleration."""
        p = self.p
        for side, h0, h in zip(SIDES, roads0, roads, strict=True):
            self.corners[side]["road"].velocity = (0.0, (h - h0) / p.dt)
        self.space.gravity = (-(a0 + a1) / 2, 0.0)
        step, h_sub = self._steps, p.h
        for _ in range(p.substeps):
            step(h_sub)
        for side, h in zip(SIDES, roads, strict=True):  # exact road position, no drift
            road = self.corners[side]["road"]
            road.position = (road.position.x, h)
            road.velocity = (0.0, 0.0)

    def snapshot(self) -> dict[str, Any]:
        """The car's state between two steps: bodies, the springs' rest lengths, stiffnesses
        and damping coefficients, held remainders, contact flags, damping angles."""
        springs = {}
        for i, pivot in enumerate(self.pivots):
            for axis in ("axial", "radial"):
                b = pivot[axis]
                springs[f"{i}{axis}"] = (b.spring.rest_length, b.spring.damping, b.held_n)
            r = pivot["rotation"]
            springs[f"{i}rotation"] = (r.spring.rest_angle, r.spring.damping, r.held_nm)
        for side, c in self.corners.items():
            for key in ("coil", "tyre", "lateral", "lower_joint", "upper_joint"):
                sp = c[key]
                springs[f"{side}{key}"] = (sp.rest_length, sp.damping, sp.stiffness)
        return {
            "bodies": {
                k: (tuple(b.position), tuple(b.velocity), b.angle, b.angular_velocity)
                for k, b in self.bodies.items()
            },
            "springs": springs,
            "contact": {side: c["contact"] for side, c in self.corners.items()},
            "damping_angles": list(self._damping_angles),
        }

    def restore(self, snap: dict[str, Any]) -> None:
        for k, (pos, vel, angle, omega) in snap["bodies"].items():
            b = self.bodies[k]
            b.position, b.velocity, b.angle, b.angular_velocity = pos, vel, angle, omega
        sp = snap["springs"]
        for i, pivot in enumerate(self.pivots):
            for axis in ("axial", "radial"):
                b = pivot[axis]
                b.spring.rest_length, b.spring.damping, b.held_n = sp[f"{i}{axis}"]
            r = pivot["rotation"]
            r.spring.rest_angle, r.spring.damping, r.held_nm = sp[f"{i}rotation"]
        for side, c in self.corners.items():
            c["contact"] = snap["contact"][side]
            for key in ("coil", "tyre", "lateral", "lower_joint", "upper_joint"):
                c[key].rest_length, c[key].damping, c[key].stiffness = sp[f"{side}{key}"]
        self._damping_angles = list(snap["damping_angles"])

    def __getstate__(self) -> dict[str, Any]:
        # the tyre's force_func and the chipmunk handles do not pickle: rebuild, then restore
        return {"p": self.p, "role": self.role, "snapshot": self.snapshot()}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(state["p"], state["role"])
        self.restore(state["snapshot"])


class HalfCarPair:
    """The model car and its reference twin on the same roads and lateral load, each in its own
    space (nothing one does reaches the other). Built fresh at every episode."""

    def __init__(self, p: HalfCarParameters) -> None:
        self.p = p
        self.car = HalfCar(p, "model")
        self.twin = HalfCar(p, "reference")

    def integrate(self, roads0, roads, a0: float, a1: float) -> None:
        self.car.integrate(roads0, roads, a0, a1)
        self.twin.integrate(roads0, roads, a0, a1)


def step_models(models: Any, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(4, 3) forces of the four pivots: one model with four histories, or one per position."""
    if isinstance(models, dict):
        return np.array([models[k].step(q[i], v[i]) for i, k in enumerate(POSITIONS)])
    return np.asarray(models.step(q, v), dtype=np.float64).reshape(4, 3)
