"""The physical parameters a model card lists: name, value, unit (none for a network alone)."""

from __future__ import annotations

from typing import Any

import numpy as np

# Units of the physical parameters a card lists (Bouc-Wen: seed 002 eqs 1-5).
PARAMETER_UNITS = {
    "k_n_per_m": "N/m",
    "c_ns_per_m": "N s/m",
    **{k: "N s/m" for k in ("c0", "c1", "c2")},
    **{k: "N/m" for k in ("k0", "k1", "k2", "a1", "a2")},
    **{k: "m^-n" for k in ("beta1", "beta2", "gamma1", "gamma2")},
    **{k: "-" for k in ("A1", "A2", "n1", "n2")},
}


def physical_parameters(model: Any) -> dict[str, dict[str, Any]] | None:
    """{name: {"value", "unit"}} of a physical model of one coordinate (linear or the hybrid's
    backbone: k, c; Bouc-Wen: its sixteen, seed 002 order); None for a network alone and for
    a model whose parameters are matrices over several coordinates (its model file holds
    them)."""
    names = getattr(model, "param_names", None) if model.name == "boucwen" else None
    if names is None and hasattr(model, "k_n_per_m") and hasattr(model, "c_ns_per_m"):
        names = ("k_n_per_m", "c_ns_per_m")
    if names is None or any(np.ndim(getattr(model, n)) != 0 for n in names):
        return None
    return {n: {"value": float(getattr(model, n)), "unit": PARAMETER_UNITS[n]} for n in names}
