"""The passive half car's energy terms, for the energy-balance test: stored energy, dissipated
power and the tyre forces on the road, read from a ``HalfCar``'s pymunk bodies."""

from __future__ import annotations

import numpy as np

from bushenv.rigs.coupling import LONG_ARM_M


def _length_and_rate(s) -> tuple[float, float]:
    """A spring's anchor distance and its lengthening rate."""
    d = s.b.local_to_world(s.anchor_b) - s.a.local_to_world(s.anchor_a)
    dv = s.b.velocity_at_local_point(s.anchor_b) - s.a.velocity_at_local_point(s.anchor_a)
    n = d.normalized() if d.length > 0 else d
    return d.length, dv.dot(n)


def energy_terms(car) -> tuple[float, float, np.ndarray]:
    """(stored energy J, dissipated power W, (2,) vertical tyre forces on the wheels N) of a
    ``HalfCar`` with linear bushings: kinetic energy of every dynamic body, every spring's
    1/2 k (L - L_rest)^2 (the rotary bushings' 1/2 k (theta - rest)^2), every damper's c v^2
    with its physical c (not chipmunk's implicit-Euler coefficient)."""
    p = car.p
    stored = sum(
        0.5 * b.mass * b.velocity.dot(b.velocity) + 0.5 * b.moment * b.angular_velocity**2
        for k, b in car.bodies.items()
        if not k.startswith("road")
    )
    power = 0.0
    springs = []
    for pivot in car.pivots:
        springs += [(pivot[a].spring, pivot[a].c_in) for a in ("axial", "radial")]
        r = pivot["rotation"]
        theta = r.b.angle - r.a.angle
        omega = r.b.angular_velocity - r.a.angular_velocity
        stored += 0.5 * r.k_in * (theta - r.spring.rest_angle) ** 2
        power += r.c_in * omega * omega
    tyres = []
    for corner in car.corners.values():
        springs += [(corner["coil"], p.c_s), (corner["lateral"], p.c_y)]
        springs += [(corner["lower_joint"], p.c_bj), (corner["upper_joint"], p.c_bj)]
        length, rate = _length_and_rate(corner["tyre"])
        stored += 0.5 * p.k_t * (LONG_ARM_M - length) ** 2
        power += p.c_t * rate * rate
        tyres.append(p.k_t * (LONG_ARM_M - length) - p.c_t * rate)
    for spring, c in springs:
        length, rate = _length_and_rate(spring)
        stored += 0.5 * spring.stiffness * (length - spring.rest_length) ** 2
        power += c * rate * rate
    return stored, power, np.array(tyres)
