"""The reference rubber bushing: the "real" specimen the other models are identified from.

One axis, SI units (x deflection m, v velocity m/s, F force N), fixed sample time ``dt``. A
Kelvin-Voigt backbone plus seven switchable effects, four physical and three on the
measurement side::

    F_spec = s_k(dT) * k * g(x) + s_c(dT) * c * v + sum_i F_i + F_f           (specimen)
    F_meas(t) = [F_spec + m_fix * a](t - tau_d) + sigma_n * N(0, 1)             (load cell)

| effect      | parameters (SI, units in the names)               | equation                       |
|-------------|---------------------------------------------------|--------------------------------|
| backbone    | k_n_per_m, c_ns_per_m                             | k x + c v  (seed 000 eq. 1)    |
| relaxation  | relax_k_n_per_m[i], relax_tau_s[i]  (0..6)        | F_i' = k_i xdot - F_i / tau_i  |
| friction    | friction_fmax_n, friction_x2_m; law friction_law  | see below                      |
| hardening   | hardening_x_m; law hardening_law                  | g(x) see below                 |
| thermal     | thermal_r_k_per_w, thermal_c_j_per_k,             | dT' = (P - dT/R_th) / C_th     |
|             | thermal_ak_per_k, thermal_ac_per_k                | s_k = max(0.2, 1 - a_k dT) ... |
| delay       | delay_s                                           | F_meas(t) = F(t - tau_d)       |
| inertia     | fixture_mass_kg                                   | + m_fix * (v_t - v_{t-1}) / dt |
| noise       | noise_std_n, seed (constructor, not an array)     | + sigma_n * N(0, 1)            |

An effect is active when it is switched on (``effects``, default: every effect whose parameters
are set) and its parameters are non-zero. Switching does not change the parameters, so
``without_effects(("friction",))`` followed by ``with_effects(("friction",))`` restores them.

**Relaxation** (viscoelastic memory, Maxwell branches): spring k_i in series with a dashpot
k_i tau_i. Integrated exactly for x linear between samples:
F_i <- F_i exp(-dt/tau_i) + k_i (dx/dt) tau_i (1 - exp(-dt/tau_i)). Gives stress relaxation under
a held step (seed 000 §5.2) and the stiffening of the bushing with frequency.

**Friction** (rate-independent, amplitude-dependent hysteresis, the Payne effect), all laws with
the saturation force F_fmax = ``friction_fmax_n`` and the stiffness right after a reversal
F_fmax / x2 (x2 = ``friction_x2_m``):

- ``"berg"`` (Berg 1998, smooth friction element), with (x_s, F_fs) the last reversal point and
  alpha = F_fs / F_fmax:
  loading   F_f = F_fs + (x - x_s) / (x2 (1 - alpha) + (x - x_s)) (F_fmax - F_fs),
  unloading F_f = F_fs + (x - x_s) / (x2 (1 + alpha) - (x - x_s)) (F_fmax + F_fs).
  From the virgin state F_f reaches F_fmax / 2 at x = x2.
- ``"iwan"``: ``friction_elements`` parallel Jenkins elements (spring k_e = F_fmax / (x2 N) in
  series with a Coulomb slider), slip displacements uniform on (0, 2 x2]: z_j <- clip(z_j + k_e dx,
  -f_j, f_j), F_f = sum z_j. Closes minor loops exactly (Masing).
- ``"dahl"``: dF_f/dx = (F_fmax / x2) (1 - F_f sgn(dx) / F_fmax), solved exactly per step.

**Hardening** (elastic stiffening at large deflection), x_h = ``hardening_x_m``:

- ``"cubic"``: g(x) = x (1 + (x / x_h)^2)
- ``"tangent"``: g(x) = x_h tan(x / x_h), continued with its slope beyond |x| = 1.2 x_h
- ``"exponential"``: g(x) = x_h sinh(x / x_h), continued with its slope beyond |x| = 4 x_h

**Thermal** (self-heating): temperature rise dT with heat capacity C_th and resistance to
ambient R_th (time constant R_th C_th, tens of seconds). P is the power dissipated in the
damper, the Maxwell dashpots and the friction element. Stiffness (backbone and Maxwell springs)
scales by s_k = max(0.2, 1 - a_k dT), damping by s_c = max(0.2, 1 - a_c dT). Integrated
exactly for P held over a sample.

**Delay** (measurement): the force channel lags the displacement channel by tau_d = ``delay_s``
(fractional samples, linear interpolation in a buffer of past forces held in the state).
**Inertia** (measurement): the load cell also carries the fixture mass m_fix; acceleration is
the backward difference of the velocity input (m_fix may be negative: an over-compensated
fixture). **Noise** (measurement): Gaussian, std
``noise_std_n``, drawn from ``numpy.random.default_rng(seed)`` at every ``reset``; the draws are
made in (T, B) C order, so a batched ``simulate`` and T looped ``step`` calls agree bit for bit.

The friction element and the Maxwell branches see the deflection increment dx (the specimen's
own history); the damper and the fixture see the velocity input v.

Calibration (``python scripts/reference_calibration.py --behaviour``): the drive is
``bushenv.excitation.random_rpc`` (durability spectrum, 0.5-20 Hz, 204.8 Hz, peak |x| = n * 2 mm);
linear least-squares fit F ~ k x + c v on n = 1 (40 s, seed s), judged on n = 1.5 (20 s, seed
s + 1), measurement effects on. Seed 0 (in brackets: the papers), and the range over seeds
0, 10, ..., 90 as deviations from Table 1 or as the spread of the ratios:

| axis   | k fit N/mm (Table 1) | c fit N s/mm (T. 1) | RMS n=1.5 (Table 2)   | MAX n=1.5    |
|--------|----------------------|---------------------|-----------------------|--------------|
| axial  | 385.9 (379.68)       | 4.43 (4.4)          | 10.6 % (9.8 %)        | 13.3 %       |
| radial | 1548 (1518.73)       | 15.09 (15)          | 12.9 % (11.9 %)       | 16.2 %       |
| range  | -1.4 .. +1.9 %       | -1.2 .. +0.6 %      | ax 9.1-10.6, rad 11.1-12.9 % | 10-16 % |

The presets were tuned (k, c, friction_fmax_n) so that seeds 0, 10, 20 average Table 1 and
Table 2. Specimen alone: a held 4 mm step relaxes 1141 -> 1014 -> 946 -> 923 N (axial) and
4563 -> 4029 -> 3754 -> 3664 N (radial) at 0.1, 1, 5, 20 s after the step; a 4 mm 10 Hz sine
heats it by 5 / 17 K (axial, 10 / 60 s) and 9 / 28 K (radial), its force amplitude drifting down
1.9 / 6.6 % and 3.0 / 9.8 %, while 10 s at 0.5 mm 1 Hz heats it by < 0.01 K; a 12.5 mm 1 Hz sine
peaks at 4.1 kN axial, 20.2 kN radial (machine: 25 kN). Dynamic stiffness falls with amplitude
(radial 10 Hz: 1936 N/mm at 0.5 mm, 1567 at 4 mm) and rises with frequency (radial 2 mm: 1206 at
1 Hz, 2114 at 20 Hz); docs/reference.md has the whole sine grid.

Stability: every update is exact or algebraic (see ``kernel.py``), so the kernel is stable for
any input; tested for +-12.5 mm, |v| up to 1.3 m/s and dt from 1/2048 s to 1/100 s. For an
explicit coupling to a mass, ``stiffness_bound_n_per_m()`` bounds the tangent stiffness (radial
preset: 4.7e6 N/m at the stroke end, 3.1e6 N/m within 4 mm; axial 0.91e6 / 0.72e6 N/m), about
three times Table 1 because friction and the Maxwell springs are stiff right after a reversal.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from bushenv.models.base import PAPER_DT, BushingModel, ModelError
from bushenv.reference import kernel
from bushenv.reference.kernel import FRICTION_LAWS, HARDENING_LAWS, friction_rows, rubber_kernel

MAX_BRANCHES = 6
MAX_DELAY_SAMPLES = 64


@dataclass(frozen=True)
class ReferenceEffect:
    """One switchable effect of the reference: its parameters, where it acts, and whether a
    bushing's parameter values set it (``configured(bushing) -> bool``)."""

    params: tuple[str, ...]
    kind: str  # "physical" (the specimen) or "measurement" (the load cell)
    configured: Callable[[Any], bool]


# The reference's one list of effects: EFFECTS, PHYSICAL_EFFECTS, MEASUREMENT_EFFECTS and
# EFFECT_PARAMS are derived from it. The kernel's order of operations is its own.
REFERENCE_EFFECTS: dict[str, ReferenceEffect] = {
    "relaxation": ReferenceEffect(
        ("relax_k_n_per_m", "relax_tau_s"),
        "physical",
        lambda b: bool(np.any(b.relax_k_n_per_m > 0)),
    ),
    "friction": ReferenceEffect(
        ("friction_fmax_n", "friction_x2_m"),
        "physical",
        lambda b: b.friction_fmax_n > 0 and b.friction_x2_m > 0,
    ),
    "hardening": ReferenceEffect(("hardening_x_m",), "physical", lambda b: b.hardening_x_m > 0),
    "thermal": ReferenceEffect(
        ("thermal_r_k_per_w", "thermal_c_j_per_k", "thermal_ak_per_k", "thermal_ac_per_k"),
        "physical",
        lambda b: (
            b.thermal_r_k_per_w > 0
            and b.thermal_c_j_per_k > 0
            and (b.thermal_ak_per_k != 0 or b.thermal_ac_per_k != 0)
        ),
    ),
    "delay": ReferenceEffect(("delay_s",), "measurement", lambda b: b.delay_s > 0),
    "inertia": ReferenceEffect(
        ("fixture_mass_kg",), "measurement", lambda b: b.fixture_mass_kg != 0
    ),
    "noise": ReferenceEffect(("noise_std_n",), "measurement", lambda b: b.noise_std_n > 0),
}
EFFECTS = tuple(REFERENCE_EFFECTS)
PHYSICAL_EFFECTS = tuple(n for n, e in REFERENCE_EFFECTS.items() if e.kind == "physical")
MEASUREMENT_EFFECTS = tuple(n for n, e in REFERENCE_EFFECTS.items() if e.kind == "measurement")
# Parameters per effect (the backbone k, c is always on).
EFFECT_PARAMS = {n: e.params for n, e in REFERENCE_EFFECTS.items()}

# Presets: measured numbers in the module docstring and docs/reference.md.
PRESETS: dict[str, dict[str, Any]] = {
    "axial": dict(
        k_n_per_m=203.5e3,
        c_ns_per_m=3.95e3,
        relax_k_n_per_m=(50.0e3, 35.0e3, 30.0e3),
        relax_tau_s=(0.02, 0.3, 3.0),
        friction_fmax_n=97.5,
        friction_x2_m=0.25e-3,
        hardening_x_m=16.0e-3,
        thermal_r_k_per_w=0.16,
        thermal_c_j_per_k=250.0,
        thermal_ak_per_k=0.003,
        thermal_ac_per_k=0.006,
        delay_s=1.0e-3,
        fixture_mass_kg=1.0,
        noise_std_n=0.8,
        friction_law="berg",
        hardening_law="tangent",
    ),
    "radial": dict(
        k_n_per_m=738.0e3,
        c_ns_per_m=12.88e3,
        relax_k_n_per_m=(200.0e3, 150.0e3, 120.0e3),
        relax_tau_s=(0.02, 0.3, 3.0),
        friction_fmax_n=506.0,
        friction_x2_m=0.3e-3,
        hardening_x_m=14.0e-3,
        thermal_r_k_per_w=0.08,
        thermal_c_j_per_k=500.0,
        thermal_ak_per_k=0.003,
        thermal_ac_per_k=0.006,
        delay_s=1.0e-3,
        fixture_mass_kg=1.5,
        noise_std_n=3.0,
        friction_law="berg",
        hardening_law="cubic",
    ),
}


def _float(name: str, value: Any) -> float:
    try:
        out = float(np.asarray(value, dtype=np.float64).reshape(()))
    except (TypeError, ValueError):
        raise ModelError(f"rubber: {name} must be a number, got {value!r}") from None
    if not np.isfinite(out):
        raise ModelError(f"rubber: {name} must be finite, got {value!r}")
    return out


def _check_names(names: Any, what: str) -> tuple[str, ...]:
    if isinstance(names, str):
        names = (names,)
    names = tuple(names)
    unknown = [n for n in names if n not in EFFECTS]
    if unknown:
        raise ModelError(f"rubber: unknown effect(s) {unknown} in {what}; known: {list(EFFECTS)}")
    return names


def _relaxation(relax_k_n_per_m: Any, relax_tau_s: Any) -> tuple[np.ndarray, np.ndarray]:
    """The Maxwell branches' stiffnesses and time constants, checked."""
    rk = np.array(relax_k_n_per_m, dtype=np.float64).reshape(-1)
    rt = np.array(relax_tau_s, dtype=np.float64).reshape(-1)
    if rk.shape != rt.shape or rk.size > MAX_BRANCHES:
        raise ModelError(
            f"rubber: relax_k_n_per_m ({rk.size}) and relax_tau_s ({rt.size}) must have the "
            f"same length, at most {MAX_BRANCHES}"
        )
    if not (np.all(np.isfinite(rk)) and np.all(rk >= 0)):
        raise ModelError(f"rubber: relax_k_n_per_m must be finite and >= 0, got {rk}")
    if not (np.all(np.isfinite(rt)) and np.all(rt > 0)):
        raise ModelError(f"rubber: relax_tau_s must be finite and > 0, got {rt}")
    return rk, rt


def _check_laws(friction_law: str, hardening_law: str) -> None:
    if friction_law not in FRICTION_LAWS or friction_law == "off":
        raise ModelError(
            f"rubber: unknown friction_law {friction_law!r}; known: "
            f"{[k for k in FRICTION_LAWS if k != 'off']}"
        )
    if hardening_law not in HARDENING_LAWS or hardening_law == "off":
        raise ModelError(
            f"rubber: unknown hardening_law {hardening_law!r}; known: "
            f"{[k for k in HARDENING_LAWS if k != 'off']}"
        )


class RubberBushing(BushingModel):
    """Reference rubber bushing; see the module docstring for the force law and parameters."""

    name = "rubber"
    EFFECTS: ClassVar[tuple[str, ...]] = EFFECTS
    PHYSICAL_EFFECTS: ClassVar[tuple[str, ...]] = PHYSICAL_EFFECTS
    MEASUREMENT_EFFECTS: ClassVar[tuple[str, ...]] = MEASUREMENT_EFFECTS
    param_names = (
        "k_n_per_m",
        "c_ns_per_m",
        "relax_k_n_per_m",
        "relax_tau_s",
        "friction_fmax_n",
        "friction_x2_m",
        "hardening_x_m",
        "thermal_r_k_per_w",
        "thermal_c_j_per_k",
        "thermal_ak_per_k",
        "thermal_ac_per_k",
        "delay_s",
        "fixture_mass_kg",
        "noise_std_n",
    )

    def __init__(
        self,
        k_n_per_m: float,
        c_ns_per_m: float,
        relax_k_n_per_m: Any = (),
        relax_tau_s: Any = (),
        friction_fmax_n: float = 0.0,
        friction_x2_m: float = 0.0,
        hardening_x_m: float = 0.0,
        thermal_r_k_per_w: float = 0.0,
        thermal_c_j_per_k: float = 0.0,
        thermal_ak_per_k: float = 0.0,
        thermal_ac_per_k: float = 0.0,
        delay_s: float = 0.0,
        fixture_mass_kg: float = 0.0,
        noise_std_n: float = 0.0,
        friction_law: str = "berg",
        hardening_law: str = "cubic",
        friction_elements: int = 10,
        seed: int = 0,
        effects: Any = None,
        dt: float = PAPER_DT,
    ) -> None:
        self.k_n_per_m = _float("k_n_per_m", k_n_per_m)
        self.c_ns_per_m = _float("c_ns_per_m", c_ns_per_m)
        if self.k_n_per_m <= 0 or self.c_ns_per_m < 0:
            raise ModelError(
                f"rubber: need k_n_per_m > 0 and c_ns_per_m >= 0, got {k_n_per_m!r}, {c_ns_per_m!r}"
            )
        self.relax_k_n_per_m, self.relax_tau_s = _relaxation(relax_k_n_per_m, relax_tau_s)
        for name, value in (
            ("friction_fmax_n", friction_fmax_n),
            ("friction_x2_m", friction_x2_m),
            ("hardening_x_m", hardening_x_m),
            ("thermal_r_k_per_w", thermal_r_k_per_w),
            ("thermal_c_j_per_k", thermal_c_j_per_k),
            ("thermal_ak_per_k", thermal_ak_per_k),
            ("thermal_ac_per_k", thermal_ac_per_k),
            ("delay_s", delay_s),
            ("fixture_mass_kg", fixture_mass_kg),
            ("noise_std_n", noise_std_n),
        ):
            val = _float(name, value)
            if val < 0 and name != "fixture_mass_kg":
                raise ModelError(f"rubber: {name} must be >= 0, got {value!r}")
            setattr(self, name, val)
        _check_laws(friction_law, hardening_law)
        self.friction_law = str(friction_law)
        self.hardening_law = str(hardening_law)
        self.friction_elements = int(friction_elements)
        if not 1 <= self.friction_elements <= 64:
            raise ModelError(f"rubber: friction_elements must be 1..64, got {friction_elements!r}")
        self.seed = int(seed)
        self.effects = self._switched_on(effects)
        super().__init__(dt)
        self._n_branches, self._n_fric, self._n_delay, self._args = self._kernel_args()
        self._noise_on = "noise" in self.effects
        self._no_noise = np.zeros((1, 1))
        self._rng = np.random.default_rng(self.seed)  # the noise's draws; reset restarts them
        self.reset(1)

    # ----- effects -----------------------------------------------------------------------
    def _switched_on(self, effects: Any) -> tuple[str, ...]:
        """The effects that run: every configured one, or those asked for (each configured)."""
        configured = tuple(e for e in EFFECTS if self._has_params(e))
        if effects is None:
            return configured
        wanted = _check_names(effects, "effects")
        missing = [e for e in wanted if e not in configured]
        if missing:
            raise ModelError(
                f"rubber: effect(s) {missing} switched on but their parameters are zero: "
                + ", ".join(f"{e}: {EFFECT_PARAMS[e]}" for e in missing)
            )
        return tuple(e for e in EFFECTS if e in wanted)

    def _has_params(self, effect: str) -> bool:
        return bool(REFERENCE_EFFECTS[effect].configured(self))

    @property
    def active_effects(self) -> tuple[str, ...]:
        """The effects that act (switched on and with non-zero parameters), in EFFECTS order."""
        return self.effects

    def only_effects(self, names: Any) -> RubberBushing:
        """A copy with exactly ``names`` switched on (each must have its parameters set)."""
        names = _check_names(names, "only_effects")
        return type(self).from_params(self.params, self.dt, {**self.extra_meta(), "effects": names})

    def with_effects(self, names: Any) -> RubberBushing:
        """A copy with ``names`` switched on in addition to the active effects."""
        names = _check_names(names, "with_effects")
        return self.only_effects(tuple(set(self.effects) | set(names)))

    def without_effects(self, names: Any) -> RubberBushing:
        """A copy with ``names`` switched off (parameters kept, so they can be switched back)."""
        names = _check_names(names, "without_effects")
        return self.only_effects(tuple(e for e in self.effects if e not in names))

    def specimen(self) -> RubberBushing:
        """A copy without the measurement effects (delay, inertia, noise): the bushing alone."""
        return self.without_effects(MEASUREMENT_EFFECTS)

    def stiffness_bound_n_per_m(self, x_max_m: float = 12.5e-3) -> float:
        """Upper bound of the specimen's tangent stiffness dF/dx within |x| <= ``x_max_m``.

        k g'(x_max) + sum k_i (Maxwell springs, at frequencies >> 1/tau_i) + the friction
        element's largest slope (F_fmax/x2 right after a reversal; twice that for Dahl). For
        the stability margin of explicit couplings (omega = sqrt(bound / mass)); the damper adds
        ``c_ns_per_m`` on top. Measurement effects are not included.
        """
        on = set(self.effects)
        u = x_max_m / self.hardening_x_m if "hardening" in on else 0.0
        if "hardening" not in on:
            slope = 1.0
        elif self.hardening_law == "cubic":
            slope = 1.0 + 3.0 * u * u
        elif self.hardening_law == "tangent":
            slope = 1.0 / np.cos(min(u, kernel.TANGENT_U_MAX)) ** 2
        else:
            slope = float(np.cosh(min(u, kernel.EXPONENTIAL_U_MAX)))
        bound = self.k_n_per_m * slope
        if "relaxation" in on:
            bound += float(self.relax_k_n_per_m.sum())
        if "friction" in on:
            k0 = self.friction_fmax_n / self.friction_x2_m
            bound += 2.0 * k0 if self.friction_law == "dahl" else k0
        return float(bound)

    # ----- kernel arguments --------------------------------------------------------------
    def _kernel_args(self) -> tuple[int, int, int, tuple]:
        """(relaxation branches, friction rows, delay samples held, the kernel's parameter
        arguments (fpar, ipar, relax, iwan))."""
        dt = self.dt
        on = set(self.effects)
        if "relaxation" in on:
            keep = self.relax_k_n_per_m > 0
            rk = self.relax_k_n_per_m[keep].copy()
            tau = self.relax_tau_s[keep]
        else:
            rk = np.zeros(0)
            tau = np.ones(0)
        decay = np.exp(-dt / tau)
        gain = tau * -np.expm1(-dt / tau)
        eta = rk * tau
        law = FRICTION_LAWS[self.friction_law] if "friction" in on else 0
        fmax = self.friction_fmax_n if law else 1.0
        k0 = self.friction_fmax_n / self.friction_x2_m if law else 1.0
        if law == 2:
            n = self.friction_elements
            iwan_k = np.full(n, k0 / n)
            iwan_f = iwan_k * 2.0 * self.friction_x2_m * (np.arange(n) + 0.5) / n
        else:
            iwan_k = np.zeros(0)
            iwan_f = np.zeros(0)
        hard = HARDENING_LAWS[self.hardening_law] if "hardening" in on else 0
        hard_x = self.hardening_x_m if hard else 1.0
        if "thermal" in on:
            th_r = self.thermal_r_k_per_w
            th_decay = float(np.exp(-dt / (self.thermal_r_k_per_w * self.thermal_c_j_per_k)))
            th_ak, th_ac = self.thermal_ak_per_k, self.thermal_ac_per_k
        else:
            th_r, th_decay, th_ak, th_ac = 0.0, 1.0, 0.0, 0.0
        if "delay" in on:
            d = self.delay_s / dt
            if d > MAX_DELAY_SAMPLES:
                raise ModelError(
                    f"rubber: delay_s={self.delay_s:g} s is {d:.1f} samples at dt={dt:g} s; "
                    f"at most {MAX_DELAY_SAMPLES}"
                )
            d_int = int(np.floor(d))
            d_frac = float(d - d_int)
            n_delay = d_int + 1
        else:
            d_int, d_frac, n_delay = 0, 0.0, 0
        m_fix = self.fixture_mass_kg if "inertia" in on else 0.0
        fpar = np.zeros(kernel.N_FPAR)
        fpar[kernel.F_K] = self.k_n_per_m
        fpar[kernel.F_C] = self.c_ns_per_m
        fpar[kernel.F_FMAX] = fmax
        fpar[kernel.F_K0] = k0
        fpar[kernel.F_HARD_X] = hard_x
        fpar[kernel.F_TH_DECAY] = th_decay
        fpar[kernel.F_TH_R] = th_r
        fpar[kernel.F_TH_AK] = th_ak
        fpar[kernel.F_TH_AC] = th_ac
        fpar[kernel.F_DELAY_FRAC] = d_frac
        fpar[kernel.F_M_FIX] = m_fix
        fpar[kernel.F_DT] = dt
        ipar = np.zeros(kernel.N_IPAR, dtype=np.int64)
        ipar[kernel.I_FRIC_LAW] = law
        ipar[kernel.I_HARD_LAW] = hard
        ipar[kernel.I_DELAY_INT] = d_int
        ipar[kernel.I_N_DELAY] = n_delay
        ipar[kernel.I_NOISE_ON] = int("noise" in on)
        relax = np.ascontiguousarray(np.stack([rk, decay, gain, eta]).reshape(4, rk.size))
        iwan = np.ascontiguousarray(np.stack([iwan_k, iwan_f]).reshape(2, iwan_k.size))
        n_fric = friction_rows(law, self.friction_elements)
        return rk.size, n_fric, n_delay, (fpar, ipar, relax, iwan)

    @property
    def n_state(self) -> int:
        if not hasattr(self, "_n_fric"):
            return 3
        return 3 + self._n_branches + self._n_fric + self._n_delay

    def reset(self, batch_size: int = 1) -> None:
        super().reset(batch_size)
        self._rng = np.random.default_rng(self.seed)

    def _advance(self, x: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        if self.state.shape != (self.n_state, x.shape[1]):
            raise ModelError(
                f"rubber: state of shape {self.state.shape} does not fit a batch of "
                f"{x.shape[1]}; call reset({x.shape[1]}) first"
            )
        if self._noise_on:
            noise = self._rng.standard_normal(x.shape)
            noise *= self.noise_std_n
        else:
            noise = self._no_noise
        fpar, ipar, relax, iwan = self._args
        rubber_kernel(x, v, noise, self.state, fpar, ipar, relax, iwan, out)

    # ----- parameters and files ----------------------------------------------------------
    def extra_meta(self) -> dict[str, Any]:
        return {
            "friction_law": self.friction_law,
            "hardening_law": self.hardening_law,
            "friction_elements": self.friction_elements,
            "seed": self.seed,
            "effects": list(self.effects),
        }

    @classmethod
    def from_params(
        cls, params: dict[str, np.ndarray], dt: float, extra: dict[str, Any]
    ) -> RubberBushing:
        return cls(dt=dt, **{k: params[k] for k in cls.param_names}, **extra)

    @classmethod
    def preset(
        cls,
        axis: str = "axial",
        dt: float = PAPER_DT,
        effects: Any = None,
        measurement: bool = True,
        seed: int = 0,
        **overrides: Any,
    ) -> RubberBushing:
        """The calibrated specimen for ``axis``.

        ``effects=None`` switches on the four physical effects; a list picks any of EFFECTS.
        ``measurement=True`` adds delay, inertia and noise (the test machine's load cell);
        ``measurement=False`` gives the specimen alone. ``overrides`` replace preset parameters
        (e.g. ``friction_law="iwan"``).
        """
        if axis not in PRESETS:
            raise ModelError(f"rubber: unknown axis {axis!r}; known: {sorted(PRESETS)}")
        unknown = [k for k in overrides if k not in PRESETS[axis] and k != "friction_elements"]
        if unknown:
            raise ModelError(f"rubber: unknown preset override(s) {unknown}")
        params = {**PRESETS[axis], **overrides}
        chosen = PHYSICAL_EFFECTS if effects is None else _check_names(effects, "preset effects")
        if measurement:
            chosen = tuple(chosen) + MEASUREMENT_EFFECTS
        return cls(dt=dt, seed=seed, effects=chosen, **params)

    def __repr__(self) -> str:
        return (
            f"RubberBushing(k={self.k_n_per_m:.6g} N/m, c={self.c_ns_per_m:.6g} N s/m, "
            f"effects={list(self.effects)}, friction_law={self.friction_law!r}, "
            f"hardening_law={self.hardening_law!r}, dt={self.dt:.6g})"
        )
