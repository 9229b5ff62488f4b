"""The bushing models a vehicle comparison puts in the car's four pivots: identified on the
coupled reference's three-axis records (kept in a cache folder, so a rerun reuses them), or
given as model files.

Identification records: ``bushenv.reproduce.identification_records`` -- random motion
of all three coordinates at n = 1, independent and correlated (``identification_s`` each), and
the coupled sine sets at n = 1 (``identification_s`` / 2 each), the reference measured with its
load cell, each record its own noise seed: what ``bushenv reproduce --planar`` identifies on,
but of the reference in the car's rotation parameter set (``halfcar_params.PIVOT_ROTATION``:
torsion), the one the car's twins run; for that set the same again at the wide peaks
(``reproduce.WIDE_PEAKS``: 12.5 mm, 4 mm and the set's calibrated 0.442 rad, in 0.5-5 Hz;
random ``identification_s`` / 2, the sets / 2 each), so the fits cover the rotation and
translations the car's manoeuvres reach.
Each kind is fitted by ``bushenv.identify.fit`` with its default options and the
seed, as ``bushenv fit REC... --model KIND --seed SEED`` would.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from bushenv.identify.card import sha256_file
from bushenv.models import load_model, names_for
from bushenv.persist import plain, write_json
from bushenv.rigs.halfcar_params import PIVOT_ROTATION
from bushenv.vehicle.checks import VehicleInputError

RECIPE_VERSION = 3  # bump when the identification changes: older cached fits are then redone
# 3: the torsion set's calibrated range (0.442 rad), strain-mapped hardening, and the records
# at the wide peaks; 2: the reference's torsion parameter set (1: its cardanic rotation)
DEFAULT_KINDS = ("linear", "hybrid", "nn")


@dataclass(frozen=True)
class Recipe:
    """How a bushing kind is identified when no file is given (all of it the cache's key)."""

    dt_s: float
    seed: int = 0
    identification_s: float = 40.0
    records: str = "programme"  # identification_records': random and the coupled sets at n = 1
    rotation: str = PIVOT_ROTATION  # the reference's rotation parameter set measured

    def key(self, kind: str) -> dict[str, Any]:
        return {"kind": kind, "seed": self.seed, "identification_s": self.identification_s,
                "records": self.records, "rotation": self.rotation, "dt_s": self.dt_s,
                "options": "defaults",
                "recipe_version": RECIPE_VERSION}  # fmt: skip


@dataclass(frozen=True)
class VehicleBushing:
    """A resolved bushing kind: the model (read back from its file), where it came from."""

    kind: str
    model: Any
    file: str
    sha256: str
    how: str
    fit_seconds: float | None = None
    info: dict[str, Any] = field(default_factory=dict)

    def describe(self) -> dict[str, Any]:
        return {"kind": self.kind, "model": self.model.name, "file": self.file,
                "sha256": self.sha256, "how": self.how, "fit_seconds": self.fit_seconds,
                "info": plain(self.info)}  # fmt: skip


def check_kinds(kinds: list[str] | tuple[str, ...]) -> tuple[str, ...]:
    """The kinds, each a three-axis model that can be identified, without repeats."""
    known = names_for(3, fittable=True)
    bad = [k for k in kinds if k not in known]
    if bad or not kinds:
        raise VehicleInputError(
            f"bushing kinds {list(kinds)}: give one or more of {', '.join(known)}"
        )
    return tuple(dict.fromkeys(kinds))


def _cached(path: Path, meta_path: Path, key: dict[str, Any]) -> dict[str, Any] | None:
    if not (path.exists() and meta_path.exists()):
        return None
    try:
        meta = json.loads(meta_path.read_text())
    except (OSError, ValueError):
        return None
    return meta if meta.get("key") == key else None


def vehicle_bushings(
    kinds: tuple[str, ...],
    recipe: Recipe,
    cache_dir: str | Path,
    files: dict[str, str] | None = None,
    say: Callable[[str], None] | None = None,
) -> dict[str, VehicleBushing]:
    """Each kind's model: its file from ``files`` if given, else the cached fit in ``cache_dir``
    if its key matches ``recipe``, else identified now and saved there. Every model is the one
    read back from its file, so a first run and a rerun use the same numbers."""
    from bushenv.identify import fit
    from bushenv.reproduce import WIDE_PEAKS, identification_records

    kinds = check_kinds(kinds)
    files = files or {}
    cache = Path(cache_dir)
    out: dict[str, VehicleBushing] = {}
    histories = None
    for kind in kinds:
        if kind in files:
            path = Path(files[kind])
            wanted = f"the vehicle comparison's {kind} bushing"
            model = load_model(path, dt=recipe.dt_s, coords=3, wanted_by=wanted)
            out[kind] = VehicleBushing(kind, model, str(path), sha256_file(path), f"given: {path}")
            continue
        path, meta_path = cache / f"{kind}.npz", cache / f"{kind}.fit.json"
        key = recipe.key(kind)
        meta = _cached(path, meta_path, key)
        if meta is None:
            if histories is None:
                if say:
                    say(f"measuring the reference's identification records "
                        f"({recipe.identification_s:g} s random x 2, coupled sets)")  # fmt: skip
                ident = (recipe.dt_s, recipe.seed, recipe.identification_s, recipe.records)
                histories = identification_records(*ident, recipe.rotation)
            if say:
                say(f"identifying {kind} (seed {recipe.seed}, default options)")
            result = fit(histories, kind, {}, recipe.seed, say or False, dt=recipe.dt_s)
            cache.mkdir(parents=True, exist_ok=True)
            result.model.save(path)
            meta = {"key": key, "fit_seconds": result.seconds, "info": plain(result.info)}
            write_json(meta_path, meta)
            how = f"identified now in {result.seconds:.1f} s"
        else:
            how = f"cached ({meta['fit_seconds']:.1f} s when identified)"
        model = load_model(path, dt=recipe.dt_s, coords=3)
        ident = recipe.identification_s
        samples = f"random {ident:g} s x 2, coupled sets {ident / 2:g} s x 3"
        if recipe.rotation in WIDE_PEAKS:
            samples += (f"; at the wide peaks random {ident / 2:g} s x 2, "
                        f"coupled sets {ident / 2:g} s x 3")  # fmt: skip
        out[kind] = VehicleBushing(
            kind, model, str(path), sha256_file(path),
            f"fit({kind!r}, default options, seed {recipe.seed}) on the coupled "
            f"reference's records ({recipe.rotation} rotation; {samples}); {how}",
            meta["fit_seconds"], meta.get("info", {}),
        )  # fmt: skip
    return out
