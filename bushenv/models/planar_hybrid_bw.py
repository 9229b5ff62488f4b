"""MIMO hybrid on a vector Bouc-Wen backbone: f = f_bw(q history) + f_nn.

    f = [K q + C v + G3(q) + h (.) z]  +  f_nn       (backbone: ``boucwen.PlanarBoucWen``)

The backbone is the vector Bouc-Wen (3x3 K and C, cubic stiffness G, one hysteretic state on
the deflection vector), the network the MIMO NARX of ``narx.py`` fed with its own past
residual outputs, as in the matrix-backbone ``hybrid``. The backbone carries what physics
gives (stiffness, damping, the shared yield surface); the network what is left (relaxation,
the elastic coupling's shape). Bounded as the hybrid: |f_nn,i| <= ``nn_bound()``; the
backbone is bounded by |K q + C v + G3(q)| + |h| because |z| <= 1.

State: the network's 30 rows in ``state``, the backbone's own (z, previous q) in
``backbone.state``; ``reset`` resets both.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from bushenv.models.base import PAPER_DT
from bushenv.models.boucwen.planar import PlanarBoucWen
from bushenv.models.planar_narx import PlanarNarx

BACKBONE_PARAMS = PlanarBoucWen.param_names


class PlanarBoucWenHybrid(PlanarNarx):
    """Vector Bouc-Wen backbone + MIMO network on its own past residual outputs."""

    name = "hybrid-bw"
    param_names = (*BACKBONE_PARAMS, *PlanarNarx.param_names)
    optional_params = PlanarBoucWen.optional_params

    def __init__(self, **params: Any) -> None:  # noqa: D107
        dt = params.get("dt", PAPER_DT)
        backbone = {k: params.pop(k) for k in BACKBONE_PARAMS if k in params}
        surface = params.pop("yield_surface", "vector")
        form = params.pop("relaxation_form", "constant")
        self.backbone = PlanarBoucWen(
            **backbone, yield_surface=surface, relaxation_form=form, dt=dt
        )
        for k in BACKBONE_PARAMS:
            setattr(self, k, getattr(self.backbone, k))
        super().__init__(**params)

    @classmethod
    def untrained(cls, seed: int = 0, dt: float = PAPER_DT, **_: Any) -> PlanarBoucWenHybrid:
        """The ``boucwen`` preset under an untrained MIMO network (for tests and checks)."""
        net = PlanarNarx.untrained(seed=seed, dt=dt)
        bw = PlanarBoucWen.preset(dt=dt)
        return cls(**bw.params, **net.params, dt=dt)

    def extra_meta(self) -> dict[str, Any]:
        return self.backbone.extra_meta()

    def backbone_alone(self) -> PlanarBoucWen:
        return PlanarBoucWen(**self.backbone.params, **self.backbone.extra_meta(), dt=self.dt)

    def reset(self, batch_size: int = 1) -> None:
        super().reset(batch_size)
        if hasattr(self, "backbone"):
            self.backbone.reset(batch_size)

    def reset_columns(self, mask: np.ndarray) -> None:
        super().reset_columns(mask)
        self.backbone.reset_columns(mask)

    def _advance(self, q: np.ndarray, v: np.ndarray, out: np.ndarray) -> None:
        super()._advance(q, v, out)  # the network alone (no linear backbone)
        f_bw = np.empty_like(out)
        self.backbone._advance(q, v, f_bw)
        out += f_bw


def compose(backbone: PlanarBoucWen, network: PlanarNarx) -> PlanarBoucWenHybrid:
    """The hybrid of a fitted backbone and a network trained on its residual."""
    return PlanarBoucWenHybrid(
        **backbone.params, **network.params, **backbone.extra_meta(), dt=backbone.dt
    )
