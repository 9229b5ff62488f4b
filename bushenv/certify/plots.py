"""The certificate's plots (matplotlib Agg): static force, spectral radius, Im K."""

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


def _folds(ax, cert: Certificate) -> None:
    for k, f in enumerate(cert.folds):
        ax.axvline(f.x_m * 1e3, color="tab:purple", ls=":", lw=1, label="fold" if k == 0 else None)


def static_force_plot(cert: Certificate, path: Path, title: str) -> Path:
    """Fixed-point force vs held displacement beside the reference's settled force."""
    plt = _pyplot()
    fp = cert.fp
    x_mm = fp.x_m * 1e3
    fig, ax = plt.subplots(figsize=(7.5, 4.5))
    ax.plot(x_mm, cert.reference_static_n, color="black", lw=1.5, label="reference, settled hold")
    st = fp.stable
    ax.plot(
        fp.point_x_m[st] * 1e3,
        fp.force_n[st],
        "o",
        ms=3,
        color="tab:blue",
        label="stable fixed point",
    )
    if np.any(~st):
        ax.plot(
            fp.point_x_m[~st] * 1e3,
            fp.force_n[~st],
            "o",
            ms=4,
            mfc="none",
            color="tab:red",
            label="unstable fixed point",
        )
    reached = [
        (x_mm[i], fp.force_n[fp.of_hold(i)[r.reached]])
        for i, r in enumerate(cert.runs)
        if r.reached is not None
    ]
    if reached:
        rx, rf = np.array(reached).T
        ax.plot(rx, rf, "-", color="tab:blue", lw=0.8, alpha=0.6, label="free run settles at")
    wrong = np.array([h["wrong_sign"] for h in cert.document["holds"]])
    for k, i in enumerate(np.flatnonzero(wrong)):
        ax.axvspan(
            x_mm[i] - 0.5 * np.diff(x_mm[:2])[0],
            x_mm[i] + 0.5 * np.diff(x_mm[:2])[0],
            color="tab:orange",
            alpha=0.3,
            lw=0,
            label="wrong sign" if k == 0 else None,
        )
    dep = [(x_mm[i], r.linger_force_n) for i, r in enumerate(cert.runs) if r.departs]
    if dep:
        dx, df = np.array(dep).T
        ax.plot(dx, df, "x", ms=8, color="tab:red", label="departs: lingers here, then jumps")
    _folds(ax, cert)
    ax.axhline(0, color="grey", lw=0.5)
    ax.set_xlabel("held displacement x [mm]")
    ax.set_ylabel("static force [N]")
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return _finish(fig, path)


def spectral_radius_plot(cert: Certificate, path: Path, title: str) -> Path:
    """Spectral radius of every fixed point vs held displacement."""
    plt = _pyplot()
    fp = cert.fp
    fig, ax = plt.subplots(figsize=(7.5, 3.8))
    st = fp.stable
    ax.plot(
        fp.point_x_m[st] * 1e3, fp.spectral_radius[st], "o", ms=3, color="tab:blue", label="stable"
    )
    if np.any(~st):
        ax.plot(
            fp.point_x_m[~st] * 1e3,
            fp.spectral_radius[~st],
            "o",
            ms=4,
            mfc="none",
            color="tab:red",
            label="unstable",
        )
    ax.axhline(1.0, color="black", lw=1, ls="--", label="stability limit")
    _folds(ax, cert)
    ax.set_xlabel("held displacement x [mm]")
    ax.set_ylabel("spectral radius of the companion Jacobian [-]")
    ax.set_title(title)
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return _finish(fig, path)


def passivity_plot(cert: Certificate, path: Path, title: str) -> Path:
    """Im K about each passivity hold beside the reference's (top) and where the judge's
    ``energy`` criterion fired on sines from rest (bottom)."""
    plt = _pyplot()
    fig, (ax, bx) = plt.subplots(
        2, 1, figsize=(7.5, 6.0), sharex=True, gridspec_kw={"height_ratios": [3, 1]}
    )
    colors = plt.cm.viridis(np.linspace(0, 0.9, max(1, len(cert.passivity))))
    for e, col in zip(cert.passivity, colors, strict=False):
        mm = f"{e['x_m'] * 1e3:+g} mm"
        for k, imk in enumerate(np.atleast_2d(e["im_k_n_per_m"])):
            ax.plot(
                e["frequency_hz"],
                imk / 1e3,
                color=col,
                lw=1.2,
                label=f"model, hold {mm}" if k == 0 else None,
            )
        ax.plot(
            e["reference_frequency_hz"],
            np.asarray(e["reference_im_k_n_per_m"]) / 1e3,
            "--",
            color=col,
            lw=1,
            label=f"reference, hold {mm}",
        )
    ax.axhline(0, color="black", lw=0.8)
    ax.set_ylabel("Im K [kN/m]\n(work per cycle = pi A^2 Im K)")
    ax.set_title(title)
    ax.legend(fontsize=7, ncol=2)
    ax.grid(alpha=0.3)
    scan = cert.document["passivity"]["energy_scan"]
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
