"""The fixed-rate split coupling of a bushing model into pymunk, and direct chipmunk calls.

The bushing model steps at its sample time ``dt`` (seed 001 §2: the network ran at 204.8 Hz
beside ADAMS); pymunk sub-steps in between. Holding the sampled force over ``dt`` is an explicit
scheme, unstable once omega * dt nears 1 (../shared/DESIGN-NOTES.md). ``SplitBushing`` therefore
applies a linear spring-damper (``k_in``, ``c_in``) inside every pymunk sub-step and holds only
the remainder::

    F(t) = k_in x(t) + c_in v(t) + [F_model(x_k, v_k) - k_in x_k - c_in v_k],  t_k <= t < t_k+1

At the sample instants F equals the model's force exactly; for a linear model with k_in, c_in
the held remainder is exactly zero and the coupling is the continuous system.
"""

from __future__ import annotations

import math

from bushenv.rigs.common import positive

# A pymunk DampedSpring acts along the line between its anchors. Anchoring one end LONG_ARM_M
# away along the bushing direction makes it a one-direction spring: a perpendicular offset d
# changes its length by d^2 / (2 LONG_ARM_M) (1e-8 m for d = 1 mm).
LONG_ARM_M = 50.0


def inverse_mass_along(a, b, anchor_a, anchor_b, direction) -> float:
    """Chipmunk's k = 1/m_a + 1/m_b + (r_a x n)^2 / I_a + (r_b x n)^2 / I_b at the anchors
    (local points), n a world direction: the inverse mass a force along n meets."""
    n0, n1 = direction
    k = 0.0
    for body, anchor in ((a, anchor_a), (b, anchor_b)):
        if body.body_type != body.DYNAMIC:
            continue
        r = _rotate(body.angle, anchor)
        cross = r[0] * n1 - r[1] * n0
        k += 1.0 / body.mass
        if math.isfinite(body.moment):
            k += cross * cross / body.moment
    return k


def _rotate(angle: float, p) -> tuple[float, float]:
    c, s = math.cos(angle), math.sin(angle)
    return c * p[0] - s * p[1], s * p[0] + c * p[1]


def implicit_euler_damping(c: float, h: float, k_inv_mass: float) -> float:
    """The chipmunk damping coefficient that makes a DampedSpring's damper act as implicit Euler.

    Chipmunk damps the relative velocity exactly, v <- v exp(-d h k), as if the damper were
    alone. With forces applied explicitly in the same step that over-damps badly once
    c h k >~ 0.1: a spring-damper loaded by F then creeps at F / (c_eff), c_eff ~ (e^{chk} - 1) /
    (h k), five times too slowly at c h k = 2.7 (the radial bushing on the control arm at 16
    sub-steps). Choosing d = ln(1 + c h k) / (h k) gives v <- v / (1 + c h k): implicit Euler,
    whose creep rate F / c is exact and which stays stable for any c h k.
    """
    x = c * h * k_inv_mass
    if x <= 0.0:
        return c
    return math.log1p(x) / (h * k_inv_mass)


class SplitBushing:
    """One axis of a bushing between pymunk bodies ``a`` (holds the bushing frame) and ``b``.

    ``direction`` is a unit vector fixed in ``a``'s frame (``a`` must not rotate); ``anchor_a``,
    ``anchor_b`` are the coincident bushing centres in each body's local frame at rest.

    The linear part k_in x + c_in v is a pymunk DampedSpring, evaluated in C inside every
    sub-step (its damper made implicit Euler by ``implicit_euler_damping``; call
    ``update_damping`` when the configuration has changed). ``hold(F, x, v)`` holds the
    remainder H = F - (k_in x + c_in v) of the sampled model force for the coming model step by
    shifting the spring's rest length by -H / k_in: the spring then pushes b with
    -(k_in x(t) + c_in v(t) + H), so no Python runs per sub-step.
    """

    def __init__(self, space, a, b, anchor_a, anchor_b, direction, k_in, c_in, h) -> None:
        import pymunk

        self.a, self.b = a, b
        self.h = positive("sub-step", h)
        self.k_in = positive("k_in", k_in)
        self.c_in = float(c_in)
        self.direction = (float(direction[0]), float(direction[1]))
        self.anchor_a = (float(anchor_a[0]), float(anchor_a[1]))
        self.anchor_b = (float(anchor_b[0]), float(anchor_b[1]))
        far = (
            self.anchor_a[0] - LONG_ARM_M * self.direction[0],
            self.anchor_a[1] - LONG_ARM_M * self.direction[1],
        )
        self.spring = pymunk.DampedSpring(a, b, far, self.anchor_b, LONG_ARM_M, k_in, c_in)
        space.add(self.spring)
        self.held_n = 0.0
        self.update_damping()

    def update_damping(self) -> None:
        """Set the chipmunk damping for implicit-Euler c_in at the current configuration."""
        k = inverse_mass_along(self.a, self.b, self.anchor_a, self.anchor_b, self.direction)
        self.spring.damping = implicit_euler_damping(self.c_in, self.h, k)

    def project(self, dx: float, dy: float) -> float:
        return dx * self.direction[0] + dy * self.direction[1]

    def hold(self, force_n: float, x: float, v: float) -> float:
        """Hold the remainder of the sampled model force ``force_n`` at deflection (x, v)."""
        held = force_n - (self.k_in * x + self.c_in * v)
        self.held_n = held
        self.spring.rest_length = LONG_ARM_M - held / self.k_in
        return held

    def release(self) -> None:
        self.held_n = 0.0
        self.spring.rest_length = LONG_ARM_M


def space_stepper(space):
    """``space.step`` without pymunk's per-call Python bookkeeping (it re-checks masses and
    processes deferred additions; our spaces add nothing while stepping): calls chipmunk's
    cpSpaceStep directly, 3-5 us less per sub-step. Falls back to ``space.step``."""
    try:
        from pymunk._chipmunk import lib

        space.step(0.0)  # pymunk's one-off checks of the bodies, no motion
        handle = space._space
        cp_step = lib.cpSpaceStep

        def step(dt: float) -> None:
            cp_step(handle, dt)

        return step
    except (ImportError, AttributeError):  # another pymunk layout
        return space.step


def velocity_setter(body):
    """``body.velocity = (vx, vy)`` through chipmunk directly (pymunk's attribute machinery
    costs ~1 us a call); falls back to the attribute."""
    try:
        from pymunk._chipmunk import lib

        handle = body._body
        cp_set = lib.cpBodySetVelocity
        cp_set(handle, (0.0, 0.0))

        def set_velocity(vx: float, vy: float) -> None:
            cp_set(handle, (vx, vy))

        return set_velocity
    except (ImportError, AttributeError, TypeError):

        def set_velocity(vx: float, vy: float) -> None:
            body.velocity = (vx, vy)

        return set_velocity


class SplitRotation:
    """The rotational coordinate of a planar bushing between bodies ``a`` (the bushing frame; it
    must not rotate) and ``b``: ``SplitBushing``'s scheme for a moment. A pymunk
    DampedRotarySpring applies k_in theta + c_in omega inside every sub-step (its damper made
    implicit Euler about ``b``'s inertia); ``hold(M, theta, omega)`` holds the remainder
    H = M - (k_in theta + c_in omega) by the spring's rest angle (chipmunk's rotary spring acts
    on b with -k (theta + rest_angle)), so ``b`` feels -(k_in theta(t) + c_in omega(t) + H)."""

    def __init__(self, space, a, b, k_in, c_in, h) -> None:
        import pymunk

        self.a, self.b = a, b
        self.h = positive("sub-step", h)
        self.k_in = positive("k_in", k_in)
        self.c_in = float(c_in)
        self.spring = pymunk.DampedRotarySpring(a, b, 0.0, self.k_in, self.c_in)
        space.add(self.spring)
        self.held_nm = 0.0
        self.update_damping()

    def update_damping(self) -> None:
        k = sum(1.0 / x.moment for x in (self.a, self.b) if math.isfinite(x.moment))
        self.spring.damping = implicit_euler_damping(self.c_in, self.h, k)

    def hold(self, moment_nm: float, theta: float, omega: float) -> float:
        """Hold the remainder of the sampled model moment ``moment_nm`` at (theta, omega)."""
        held = moment_nm - (self.k_in * theta + self.c_in * omega)
        self.held_nm = held
        self.spring.rest_angle = held / self.k_in
        return held

    def release(self) -> None:
        self.held_nm = 0.0
        self.spring.rest_angle = 0.0
