"""The comparisons a user would make, for scripts/bench.py (sections ``scipy`` and ``torch``).

- Bouc-Wen: scipy's ``solve_ivp`` (LSODA, Radau) on seed 002 eqs. 1-4 as printed, one profile
  per call as a user writes it, the tolerance tuned until its error against the converged run is
  no larger than bushenv's on the same profile; steps/s beside bushenv's kernel on that profile
  (one thread) and beside the batched two-thread figure of the same run.
- NARX: the same network as a torch ``nn.Module`` (the layers filled with the shipped model's
  weights), stepped over time on its own past outputs, batched over profiles, under
  ``torch.no_grad()``, with one and with two threads; steps/s beside bushenv's kernel on the
  same profiles with the same threads. The two must agree (checked, reported).
"""

from __future__ import annotations

import time

import numpy as np

SCIPY_METHODS = ("LSODA", "Radau")
SCIPY_RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)  # tried loosest first


def _time(fn, min_time: float) -> float:
    fn()
    reps, t0 = 0, time.perf_counter()
    while reps < 2 or time.perf_counter() - t0 < min_time:
        fn()
        reps += 1
    return (time.perf_counter() - t0) / reps


def scipy_free_run(p: dict, x: np.ndarray, v: np.ndarray, dt: float, method: str, rtol: float):
    """Eqs. 1-5 by ``solve_ivp`` over the whole record from rest, x and x' linear between
    samples (as bushenv's kernel takes them): forces at the samples, (T,)."""
    from scipy.integrate import solve_ivp

    X = np.concatenate([[0.0], x])  # rest at t = 0, sample t at (t + 1) dt
    U = np.concatenate([[0.0], v])
    T = len(x)
    c0, k0, c1, k1, c2, k2 = (p[k] for k in ("c0", "k0", "c1", "k1", "c2", "k2"))
    A1, A2, b1, b2, g1, g2 = (p[k] for k in ("A1", "A2", "beta1", "beta2", "gamma1", "gamma2"))
    n1, n2, a1, a2 = (p[k] for k in ("n1", "n2", "a1", "a2"))

    def rhs(t, s):
        y, w, z1, z2 = s
        k = min(int(t / dt), T - 1)
        fr = t / dt - k
        xx = X[k] + fr * (X[k + 1] - X[k])
        u = U[k] + fr * (U[k + 1] - U[k])
        dy = (c1 * u + k1 * (xx - y) - k0 * y + a1 * z1) / c1  # eq. 3
        dw = (c2 * u + k2 * (xx - w) + a2 * z2) / (c0 + c2)  # eq. 4
        d1, d2 = u - dy, u - dw
        dz1 = d1 * (A1 - (g1 + b1 * np.sign(d1) * np.sign(z1)) * abs(z1) ** n1)  # eq. 1
        dz2 = d2 * (A2 - (g2 + b2 * np.sign(d2) * np.sign(z2)) * abs(z2) ** n2)  # eq. 2
        return [dy, dw, dz1, dz2]

    times = dt * np.arange(1, T + 1)
    # absolute tolerance per state from its size on this record (what a user would look at)
    scale = np.array([1e-3, 1e-3, 1e-4, 1e-4])
    sol = solve_ivp(rhs, (0.0, T * dt), np.zeros(4), method=method, t_eval=times,
                    rtol=rtol, atol=rtol * scale)  # fmt: skip
    if not sol.success:
        raise RuntimeError(f"solve_ivp {method} rtol {rtol:g}: {sol.message}")
    y, w, _, z2 = sol.y
    dw = (c2 * v + k2 * (x - w) + a2 * z2) / (c0 + c2)
    return k0 * y + c0 * dw  # eq. 5


def bench_scipy(fig, quick: bool) -> None:
    """Bouc-Wen: solve_ivp at bushenv's accuracy, steps/s, as ratios."""
    from boucwen_converged import converged  # tests/models, on sys.path by bench.py

    from bushenv.excitation import random_rpc
    from bushenv.models import get_model

    print("\n== Bouc-Wen beside scipy's solve_ivp at the same accuracy (one profile, one thread)")
    model = get_model("boucwen", axis="axial")
    dt = model.dt
    x = random_rpc(1.0, 0.5 if quick else 4.0, dt, seed=0)
    v = np.gradient(x, dt)
    T = len(x)
    ref = converged(model.vector()[:, None], x[:, None], v[:, None])[:, 0]
    peak = float(np.max(np.abs(ref)))
    ours = float(np.max(np.abs(model.simulate(x, v) - ref))) / peak
    sec = _time(lambda: model.simulate(x, v), 0.05 if quick else 0.5)
    ours_rate = fig.add(
        "compare.boucwen.bushenv_B1",
        T / sec,
        "steps/s",
        note=f"axial, random n = 1 ({T} samples); error {ours:.2g} of peak",
    )
    fig.add("compare.boucwen.bushenv_B1.error_vs_converged", ours, "of peak", better="lower")
    batched = next((r["value"] for r in fig.rows
                    if r["name"] == "free_run.boucwen.B1024.threads2"), None)  # fmt: skip
    for method in SCIPY_METHODS:
        chosen = None
        for rtol in SCIPY_RTOLS:
            err = float(np.max(np.abs(scipy_free_run(model.params, x, v, dt, method, rtol) - ref)))
            if err / peak <= ours:
                chosen = (rtol, err / peak)
                break
        if chosen is None:
            print(f"  solve_ivp {method}: no rtol down to {SCIPY_RTOLS[-1]:g} reached {ours:.2g}")
            continue
        rtol, err = chosen
        sec = _time(lambda m=method, r=rtol: scipy_free_run(model.params, x, v, dt, m, r), 0.0)
        rate = fig.add(f"compare.boucwen.scipy_{method}", T / sec, "steps/s",
                       note=f"rtol {rtol:g} (the loosest of {SCIPY_RTOLS} at bushenv's error); "
                       f"error {err:.2g} of peak")  # fmt: skip
        fig.add(f"compare.boucwen.bushenv_B1_over_scipy_{method}", ours_rate / rate, "x",
                note="same profile, one thread")  # fmt: skip
        if batched is not None:
            name = f"compare.boucwen.bushenv_B1024_threads2_over_scipy_{method}"
            fig.add(name, batched / rate, "x", note="free_run.boucwen.B1024.threads2 / scipy")


def narx_torch_module(model):
    """The shipped NARX network as a torch nn.Module, its layers filled with its weights."""
    import torch

    class Narx(torch.nn.Module):
        def __init__(self):
            super().__init__()
            layers = [torch.nn.Linear(model.w1.shape[1], model.w1.shape[0])]
            if model.w2.shape[0]:
                layers.append(torch.nn.Linear(model.w2.shape[1], model.w2.shape[0]))
            self.hidden = torch.nn.ModuleList(layers)
            self.out = torch.nn.Linear(len(model.w_out), 1)

        def forward(self, inp):
            h = inp
            for layer in self.hidden:
                h = torch.tanh(layer(h))
            return self.out(h)[:, 0]

    net = Narx().double()
    with torch.no_grad():
        pairs = [(model.w1, model.b1)] + ([(model.w2, model.b2)] if model.w2.shape[0] else [])
        for layer, (w, b) in zip(net.hidden, pairs, strict=True):
            layer.weight.copy_(torch.from_numpy(w))
            layer.bias.copy_(torch.from_numpy(b))
        net.out.weight.copy_(torch.from_numpy(model.w_out[None, :]))
        net.out.bias.fill_(model.b_out)
    return net


def torch_free_run(net, model, x: np.ndarray) -> np.ndarray:
    """Free run of (T, B) displacements the way a user writes it: scaled inputs, the net fed
    its own past outputs, one step at a time, batched over profiles. Forces (T, B)."""
    import torch

    with torch.no_grad():
        xs = (torch.from_numpy(x) - model.x_offset_m) / model.x_scale_m
        T, B = xs.shape
        past_x = torch.full((B, model.n_past_x), -model.x_offset_m / model.x_scale_m,
                            dtype=torch.float64)  # fmt: skip
        past_f = torch.full((B, model.n_past_f), -model.f_offset_n / model.f_scale_n,
                            dtype=torch.float64)  # fmt: skip
        out = torch.empty((T, B), dtype=torch.float64)
        for t in range(T):
            cur = xs[t][:, None]
            y = net(torch.cat([cur, past_x, past_f], dim=1))
            out[t] = model.f_offset_n + model.f_scale_n * y
            past_x = torch.cat([cur, past_x[:, :-1]], dim=1)
            past_f = torch.cat([y[:, None], past_f[:, :-1]], dim=1)
    return out.numpy()


def bench_torch(fig, quick: bool) -> None:
    """NARX: the network as a user writes it in torch, beside bushenv's kernel."""
    import torch

    from bushenv.excitation import random_rpc
    from bushenv.models import get_model

    print("\n== NARX beside the same network in torch (nn.Module, no_grad, batched)")
    model = get_model("nn", axis="axial")
    T, B = (64, 64) if quick else (512, 1024)
    x = np.stack([random_rpc(1.0, T * model.dt, model.dt, seed=b) for b in range(B)], 1)
    net = narx_torch_module(model)
    ours = model.simulate(x)
    theirs = torch_free_run(net, model, x)
    agreement = float(np.max(np.abs(theirs - ours)) / np.max(np.abs(ours)))
    fig.add("compare.nn.torch_agreement", agreement, "of peak", better="lower",
            note="max |torch - bushenv| / peak: the same network")  # fmt: skip
    before = torch.get_num_threads()
    try:
        for threads in (1, 2):
            torch.set_num_threads(threads)
            sec_t = _time(lambda: torch_free_run(net, model, x), 0.0 if quick else 1.0)
            rate_t = fig.add(f"compare.nn.torch.threads{threads}", T * B / sec_t, "steps/s",
                             note=f"B = {B}, T = {T}")  # fmt: skip
            sec_b = _time(lambda t=threads: model.simulate(x, threads=t), 0.05 if quick else 0.5)
            rate_b = fig.add(f"compare.nn.bushenv.threads{threads}", T * B / sec_b, "steps/s")
            fig.add(f"compare.nn.bushenv_over_torch.threads{threads}", rate_b / rate_t, "x")
    finally:
        torch.set_num_threads(before)
