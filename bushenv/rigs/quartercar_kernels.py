"""The compiled arithmetic of ``QuarterCarBatch``: the parameter vector, the bushing's motion
and ``physics_substeps`` sub-steps of B cars.

The state is (y_c, X, Y, theta) and their rates per column: chassis height, the unsprung body's
centre of mass and its angle (the chassis does not rotate, so theta is also the arm's rotation
relative to the chassis, ``Car.bushing_rotation``). Each sub-step is pymunk's order --
positions first, then the explicit spring forces, then the dampers -- with the dampers solved
together as implicit Euler (``quartercar_batch``'s docstring gives why).
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

from bushenv.rigs.car import CarParameters
from bushenv.rigs.coupling import LONG_ARM_M

# parameter vector layout for the kernel
P_M_S, P_M_U, P_I_U, P_XCM, P_L, P_MOUNT, P_H, P_KS, P_CS, P_KT, P_TSTAT = range(11)
P_KR, P_CR, P_KA, P_CA, P_STEP = range(11, 16)
N_PARAMS = 16
# state rows
Y_C, X_U, Y_U, TH, VY_C, VX_U, VY_U, OM = range(8)
# rows of the forces sampled at a model step: radial, axial N, the deflections m, (with a
# planar arm bushing) the moment N m
F_RADIAL, F_AXIAL, X_RADIAL, X_AXIAL, F_MOMENT = range(5)


def parameter_vector(p: CarParameters) -> np.ndarray:
    v = np.zeros(N_PARAMS)
    v[P_M_S], v[P_M_U], v[P_I_U], v[P_XCM] = p.m_s, p.m_u, p.i_u, p.x_cm
    v[P_L], v[P_MOUNT], v[P_H] = p.L, p.mount, p.H
    v[P_KS], v[P_CS], v[P_KT], v[P_TSTAT] = p.k_s, p.c_s, p.k_t, p.tyre_static_n
    v[P_KR], v[P_CR] = p.k_in["radial"], p.c_in["radial"]
    v[P_KA], v[P_CA] = p.k_in["axial"], p.c_in["axial"]
    v[P_STEP] = p.h
    return v


@nb.njit(cache=True, nogil=True)
def bushing_motion_kernel(state, prm, out):  # pragma: no cover - compiled
    """out (4, B): x_radial, v_radial, x_axial, v_axial of the arm's inner end."""
    x_cm = prm[P_XCM]
    for b in range(state.shape[1]):
        c, s = math.cos(state[TH, b]), math.sin(state[TH, b])
        rx, ry = -x_cm * c, -x_cm * s
        om = state[OM, b]
        out[0, b] = state[Y_U, b] + ry - state[Y_C, b]
        out[1, b] = state[VY_U, b] + om * rx - state[VY_C, b]
        out[2, b] = state[X_U, b] + rx
        out[3, b] = state[VX_U, b] - om * ry


@nb.njit(cache=True, nogil=True)
def substeps_kernel(state, road, road_v, held, rotation, active, n_sub, prm):  # pragma: no cover
    """Advance B cars by n_sub sub-steps of h = prm[P_STEP]; road (B,) is updated in place.

    ``held`` (3, B): the held remainders, radial and axial N and the arm's moment N m;
    ``rotation`` (2, B): each column's rotary (k_in N m/rad, c_in N m s/rad) between arm and
    chassis (``coupling.SplitRotation``; zero without a planar arm bushing, which leaves every
    sum unchanged to the last bit)."""
    h = prm[P_STEP]
    m_s, m_u, i_u, x_cm = prm[P_M_S], prm[P_M_U], prm[P_I_U], prm[P_XCM]
    L, H = prm[P_L], prm[P_H]
    a_m = prm[P_MOUNT] * L - x_cm
    a_w = L - x_cm
    k_s, c_s, k_t, lift = prm[P_KS], prm[P_CS], prm[P_KT], -prm[P_TSTAT]
    k_r, c_r, k_a, c_a = prm[P_KR], prm[P_CR], prm[P_KA], prm[P_CA]
    mass = np.empty(4)
    mass[0], mass[1], mass[2], mass[3] = m_s, m_u, m_u, i_u
    J = np.empty((3, 4))
    A = np.empty((4, 4))
    rhs = np.empty(4)
    q = np.empty(4)
    for b in range(state.shape[1]):
        if not active[b]:
            continue
        k_th, c_th = rotation[0, b], rotation[1, b]
        for _ in range(n_sub):
            # 1. positions (and the kinematic road) with the current velocities
            state[Y_C, b] += h * state[VY_C, b]
            state[X_U, b] += h * state[VX_U, b]
            state[Y_U, b] += h * state[VY_U, b]
            state[TH, b] += h * state[OM, b]
            road[b] += h * road_v[b]
            c, s = math.cos(state[TH, b]), math.sin(state[TH, b])
            yc, X, Y = state[Y_C, b], state[X_U, b], state[Y_U, b]
            rix, riy = -x_cm * c, -x_cm * s
            rmx, rmy = a_m * c, a_m * s
            rwx, rwy = a_w * c, a_w * s
            # 2. explicit spring forces -> generalised forces Q over (y_c, X, Y, theta)
            Q0 = 0.0
            Q1 = 0.0
            Q2 = 0.0
            Q3 = 0.0
            # bushing radial (vertical at the inner end) and axial (horizontal)
            f = -(k_r * (Y + riy - yc) + held[0, b])
            Q0 -= f
            Q2 += f
            Q3 += rix * f
            f = -(k_a * (X + rix) + held[1, b])
            Q1 += f
            Q3 -= riy * f
            # the planar bushing's rotation: a rotary spring on the arm, as chipmunk's
            Q3 -= k_th * state[TH, b] + held[2, b]
            # coil-over from the chassis top mount to the arm mount
            dx = X + rmx - prm[P_MOUNT] * L
            dy = Y + rmy - (yc + H)
            ell = math.sqrt(dx * dx + dy * dy)
            ux, uy = dx / ell, dy / ell
            f = -k_s * (ell - H)
            jc3 = -ux * rmy + uy * rmx
            Q0 -= uy * f
            Q1 += ux * f
            Q2 += uy * f
            Q3 += jc3 * f
            # tyre: long-arm spring from (L, road - D) to the wheel centre, unilateral
            tx = X + rwx - L
            ty = Y + rwy - road[b] + LONG_ARM_M
            dist = math.sqrt(tx * tx + ty * ty)
            f = k_t * (LONG_ARM_M - dist)
            if f < lift:
                f = lift
            nx, ny = tx / dist, ty / dist
            Q1 += nx * f
            Q2 += ny * f
            Q3 += (-nx * rwy + ny * rwx) * f
            # 3. explicit velocity update
            q[0] = state[VY_C, b] + h * Q0 / m_s
            q[1] = state[VX_U, b] + h * Q1 / m_u
            q[2] = state[VY_U, b] + h * Q2 / m_u
            q[3] = state[OM, b] + h * Q3 / i_u
            # 4. the dampers together, implicit Euler: (M + h sum c J J^T) q+ = M q
            J[0, 0], J[0, 1], J[0, 2], J[0, 3] = -1.0, 0.0, 1.0, rix
            J[1, 0], J[1, 1], J[1, 2], J[1, 3] = 0.0, 1.0, 0.0, -riy
            J[2, 0], J[2, 1], J[2, 2], J[2, 3] = -uy, ux, uy, jc3
            for i in range(4):
                rhs[i] = mass[i] * q[i]
                for j in range(4):
                    A[i, j] = h * (
                        c_r * J[0, i] * J[0, j] + c_a * J[1, i] * J[1, j] + c_s * J[2, i] * J[2, j]
                    )
                A[i, i] += mass[i]
            A[3, 3] += h * c_th  # the rotary damper: J = (0, 0, 0, 1), the chassis not rotating
            # Gaussian elimination (A is symmetric positive definite, no pivoting needed)
            for k in range(4):
                for i in range(k + 1, 4):
                    r = A[i, k] / A[k, k]
                    for j in range(k, 4):
                        A[i, j] -= r * A[k, j]
                    rhs[i] -= r * rhs[k]
            for i in range(3, -1, -1):
                acc = rhs[i]
                for j in range(i + 1, 4):
                    acc -= A[i, j] * q[j]
                q[i] = acc / A[i, i]
            state[VY_C, b] = q[0]
            state[VX_U, b] = q[1]
            state[VY_U, b] = q[2]
            state[OM, b] = q[3]
