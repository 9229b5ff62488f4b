"""Bouc-Wen identification by a global optimiser (seed 002 §3: GA on the RMS error, eq. 6).

The cost is eq. 6, E = sqrt(mean((F_exp - F_pre)^2)) in N, of a free run from rest. A whole
population is simulated in ONE call of the batched numba kernel (one column per member,
``boucwen.simulate_population``), which is what makes a global search affordable here (seed 002
Table 5: 725 min with ADAMS + VisualDOC).

Search space (14 numbers, each within bounds scaled by the record's least-squares stiffness
k_ref and damping c_ref) and how it maps to the 16 parameters:

| search variable                  | bounds        | parameters                               |
|----------------------------------|---------------|------------------------------------------|
| log10 k0/k_ref, log10 k1/k_ref   | [-1.5, 0.5], [-2, 0.7] | k0, k1                          |
| log10 (c1/k_ref / s)             | [-3.5, -1.5]  | c1 (time constant of eq. 3, 0.3-30 ms)   |
| log10 c0/c_ref, log10 c2/c_ref   | [-2, 2], [-2, 0.7] | c0, c2                              |
| log10 k2/k_ref                   | [-4, 0.5]     | k2                                       |
| log10 (d_sat1 / m), d_sat2       | [-5, -2]      | saturation scale of z: delta = 1/d^n     |
| rho1, rho2                       | [0, 5]        | beta = rho delta                         |
| n1, n2                           | [0.5, 2.5]    | n1, n2                                   |
| log10 a1/k_ref, log10 a2/k_ref   | [-3, 0.7]     | a1, a2 (A = 1: z is a displacement, m)   |

Constraints of eq. 6 hold by construction: A1 = A2 = 1 (>= 1); beta = rho delta >= 0;
beta1 + gamma1 = delta1 > 0 (gamma1 = (1 - rho1) delta1); beta2 - gamma2 = delta2 > 0
(gamma2 = (rho2 - 1) delta2). Fixing A is no loss: z -> lambda z with A -> A/lambda,
(beta, gamma) -> lambda^(n-1) (beta, gamma), a -> a lambda gives the same force, so A is a gauge.

Procedure: ``scipy.optimize.differential_evolution`` (seeded, ``vectorized=True``, workers=1,
``generations`` generations) on the first ``fit_seconds`` of the records (record after record,
each run from rest), then a bounded Powell polish on all of every record, from the final
population's member with the lowest error on all of the records. Why 400 generations:
studies/2026-11-fit-seed-spread. Generations and evaluations, not the clock, end the search, so
a seed reproduces the parameters; ``time_limit_s`` (off by default) stops the search after the
generation that passes it, and the log says so (``stopped``, ``time_limited``,
``budget_used``). Members that cannot be integrated (more than ``max_substeps`` trial
steps in a sample, or a solution that blows up) score ``inf``.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import differential_evolution, minimize

from bushenv.identify.boucwen_options import BoucWenOptions
from bushenv.identify.data import IdentificationError, TrainingSet
from bushenv.identify.linear import least_squares_kc
from bushenv.models.boucwen import BoucWenBushing, simulate_population
from bushenv.models.kernels import BW_ORDER
from bushenv.progress import Progress, ProgressSpec

SEARCH_NAMES = (
    "log_k0",
    "log_k1",
    "log_tau1_s",
    "log_c0",
    "log_c2",
    "log_k2",
    "log_dsat1_m",
    "log_dsat2_m",
    "rho1",
    "rho2",
    "n1",
    "n2",
    "log_a1",
    "log_a2",
)
SEARCH_BOUNDS = (
    (-1.5, 0.5),
    (-2.0, 0.7),
    (-3.5, -1.5),
    (-2.0, 2.0),
    (-2.0, 0.7),
    (-4.0, 0.5),
    (-5.0, -2.0),
    (-5.0, -2.0),
    (0.0, 5.0),
    (0.0, 5.0),
    (0.5, 2.5),
    (0.5, 2.5),
    (-3.0, 0.7),
    (-3.0, 0.7),
)


def search_to_parameters(u: np.ndarray, k_ref: float, c_ref: float) -> np.ndarray:
    """Map search vectors (..., 14) to SI parameter vectors (..., 16) in BW_ORDER."""
    u = np.asarray(u, dtype=np.float64)
    g = {name: u[..., i] for i, name in enumerate(SEARCH_NAMES)}
    n1, n2 = g["n1"], g["n2"]
    delta1 = 1.0 / (10.0 ** g["log_dsat1_m"]) ** n1
    delta2 = 1.0 / (10.0 ** g["log_dsat2_m"]) ** n2
    beta1 = g["rho1"] * delta1
    beta2 = g["rho2"] * delta2
    p = {
        "c0": 10.0 ** g["log_c0"] * c_ref,
        "k0": 10.0 ** g["log_k0"] * k_ref,
        "c1": 10.0 ** g["log_tau1_s"] * k_ref,
        "k1": 10.0 ** g["log_k1"] * k_ref,
        "c2": 10.0 ** g["log_c2"] * c_ref,
        "k2": 10.0 ** g["log_k2"] * k_ref,
        "A1": np.ones_like(n1),
        "A2": np.ones_like(n1),
        "beta1": beta1,
        "beta2": beta2,
        "gamma1": delta1 - beta1,
        "gamma2": beta2 - delta2,
        "n1": n1,
        "n2": n2,
        "a1": 10.0 ** g["log_a1"] * k_ref,
        "a2": 10.0 ** g["log_a2"] * k_ref,
    }
    return np.stack([p[k] for k in BW_ORDER], axis=-1)


def satisfies_constraints(vector: np.ndarray) -> bool:
    """seed 002 eq. 6: A1, A2 >= 1, beta >= 0, beta1 + gamma1 > 0, beta2 - gamma2 > 0."""
    p = dict(zip(BW_ORDER, np.asarray(vector, dtype=np.float64), strict=True))
    return bool(
        p["A1"] >= 1
        and p["A2"] >= 1
        and p["beta1"] >= 0
        and p["beta2"] >= 0
        and p["beta1"] + p["gamma1"] > 0
        and p["beta2"] - p["gamma2"] > 0
    )


class PopulationCost:
    """Eq. 6 RMS error, N, of search vectors over records each run from rest (pooled samples).

    ``parts``: (x, v, f) arrays per record; ``__call__(u)`` takes u (14, S) and returns (S,).
    """

    def __init__(self, parts, dt: float, k_ref: float, c_ref: float, max_substeps: int) -> None:
        self.parts, self.dt, self.k_ref, self.c_ref = parts, dt, k_ref, c_ref
        self.max_substeps = max_substeps
        self.samples = sum(len(x) for x, _, _ in parts)
        self.evaluations = 0

    def __call__(self, u: np.ndarray) -> np.ndarray:
        vectors = search_to_parameters(np.atleast_2d(u.T), self.k_ref, self.c_ref)
        errs, bad = [], np.zeros(vectors.shape[0], dtype=bool)
        for x, v, f in self.parts:
            out, bad_p = simulate_population(vectors, x, v, self.dt, max_substeps=self.max_substeps)
            errs.append(out - f[:, None])
            bad |= bad_p
        err = errs[0] if len(errs) == 1 else np.concatenate(errs)
        cost = np.sqrt(np.mean(err * err, axis=0))
        cost[bad | ~np.isfinite(cost)] = np.inf
        self.evaluations += vectors.shape[0]
        return cost


def first_seconds(data: TrainingSet, seconds: float) -> list[tuple]:
    """(x, v, f) of the first ``seconds`` of the records, record after record (at least 10
    samples)."""
    left = max(10, int(round(seconds / data.dt)))
    parts = []
    for s in data.segments:
        if left <= 0:
            break
        n = min(len(s), left)
        parts.append((s.x[:n], s.v[:n], s.f[:n]))
        left -= n
    return parts


def fit_boucwen(
    data: TrainingSet,
    options: BoucWenOptions,
    seed: int = 0,
    progress: ProgressSpec = True,
) -> BoucWenBushing:
    """Identify the 16 Bouc-Wen parameters of ``data`` (see the module docstring).

    Returns the model with a ``training`` dict attribute (costs, generations, seconds).
    """
    opt = options
    x, f, v = data.concatenated()
    k_ref, c_ref = least_squares_kc(x, f, v)
    if not (k_ref > 0 and c_ref > 0):
        raise IdentificationError(
            f"least-squares stiffness {k_ref:.4g} N/m and damping {c_ref:.4g} N s/m must be "
            "positive to scale the Bouc-Wen search"
        )
    args = (data.dt, k_ref, c_ref, opt.max_substeps)
    search = PopulationCost(first_seconds(data, opt.fit_seconds), *args)
    whole = PopulationCost([(s.x, s.v, s.f) for s in data.segments], *args)
    members = opt.population * len(SEARCH_BOUNDS)
    work = (opt.generations + 1) * members * search.samples + opt.polish_evaluations * whole.samples
    prog = Progress.of(
        progress,
        total=work,
        label="boucwen",
        every_s=opt.progress_every_s,
        budget_s=opt.time_limit_s or None,
    )
    u_best, log = _evolve(search, whole, opt, seed, prog)
    u_best, log["cost_before_polish_n"], log["cost_n"] = _polish(whole, search, u_best, opt, prog)
    vector = search_to_parameters(u_best, k_ref, c_ref)
    model = BoucWenBushing.from_vector(vector, dt=data.dt)
    if not satisfies_constraints(vector):  # by construction; a failure here is a bug
        raise IdentificationError(f"identified parameters break eq. 6 constraints: {vector}")
    f_rms = float(np.sqrt(np.mean(f * f)))
    log.update(
        rms_ratio=log["cost_n"] / f_rms,
        evaluations=search.evaluations + whole.evaluations,
        seconds=prog.elapsed_s(),
        search_vector=u_best.tolist(),
        budget_used={
            "generations": log["generations"],
            "generations_planned": opt.generations,
            "search_evaluations": search.evaluations,
            "all_records_evaluations": whole.evaluations,  # the population check and polish
        },
        options={k: getattr(opt, k) for k in opt.__dataclass_fields__},
        records=data.labels,
    )
    prog.update(
        None,
        f"done in {log['seconds']:.1f} s: RMS error {log['cost_n']:.4g} N on all records "
        f"(RMS ratio {log['rms_ratio']:.4f}), {log['evaluations']} simulations",
        force=True,
    )
    model.training = log
    return model


def _work(search: PopulationCost, whole: PopulationCost) -> float:
    return search.evaluations * search.samples + whole.evaluations * whole.samples


def _evolve(search, whole, opt: BoucWenOptions, seed: int, prog: Progress):
    """Differential evolution on ``search``; returns the best vector and the log so far."""
    gen, best, stopped = [0], [np.inf], ["generations done"]

    def de_cost(u: np.ndarray) -> np.ndarray:  # u: (14, S)
        c = search(u)
        best[0] = min(best[0], float(np.min(c)))
        prog.update(
            _work(search, whole),
            f"generation {gen[0]}/{opt.generations}: {search.evaluations} evaluations, "
            f"best RMS error {best[0]:.4g} N",
        )
        return c

    def callback(intermediate_result) -> bool:
        gen[0] += 1
        if opt.time_limit_s and prog.elapsed_s() > opt.time_limit_s:
            stopped[0] = (
                f"time limit {opt.time_limit_s:g} s hit after {gen[0]} of {opt.generations} "
                "generations"
            )
            prog.say(f"stopped early: {stopped[0]}")
            return True
        return False

    result = differential_evolution(
        de_cost,
        SEARCH_BOUNDS,
        maxiter=opt.generations,
        popsize=opt.population,
        seed=seed,
        polish=False,
        vectorized=True,
        updating="deferred",
        workers=1,
        init="sobol",
        tol=0.0,
        callback=callback,
    )
    u_best = np.asarray(result.x)
    de_cost_fit = float(search(u_best[:, None])[0])
    # The search scores the first fit_seconds only; the member the polish starts from is the
    # final population's best on ALL of the records (a member that fits the first seconds best
    # can be far off on the rest: a cubic bushing's 8 s best was 42 % off over 40 s).
    on_all = whole(np.asarray(result.population).T)
    pick = int(np.argmin(on_all))
    if np.isfinite(on_all[pick]):
        u_best = np.asarray(result.population[pick])
    prog.update(
        _work(search, whole),
        f"differential evolution: {gen[0]} generations ({stopped[0]}), RMS error on the first "
        f"{search.samples * search.dt:.1f} s {de_cost_fit:.4g} N",
        force=True,
    )
    log = {"generations": gen[0], "stopped": stopped[0], "de_cost_fit_n": de_cost_fit}
    log["polish_start_rank_on_search"] = int(
        np.argsort(np.argsort(result.population_energies))[pick]
    )
    log["time_limited"] = stopped[0] != "generations done"
    return u_best, log


def _polish(whole, search, u_best: np.ndarray, opt: BoucWenOptions, prog: Progress):
    """Bounded Powell on all records from ``u_best``; (vector, cost before, cost after), N."""

    def full_cost(u: np.ndarray) -> float:
        c = float(whole(np.asarray(u)[:, None])[0])
        prog.update(
            _work(search, whole),
            f"polish: {whole.evaluations} evaluations, RMS error on all records {c:.4g} N",
        )
        return c if np.isfinite(c) else 1e300

    cost_before = full_cost(u_best)
    if opt.polish_evaluations > 0:
        pol = minimize(
            full_cost,
            u_best,
            method="Powell",
            bounds=SEARCH_BOUNDS,
            options={"maxfev": int(opt.polish_evaluations), "xtol": 1e-4, "ftol": 1e-6},
        )
        if pol.fun < cost_before:
            u_best = np.asarray(pol.x)
    return u_best, cost_before, full_cost(u_best)
