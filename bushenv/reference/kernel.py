"""The one compiled kernel of the reference rubber bushing (``rubber.py`` documents the physics).

Every update is exact or unconditionally stable at any sample time: Maxwell branches and the
temperature rise use exponential integrators, the friction laws are algebraic maps of the
displacement increment (Berg, Iwan) or its exact solution (Dahl), hardening is algebraic, and
the measurement effects are finite filters. No sub-steps are needed.

State rows (n_state, B), in this order:

| rows                    | meaning                                                         |
|-------------------------|-----------------------------------------------------------------|
| 0                       | previous deflection x, m (friction and Maxwell increments)      |
| 1                       | previous velocity v, m/s (fixture inertia)                      |
| 2                       | temperature rise dT, K                                          |
| 3 .. 3+Nb               | Maxwell branch forces F_i, N                                    |
| next n_fric             | friction: berg (F, x_s, F_s, dir); dahl (F); iwan (z_j per elem)|
| next n_delay            | past load-cell forces, newest first, N                          |
"""

from __future__ import annotations

import math

import numba as nb
import numpy as np

JIT = dict(cache=True, fastmath=False, nogil=True)

FRICTION_LAWS = {"off": 0, "berg": 1, "iwan": 2, "dahl": 3}
HARDENING_LAWS = {"off": 0, "cubic": 1, "tangent": 2, "exponential": 3}
TANGENT_U_MAX = 1.2  # tan law: beyond |x|/x_h = 1.2 continue with the tangent slope (no pole)
EXPONENTIAL_U_MAX = 4.0  # sinh law: beyond |x|/x_h = 4 continue linearly (no overflow)
BERG_ALPHA_MAX = 1.0 - 1e-12


def friction_rows(law: int, n_elements: int) -> int:
    """State rows the friction law needs."""
    return (0, 4, n_elements, 1)[law]


@nb.njit(**JIT)
def hardening_force(x, k, law, x_h):  # pragma: no cover - compiled
    """Elastic backbone force k*g(x) for a hardening law (0: linear k x)."""
    if law == 0:
        return k * x
    u = x / x_h
    if law == 1:
        return k * x * (1.0 + u * u)
    au = abs(u)
    s = 1.0 if u >= 0.0 else -1.0
    if law == 2:
        if au <= TANGENT_U_MAX:
            return k * x_h * math.tan(u)
        c = math.cos(TANGENT_U_MAX)
        return s * k * x_h * (math.tan(TANGENT_U_MAX) + (au - TANGENT_U_MAX) / (c * c))
    if au <= EXPONENTIAL_U_MAX:
        return k * x_h * math.sinh(u)
    return (
        s
        * k
        * x_h
        * (math.sinh(EXPONENTIAL_U_MAX) + (au - EXPONENTIAL_U_MAX) * math.cosh(EXPONENTIAL_U_MAX))
    )


# Packed parameters (fewer arguments make a one-sample call from Python cheaper).
F_K, F_C, F_FMAX, F_K0, F_HARD_X, F_TH_DECAY, F_TH_R, F_TH_AK, F_TH_AC = range(9)
F_DELAY_FRAC, F_M_FIX, F_DT = 9, 10, 11
N_FPAR = 12
I_FRIC_LAW, I_HARD_LAW, I_DELAY_INT, I_N_DELAY, I_NOISE_ON = range(5)
N_IPAR = 5


@nb.njit(**JIT)
def rubber_kernel(x, v, noise, state, fpar, ipar, relax, iwan, out):  # pragma: no cover
    """Advance (T, B) samples; see the module docstring for the state rows.

    ``fpar`` (float64, N_FPAR): k, c, friction F_fmax, friction stick stiffness F_fmax/x2,
    hardening x_h, exp(-dt/(R_th C_th)), R_th, a_k, a_c, delay fraction, fixture mass, dt.
    ``ipar`` (int64, N_IPAR): friction law, hardening law, whole delay samples, delay buffer
    rows, noise on. ``relax`` (4, Nb): k_i, exp(-dt/tau_i), tau_i (1 - exp(-dt/tau_i)), k_i tau_i.
    ``iwan`` (2, N): element stiffness and slip force (empty unless the law is iwan).
    """
    k = fpar[F_K]
    c = fpar[F_C]
    fric_fmax = fpar[F_FMAX]
    fric_k0 = fpar[F_K0]
    hard_x = fpar[F_HARD_X]
    th_decay = fpar[F_TH_DECAY]
    th_r = fpar[F_TH_R]
    th_ak = fpar[F_TH_AK]
    th_ac = fpar[F_TH_AC]
    delay_frac = fpar[F_DELAY_FRAC]
    m_fix = fpar[F_M_FIX]
    dt = fpar[F_DT]
    fric_law = ipar[I_FRIC_LAW]
    hard_law = ipar[I_HARD_LAW]
    delay_int = ipar[I_DELAY_INT]
    n_delay = ipar[I_N_DELAY]
    noise_on = ipar[I_NOISE_ON] != 0
    relax_k = relax[0]
    relax_decay = relax[1]
    relax_gain = relax[2]
    relax_eta = relax[3]
    iwan_k = iwan[0]
    iwan_f = iwan[1]
    T, B = x.shape
    nb_ = relax_k.shape[0]
    r_fric = 3 + nb_
    n_fric = 0
    if fric_law == 1:
        n_fric = 4
    elif fric_law == 2:
        n_fric = iwan_k.shape[0]
    elif fric_law == 3:
        n_fric = 1
    r_delay = r_fric + n_fric
    for t in range(T):
        for b in range(B):
            xt = x[t, b]
            vt = v[t, b]
            x_prev = state[0, b]
            dx = xt - x_prev
            dT = state[2, b]
            sk = 1.0 - th_ak * dT
            if sk < 0.2:
                sk = 0.2
            sc = 1.0 - th_ac * dT
            if sc < 0.2:
                sc = 0.2
            force = sk * hardening_force(xt, k, hard_law, hard_x) + sc * c * vt
            power = sc * c * vt * vt
            # relaxation: F_i' = k_i xdot - F_i/tau_i, exact for x linear over the step
            rate = dx / dt
            for i in range(nb_):
                fi = state[3 + i, b] * relax_decay[i] + sk * relax_k[i] * rate * relax_gain[i]
                state[3 + i, b] = fi
                force += fi
                power += fi * fi / relax_eta[i]
            # friction (rate independent)
            if fric_law == 1:
                f_old = state[r_fric, b]
                direction = state[r_fric + 3, b]
                if dx > 0.0 and direction <= 0.0:
                    state[r_fric + 1, b] = x_prev
                    state[r_fric + 2, b] = f_old
                    state[r_fric + 3, b] = 1.0
                    direction = 1.0
                elif dx < 0.0 and direction >= 0.0:
                    state[r_fric + 1, b] = x_prev
                    state[r_fric + 2, b] = f_old
                    state[r_fric + 3, b] = -1.0
                    direction = -1.0
                f_new = f_old
                if dx != 0.0:
                    xs = state[r_fric + 1, b]
                    fs = state[r_fric + 2, b]
                    alpha = fs / fric_fmax
                    if alpha > BERG_ALPHA_MAX:
                        alpha = BERG_ALPHA_MAX
                    elif alpha < -BERG_ALPHA_MAX:
                        alpha = -BERG_ALPHA_MAX
                    x2 = fric_fmax / fric_k0
                    u = xt - xs
                    if direction > 0.0:
                        f_new = fs + u / (x2 * (1.0 - alpha) + u) * (fric_fmax - fs)
                    else:
                        f_new = fs + u / (x2 * (1.0 + alpha) - u) * (fric_fmax + fs)
                    state[r_fric, b] = f_new
                force += f_new
                # dissipated = work in - change of the stick spring's stored energy
                e = 0.5 * (f_old + f_new) * dx - (f_new * f_new - f_old * f_old) / (2.0 * fric_k0)
                if e > 0.0:
                    power += e / dt
            elif fric_law == 2:
                for j in range(n_fric):
                    z = state[r_fric + j, b] + iwan_k[j] * dx
                    fj = iwan_f[j]
                    if z > fj:
                        power += fj * (z - fj) / iwan_k[j] / dt
                        z = fj
                    elif z < -fj:
                        power += fj * (-fj - z) / iwan_k[j] / dt
                        z = -fj
                    state[r_fric + j, b] = z
                    force += z
            elif fric_law == 3:
                f_old = state[r_fric, b]
                f_new = f_old
                if dx > 0.0:
                    f_new = fric_fmax - (fric_fmax - f_old) * math.exp(-fric_k0 * dx / fric_fmax)
                elif dx < 0.0:
                    f_new = -fric_fmax + (fric_fmax + f_old) * math.exp(fric_k0 * dx / fric_fmax)
                state[r_fric, b] = f_new
                force += f_new
                e = 0.5 * (f_old + f_new) * dx - (f_new * f_new - f_old * f_old) / (2.0 * fric_k0)
                if e > 0.0:
                    power += e / dt
            # thermal: dT' = (P - dT/R)/C, exact for P held over the step
            if th_r > 0.0:
                state[2, b] = dT * th_decay + power * th_r * (1.0 - th_decay)
            # measurement side: fixture inertia, channel delay, sensor noise
            g = force
            if m_fix != 0.0:
                g += m_fix * (vt - state[1, b]) / dt
            if n_delay > 0:
                if delay_int == 0:
                    newer = g
                else:
                    newer = state[r_delay + delay_int - 1, b]
                older = state[r_delay + delay_int, b]
                measured = (1.0 - delay_frac) * newer + delay_frac * older
                for j in range(n_delay - 1, 0, -1):
                    state[r_delay + j, b] = state[r_delay + j - 1, b]
                state[r_delay, b] = g
            else:
                measured = g
            if noise_on:
                measured += noise[t, b]
            out[t, b] = measured
            state[0, b] = xt
            state[1, b] = vt


def warm_up() -> None:
    """Compile (or load from cache) the kernel once."""
    z = np.zeros((2, 1))
    fpar = np.ones(N_FPAR)
    rubber_kernel(
        z, z, z, np.zeros((3, 1)), fpar, np.zeros(N_IPAR, dtype=np.int64), np.zeros((4, 0)),
        np.zeros((2, 0)), np.empty_like(z),
    )  # fmt: skip
