"""The certificate of a NARX bushing over C > 1 coordinates: the one-axis certificate's
questions asked of held deflection *vectors*.

- **Holds.** On a grid of ``per_coordinate`` values per coordinate over +- ``span`` (odd, so
  rest is a hold), every fixed point of the network's held recurrence and its stability
  (``bushenv.planar.fixed_points``: interval boxes, Krawczyk's uniqueness test, the block
  companion matrix's spectral radius), and where the number of fixed points changes along the
  grid's edges (fold surfaces). A hold passes when it has exactly one fixed point and it is
  stable: the free run settles to one force whatever came before.
- **Wrong sign, without a reference.** A passive bushing stores energy in a held deflection:
  the static force points away from rest, q . f >= 0 (for f = grad W with W convex and least at
  rest, q . grad W(q) >= W(q) - W(0) >= 0). A stable fixed point with q . f below
  ``-WRONG_SIGN_N`` x (|q_t| + ``LEVER_M`` |q_r|) (translations q_t in m, rotations q_r in rad)
  pulls the bushing further out: wrong sign. C = 1 is the one-axis rule F x < 0 beyond 10 N.
- **Passivity as a matrix test** at rest and at +- ``passivity_fraction`` of the span along
  each coordinate (``bushenv.planar.passivity``: the loss matrix H_I(w) of the dynamic
  stiffness must be positive semidefinite; a negative eigenvalue is a motion that returns
  energy every cycle).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

WRONG_SIGN_N = 10.0  # the one-axis certificate's force beyond which a sign counts (N)
LEVER_M = 0.04  # metres per radian when a moment's work is weighed against a force's


@dataclass(frozen=True)
class VectorOptions:
    """The grid and the passivity holds. ``span`` (C,) half-widths, m or rad."""

    span: tuple[float, ...]
    per_coordinate: int = 7
    passivity_fraction: float = 0.5
    frequencies: int = 40

    def checked(self, coords: int) -> VectorOptions:
        from bushenv.certify.network import CertifyError

        if len(self.span) != coords or not all(np.isfinite(s) and s > 0 for s in self.span):
            raise CertifyError(f"span must be {coords} positive numbers, got {self.span}")
        if self.per_coordinate < 3:
            raise CertifyError(f"holds per coordinate must be >= 3, got {self.per_coordinate}")
        return self


def per_coordinate(holds: int, coords: int) -> int:
    """Holds per coordinate for about ``holds`` holds in all: odd (rest among them), >= 3."""
    n = max(3, int(round(holds ** (1.0 / coords))))
    return n if n % 2 else n + 1


def wrong_sign(q: np.ndarray, force: np.ndarray, units: tuple[str, ...]) -> np.ndarray:
    """(P,) whether the static force ``force`` (P, C) at holds ``q`` (P, C) pulls outward."""
    lever = np.array([LEVER_M if u == "rad" else 1.0 for u in units])
    work = np.sum(q * force, axis=1)
    return work < -WRONG_SIGN_N * np.sum(np.abs(q) * lever, axis=1)


def certify_vector(
    model: Any, opts: VectorOptions, progress: Callable[[str, float], None] | None = None
) -> tuple[dict[str, Any], dict[str, Any]]:
    """The certificate document of a NARX ``model`` over C > 1 coordinates, and the grid of
    the largest spectral radius per hold (for ``radius_plot``)."""
    from bushenv.certify.network import CertifyError
    from bushenv.models.planar_narx import PlanarNarx
    from bushenv.planar.fixed_points import fixed_points, fold_crossings, grid
    from bushenv.planar.passivity import passivity

    if not isinstance(model, PlanarNarx):
        raise CertifyError(
            f"{model.name} has no recurrence to certify: the certificate is of NARX networks "
            "(nn, nn-axis, hybrid, hybrid-bw); a linear or Bouc-Wen model holds by construction"
        )
    c = model.n_coords
    opts = opts.checked(c)
    say = progress or (lambda stage, fraction: None)
    axes = [np.linspace(-s, s, opts.per_coordinate) for s in opts.span]
    say("fixed points at every hold", 0.0)
    fp = fixed_points(model, grid(*axes))
    say("fold surfaces", 0.5)
    folds = fold_crossings(model, *axes, fp=fp)
    n, stable_n = fp.count, fp.stable_count
    bad_sign = wrong_sign(fp.q[fp.hold], fp.force, model.units) & fp.stable
    sign_holds = np.unique(fp.hold[bad_sign])
    say("passivity about holds", 0.7)
    p_holds = [np.zeros(c)]
    for i in range(c):
        for sgn in (1.0, -1.0):
            q0 = np.zeros(c)
            q0[i] = sgn * opts.passivity_fraction * opts.span[i]
            p_holds.append(q0)
    nyquist = 0.5 / model.dt
    freq = np.geomspace(0.1, 0.9 * nyquist, opts.frequencies)
    pas = passivity(model, np.array(p_holds), freq)
    active = pas.active_bands()
    say("done", 1.0)
    settling = int(np.sum((n == 1) & (stable_n == 1)))
    summary = {
        "holds": int(len(n)),
        "holds_settling_stably": settling,
        "holds_with_more_than_one": int(np.sum(n > 1)),
        "holds_without_a_stable_one": int(np.sum(stable_n == 0)),
        "unresolved_boxes": int(fp.unresolved.sum()),
        "largest_spectral_radius": float(fp.spectral_radius.max()) if len(fp.y) else None,
        "fold_crossings": len(folds),
        "wrong_sign_holds": int(len(sign_holds)),
        "passivity_holds": len(pas.q),
        "passivity_holds_without_a_stable_point": int(len(pas.no_stable)),
        "non_passive_holds": len(active),
        "least_loss_eigenvalue_j": pas.min_eig,
    }
    summary["passes_holds"] = (
        settling == len(n) and not folds and not len(sign_holds) and not fp.unresolved.any()
    )
    summary["passes_passivity"] = not active and not len(pas.no_stable)
    return {
        "format": "bushenv-certificate",
        "coords": list(model.coords),
        "units": list(model.units),
        "settings": {
            "span": list(opts.span),
            "per_coordinate": opts.per_coordinate,
            "passivity_fraction": opts.passivity_fraction,
            "frequencies_hz": [float(freq[0]), float(freq[-1]), len(freq)],
            "wrong_sign_rule": (
                f"q . f < -{WRONG_SIGN_N:g} N x (|q_translations| + {LEVER_M:g} m/rad "
                "|q_rotations|) at a stable fixed point"
            ),
        },
        "summary": summary,
        "holds": [
            {
                "q": fp.q[h].tolist(),
                "fixed_points": int(n[h]),
                "stable": int(stable_n[h]),
                "forces": fp.force[fp.hold == h].tolist(),
                "spectral_radius": fp.spectral_radius[fp.hold == h].tolist(),
            }
            for h in range(len(n))
            if n[h] != 1 or stable_n[h] != 1 or h in set(sign_holds.tolist())
        ],
        "wrong_sign_at": [fp.q[h].tolist() for h in sign_holds],
        "folds": [{"q": list(f.q), "from": f.count_from, "to": f.count_to} for f in folds],
        "non_passive": [
            {"q": pas.q[row].tolist(), "bands_hz": [list(b) for b in bands]}
            for row, bands in active
        ],
    }, {"axes": [a.tolist() for a in axes], "radius": _radius_grid(fp, axes)}


def _radius_grid(fp: Any, axes: list[np.ndarray]) -> list:
    """The largest spectral radius of each hold's stable points (inf where none), on the grid."""
    worst = np.full(len(fp.q), np.inf)
    for h in range(len(fp.q)):
        r = fp.spectral_radius[(fp.hold == h) & fp.stable]
        if r.size:
            worst[h] = r.max()
    return worst.reshape(*(len(a) for a in axes)).tolist()


def radius_plot(doc: dict[str, Any], grid: dict[str, Any], path: Any, title: str) -> Any:
    """Each pair of coordinates: the largest spectral radius over the others, as a map (mm,
    mrad), holds without a stable point marked; saved to ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    radius = np.array(grid["radius"], dtype=float)
    axes = [np.array(a) for a in grid["axes"]]
    coords, units = doc["coords"], doc["units"]
    scale = [1e3 for _ in units]  # m -> mm, rad -> mrad
    label = [f"{c} [{'mrad' if u == 'rad' else 'mm'}]" for c, u in zip(coords, units, strict=True)]
    pairs = [(i, j) for i in range(len(coords)) for j in range(i + 1, len(coords))]
    fig, axs = plt.subplots(1, len(pairs), figsize=(4.2 * len(pairs), 3.8), squeeze=False)
    finite = radius[np.isfinite(radius)]
    vmax = max(1.0, float(finite.max())) if finite.size else 1.0
    for ax, (i, j) in zip(axs[0], pairs, strict=True):
        other = tuple(k for k in range(len(coords)) if k not in (i, j))
        plane = radius.max(axis=other) if other else radius
        shown = np.where(np.isfinite(plane), plane, np.nan)
        mesh = ax.pcolormesh(axes[j] * scale[j], axes[i] * scale[i], shown, vmin=0.0, vmax=vmax,
                             cmap="viridis", shading="nearest")  # fmt: skip
        none = ~np.isfinite(plane)
        if none.any():
            jj, ii = np.meshgrid(axes[j] * scale[j], axes[i] * scale[i])
            ax.plot(jj[none], ii[none], "rx", label="no stable fixed point")
            ax.legend(loc="upper right", fontsize=7)
        ax.set_xlabel(label[j])
        ax.set_ylabel(label[i])
        fig.colorbar(mesh, ax=ax, label="largest spectral radius (max over the others)")
    fig.suptitle(title)
    fig.tight_layout()
    from bushenv.persist import write_figure

    return write_figure(fig, path)
