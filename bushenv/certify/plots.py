"""The certificate's plots (matplotlib Agg), for any number of coordinates C: static force and
spectral radius along each coordinate (the others at rest), the spectral radius over each pair
of coordinates (C > 1), and the least loss eigenvalue about each passivity hold."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from bushenv.certify.certificate import Certificate
from bushenv.persist import save_figure


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _finish(fig, path: Path) -> Path:
    """Lay out, write atomically, close."""
    fig.tight_layout()
    out = save_figure(fig, path)
    _pyplot().close(fig)
    return out


def _label(cert: Certificate, j: int) -> str:
    unit = "mrad" if cert.net.units[j] == "rad" else "mm"
    name = cert.net.coords[j]
    return f"held {name} [{unit}]" if cert.net.n_coords > 1 else f"held displacement x [{unit}]"


def _force_unit(cert: Certificate, j: int) -> str:
    return "N m" if cert.net.units[j] == "rad" else "N"


def _along(cert: Certificate, j: int) -> np.ndarray:
    """Indices of the grid's holds on coordinate j's axis (the others at rest), by q_j."""
    q = cert.fp.q
    rest = np.all(np.delete(q, j, axis=1) == 0, axis=1)
    idx = np.flatnonzero(rest)
    return idx[np.argsort(q[idx, j], kind="stable")]


def _panels(cert: Certificate, height: float):
    plt = _pyplot()
    c = cert.net.n_coords
    fig, axs = plt.subplots(1, c, figsize=(7.5 if c == 1 else 4.6 * c, height), squeeze=False)
    return fig, axs[0]


def _folds(ax, cert: Certificate, j: int) -> None:
    for k, f in enumerate(cert.folds):
        if all(v == 0 for i, v in enumerate(f.q) if i != j):
            lab = "fold" if k == 0 else None
            ax.axvline(f.q[j] * 1e3, color="tab:purple", ls=":", lw=1, label=lab)


def static_force_plot(cert: Certificate, path: Path, title: str) -> Path:
    """Fixed-point force vs held deflection beside the reference's settled force, along each
    coordinate: where the free run settles, where it lingers before departing, wrong signs."""
    fp, holds = cert.fp, cert.document["holds"]
    fig, axs = _panels(cert, 4.5)
    for j, ax in enumerate(axs):
        idx = _along(cert, j)
        x = fp.q[idx, j] * 1e3
        ax.plot(x, cert.reference_static[idx, j], color="black", lw=1.5,
                label="reference, settled hold")  # fmt: skip
        pts = np.concatenate([fp.of_hold(i) for i in idx]) if idx.size else np.zeros(0, int)
        st = fp.stable[pts]
        px, pf = fp.q[fp.hold[pts], j] * 1e3, fp.force[pts, j]
        ax.plot(px[st], pf[st], "o", ms=3, color="tab:blue", label="stable fixed point")
        if np.any(~st):
            ax.plot(px[~st], pf[~st], "o", ms=4, mfc="none", color="tab:red",
                    label="unstable fixed point")  # fmt: skip
        runs = [(fp.q[i, j] * 1e3, fp.force[fp.of_hold(i)[cert.runs[i].reached], j]) for i in idx
                if cert.runs[i].reached is not None]  # fmt: skip
        if runs:
            rx, rf = np.array(runs).T
            ax.plot(rx, rf, "-", color="tab:blue", lw=0.8, alpha=0.6, label="free run settles at")
        step = np.diff(x[:2])[0] if x.size > 1 else 1.0
        for k, i in enumerate([i for i in idx if holds[i]["wrong_sign"]]):
            ax.axvspan(fp.q[i, j] * 1e3 - 0.5 * step, fp.q[i, j] * 1e3 + 0.5 * step,
                       color="tab:orange", alpha=0.3, lw=0,
                       label="wrong sign" if k == 0 else None)  # fmt: skip
        dep = [
            (fp.q[i, j] * 1e3, cert.runs[i].linger_force[j]) for i in idx if cert.runs[i].departs
        ]
        if dep:
            dx, df = np.array(dep).T
            ax.plot(dx, df, "x", ms=8, color="tab:red", label="departs: lingers here, then jumps")
        _folds(ax, cert, j)
        ax.axhline(0, color="grey", lw=0.5)
        ax.set_xlabel(_label(cert, j))
        ax.set_ylabel(f"static force [{_force_unit(cert, j)}]")
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
    fig.suptitle(title)
    return _finish(fig, path)


def spectral_radius_plot(cert: Certificate, path: Path, title: str) -> Path:
    """Spectral radius of every fixed point vs held deflection, along each coordinate."""
    fp = cert.fp
    fig, axs = _panels(cert, 3.8)
    for j, ax in enumerate(axs):
        idx = _along(cert, j)
        pts = np.concatenate([fp.of_hold(i) for i in idx]) if idx.size else np.zeros(0, int)
        st, x = fp.stable[pts], fp.q[fp.hold[pts], j] * 1e3
        rho = fp.spectral_radius[pts]
        ax.plot(x[st], rho[st], "o", ms=3, color="tab:blue", label="stable")
        if np.any(~st):
            ax.plot(x[~st], rho[~st], "o", ms=4, mfc="none", color="tab:red", label="unstable")
        ax.axhline(1.0, color="black", lw=1, ls="--", label="stability limit")
        _folds(ax, cert, j)
        ax.set_xlabel(_label(cert, j))
        ax.set_ylabel("spectral radius of the companion Jacobian [-]")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
    fig.suptitle(title)
    return _finish(fig, path)


def radius_map_plot(cert: Certificate, path: Path, title: str) -> Path | None:
    """Each pair of coordinates: the largest spectral radius of each hold's stable points,
    the largest over the other coordinates, as a map (mm, mrad), holds without a stable point
    marked. None for one coordinate (no pair)."""
    c = cert.net.n_coords
    pairs = [(i, j) for i in range(c) for j in range(i + 1, c)]
    if not pairs:
        return None
    plt, fp = _pyplot(), cert.fp
    worst = np.full(len(fp.q), np.inf)
    for h in range(len(fp.q)):
        r = fp.spectral_radius[(fp.hold == h) & fp.stable]
        if r.size:
            worst[h] = r.max()
    radius = worst.reshape(*(len(a) for a in cert.axes))
    fig, axs = plt.subplots(1, len(pairs), figsize=(4.2 * len(pairs), 3.8), squeeze=False)
    finite = radius[np.isfinite(radius)]
    vmax = max(1.0, float(finite.max())) if finite.size else 1.0
    for ax, (i, j) in zip(axs[0], pairs, strict=True):
        other = tuple(k for k in range(c) if k not in (i, j))
        plane = radius.max(axis=other) if other else radius
        shown = np.where(np.isfinite(plane), plane, np.nan)
        xi, xj = cert.axes[i] * 1e3, cert.axes[j] * 1e3
        mesh = ax.pcolormesh(xj, xi, shown, vmin=0.0, vmax=vmax, cmap="viridis", shading="nearest")
        none = ~np.isfinite(plane)
        if none.any():
            jj, ii = np.meshgrid(xj, xi)
            ax.plot(jj[none], ii[none], "rx", label="no stable fixed point")
            ax.legend(loc="upper right", fontsize=7)
        ax.set_xlabel(_label(cert, j))
        ax.set_ylabel(_label(cert, i))
        fig.colorbar(mesh, ax=ax, label="largest spectral radius (max over the others)")
    fig.suptitle(title)
    return _finish(fig, path)


def passivity_plot(cert: Certificate, path: Path, title: str) -> Path:
    """The least loss eigenvalue (work per cycle / pi on the worst motion; one coordinate:
    A^2 Im K) about each passivity hold beside the reference's, and, for one coordinate, where
    the judge's ``energy`` criterion fired on sines from rest (bottom)."""
    plt = _pyplot()
    scan = cert.document["passivity"]["energy_scan"]
    if scan is None:
        fig, ax = plt.subplots(figsize=(7.5, 4.5))
    else:
        fig, (ax, bx) = plt.subplots(
            2, 1, figsize=(7.5, 6.0), sharex=True, gridspec_kw={"height_ratios": [3, 1]}
        )
    colors = plt.cm.viridis(np.linspace(0, 0.9, max(1, len(cert.passivity))))
    for e, col in zip(cert.passivity, colors, strict=False):
        at = ", ".join(f"{v * 1e3:+g}" for v in e["q"])
        for k, eig in enumerate(np.asarray(e["loss_eigenvalues_j"])):
            ax.plot(e["frequency_hz"], eig[:, 0], color=col, lw=1.2,
                    label=f"model, hold ({at}) mm|mrad" if k == 0 else None)  # fmt: skip
        ref = np.asarray(e["reference_loss_eigenvalues_j"])
        if np.isfinite(ref).any():
            ax.plot(e["reference_frequency_hz"], ref[:, 0], "--", color=col, lw=1,
                    label=f"reference, hold ({at})")  # fmt: skip
    ax.axhline(0, color="black", lw=0.8)
    ax.set_ylabel("least loss eigenvalue [J]\n(work per cycle / pi)")
    ax.set_title(title)
    ax.legend(fontsize=7, ncol=2)
    ax.grid(alpha=0.3)
    if scan is None:
        ax.set_xlabel("frequency [Hz]")
        return _finish(fig, path)
    freq = np.asarray(scan["frequency_hz"])
    for amp, row in zip(scan["amplitudes_m"], scan["fires"], strict=True):
        on = np.array([f is True for f in row])
        off = np.array([f is False for f in row])
        bx.plot(freq[off], np.full(off.sum(), amp * 1e3), "o", ms=3, color="lightgrey")
        bx.plot(freq[on], np.full(on.sum(), amp * 1e3), "s", ms=4, color="tab:red")
    bx.plot([], [], "s", color="tab:red", label="energy criterion fires")
    bx.plot([], [], "o", color="lightgrey", label="bounded")
    bx.set_yscale("log")
    bx.set_yticks([a * 1e3 for a in scan["amplitudes_m"]])
    bx.set_yticklabels([f"{a * 1e3:g}" for a in scan["amplitudes_m"]])
    bx.minorticks_off()
    bx.set_xlabel("frequency [Hz]")
    bx.set_ylabel("sine amplitude [mm]")
    bx.legend(fontsize=7, loc="upper left")
    bx.grid(alpha=0.3)
    return _finish(fig, path)


def certificate_plots(cert: Certificate, out: Path, name: str) -> list[Path]:
    """Every plot of ``cert`` that applies, written into ``out``."""
    paths = [
        static_force_plot(cert, out / "static_force.png", f"{name}: static force in a hold"),
        spectral_radius_plot(cert, out / "spectral_radius.png", f"{name}: hold stability"),
        radius_map_plot(cert, out / "spectral_radius_map.png", f"{name}: hold stability"),
        passivity_plot(cert, out / "passivity.png", f"{name}: small-signal loss"),
    ]
    return [p for p in paths if p is not None]
