"""``MODELS``: the one list of bushing models. Adding a model = one module + one line here.

A name is a kind of model (``linear``, ``nn``, ``hybrid``, ...) over any number of coordinates
C: each entry holds one form per C it exists for (the class, its identification and options),
e.g. ``linear`` as a scalar Kelvin-Voigt for C = 1 and as 3x3 matrices for the three in-plane
coordinates. Where the model can be identified from measured records, the entry names its
identification (``bushenv fit``, ``bushenv reproduce`` and the diagnosis baselines read it
here); it says whether trained defaults ship with the package (one file per axis in
``bushenv/data/models``) and the preset options the model takes as the *reference* of a
verdict. Entries are ``"module:attribute"`` strings, imported on first use, so this module
imports no model (and no torch).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from bushenv.models.base import ModelError, has_preset
from bushenv.registry import Registry, load_entry_point


@dataclass(frozen=True)
class Form:
    """One kind of model over C > 1 coordinates: its class, identification and options (the
    identification as ``ModelEntry.fit``, its ``data`` of (T, C) records; what the card shows
    of it, ``model.training["info"]``)."""

    entry_point: str | type
    fit: Any = None
    options: Any = None

    def model_class(self) -> type:
        ep = self.entry_point
        return load_entry_point(ep) if isinstance(ep, str) else ep

    def fit_function(self) -> Any:
        return load_entry_point(self.fit) if isinstance(self.fit, str) else self.fit

    def options_class(self) -> Any:
        return load_entry_point(self.options) if isinstance(self.options, str) else self.options


@dataclass(frozen=True)
class ModelEntry:
    """What the project knows about one registered model.

    Attributes
    ----------
    entry_point : str or type
        The ``BushingModel`` subclass, or ``"module:Class"``.
    summary : str
        One line for ``--help`` and the docs' tables.
    fit : str, callable or None
        Identification ``fit(data, options, seed, progress) -> model`` (``data`` a
        ``bushenv.identify.data.TrainingSet``), or None. ``bushenv.identify.fit`` calls it.
    options : str, type or None
        The dataclass of ``fit``'s options (``bushenv.identify.options``): the one declaration
        ``bushenv fit`` builds the model's flags from.
    shipped : bool
        Trained defaults ship in the package; the name loads ``<axis>_<name>.npz``.
    reference_preset : dict
        Keyword arguments of ``preset`` when the model is a verdict's reference.
    preset : dict
        Keyword arguments of ``preset`` that make this name, always given: a named parameter
        set of another model's class (``rubber-torsion`` is ``rubber``'s preset with
        ``rotation="torsion"``; ``kind`` names that class).
    hybrid : str or None
        The hybrid ``bushenv attack`` rechecks and attacks beside this model (default:
        ``hybrid``): the papers' NN goes with the papers' hybrid.
    also : tuple of str
        Models rechecked on every profile that broke this one, in their own rows.
    kind : str or None
        For a preset of another model's class (``nn-paper`` is an ``nn`` network trained
        another way): the registered name of that class, which its files carry. None: the
        entry's own name.
    wider : dict of int to Form
        The same kind over C > 1 coordinates, by C (3: axial, radial, rotation).
    """

    entry_point: str | type | None
    summary: str
    fit: Any = None
    options: Any = None
    shipped: bool = False
    reference_preset: dict[str, Any] = field(default_factory=dict)
    preset: dict[str, Any] = field(default_factory=dict)
    hybrid: str | None = None
    also: tuple[str, ...] = ()
    kind: str | None = None
    wider: dict[int, Form] = field(default_factory=dict)

    def coordinate_counts(self) -> tuple[int, ...]:
        """The numbers of coordinates C this kind exists for."""
        return ((1,) if self.entry_point is not None else ()) + tuple(sorted(self.wider))

    def form(self, coords: int = 1) -> Form:
        """The kind over ``coords`` coordinates (``ModelError`` saying which C it has)."""
        if coords == 1 and self.entry_point is not None:
            return Form(self.entry_point, self.fit, self.options)
        if coords in self.wider:
            return self.wider[coords]
        have = " or ".join(str(c) for c in self.coordinate_counts())
        raise ModelError(
            f"this kind exists for {have} coordinate(s), not {coords}: for "
            f"{coordinate_words(coords).split(':')[0]} choose one of "
            f"{', '.join(names_for(coords))}"
        )

    def model_class(self, coords: int = 1) -> type:
        return self.form(coords).model_class()

    def fit_function(self, coords: int = 1) -> Any:
        return self.form(coords).fit_function()

    def options_class(self, coords: int = 1) -> Any:
        return self.form(coords).options_class()

    def ready_made(self, coords: int = 1) -> bool:
        """Whether this kind over ``coords`` coordinates is there without a file of the user's
        (a shipped model or a preset; a network over several must be trained first)."""
        if coords not in self.coordinate_counts():
            return False
        if coords == 1 and self.shipped:
            return True
        return has_preset(self.model_class(coords))

    def fits(self, coords: int = 1) -> bool:
        """Whether this kind can be identified from records over ``coords`` coordinates."""
        return coords in self.coordinate_counts() and self.form(coords).fit is not None


def coordinate_words(coords: int) -> str:
    """How a user names a model of ``coords`` coordinates."""
    return {1: "a one-axis model", 3: "a three-axis model: axial, radial, rotation"}.get(
        coords, f"a {coords}-coordinate model"
    )


def names_for(coords: int = 1, fittable: bool = False) -> tuple[str, ...]:
    """The registered names that exist over ``coords`` coordinates (and can be fitted)."""
    return tuple(
        n
        for n, e in MODELS.items()
        if coords in e.coordinate_counts() and (not fittable or e.fits(coords))
    )


MODELS: Registry[ModelEntry] = Registry("model", ModelError)
M = "bushenv.models."  # the three-coordinate forms
FITS = "bushenv.identify.mimo:"  # the MIMO networks' identifications
T = "bushenv.identify.mimo_options:"  # and their options
MODELS.add(
    "linear",
    ModelEntry(
        "bushenv.models.linear:LinearBushing",
        "Kelvin-Voigt spring and dashpot, F = k x + c v (seed 000 eqs 1-3)",
        fit="bushenv.identify.linear:fit_linear",
        options="bushenv.identify.options:NoOptions",
        wider={
            3: Form(
                M + "planar_linear:PlanarLinear",
                "bushenv.identify.linear:fit_linear",
                "bushenv.identify.options:NoOptions",
            )
        },  # fmt: skip
    ),
)
MODELS.add(
    "nn",
    ModelEntry(
        "bushenv.models.narx:NarxBushing",
        "NARX network fed with its own past forces (seed 000 eqs 4-6)",
        fit="bushenv.identify.neural:fit_nn",
        options="bushenv.identify.narx_options:NarxOptions",
        shipped=True,
        wider={
            3: Form(
                M + "planar_narx:PlanarNarx",
                FITS + "fit_nn",
                T + "MimoOptions",
            )
        },  # fmt: skip
    ),
)
MODELS.add(
    "nn-axis",
    ModelEntry(
        None,
        "three single-axis NARX networks in one model, seed 000 §4.2's kind in three axes",
        wider={
            3: Form(
                M + "planar_narx:PlanarNarxPerAxis",
                FITS + "fit_nn_axis",
                T + "MimoOptions",
            )
        },  # fmt: skip
    ),
)
MODELS.add(
    "hybrid",
    ModelEntry(
        "bushenv.models.hybrid:HybridBushing",
        "linear backbone plus a bounded NARX residual network (seed 000 §3)",
        fit="bushenv.identify.neural:fit_hybrid",
        options="bushenv.identify.narx_options:HybridOptions",
        shipped=True,
        wider={
            3: Form(
                M + "planar_narx:PlanarHybrid",
                FITS + "fit_hybrid",
                T + "MimoHybridOptions",
            )
        },  # fmt: skip
    ),
)
MODELS.add(
    "nn-paper",
    ModelEntry(
        "bushenv.models.narx:NarxBushing",
        "the papers' pure NARX network as seed 000 made it: 5+5 lags, 9 tanh units, trained "
        "one step ahead only (teacher forcing), no certified holds",
        shipped=True,
        hybrid="hybrid-paper",
        also=("nn", "hybrid"),
        kind="nn",
    ),
)
MODELS.add(
    "hybrid-paper",
    ModelEntry(
        "bushenv.models.hybrid:HybridBushing",
        "the papers' hybrid as seed 000 made it: linear backbone plus the same network, "
        "teacher forcing, no certified holds",
        shipped=True,
        kind="hybrid",
    ),
)
MODELS.add(
    "boucwen",
    ModelEntry(
        "bushenv.models.boucwen:BoucWenBushing",
        "16-parameter Bouc-Wen model with two hysteretic variables (seed 002 eqs 1-5)",
        fit="bushenv.identify.global_search:fit_boucwen",
        options="bushenv.identify.boucwen_options:BoucWenOptions",
        shipped=True,
        wider={
            3: Form(
                M + "boucwen.planar:PlanarBoucWen",
                "bushenv.identify.vector_boucwen:fit_boucwen",
                "bushenv.identify.boucwen_options:VectorBoucWenOptions",
            )
        },  # fmt: skip
    ),
)
MODELS.add(
    "hybrid-bw",
    ModelEntry(
        None,
        "vector Bouc-Wen backbone plus a MIMO NARX network on its residual",
        wider={
            3: Form(
                M + "planar_hybrid_bw:PlanarBoucWenHybrid",
                FITS + "fit_hybrid_bw",
                FITS + "HybridBWOptions",
            )
        },  # fmt: skip
    ),
)
MODELS.add(
    "rubber",
    ModelEntry(
        "bushenv.reference.rubber:RubberBushing",
        "the reference rubber bushing (bushenv/reference); as a reference without its "
        "measurement chain",
        reference_preset={"measurement": False},
        wider={3: Form("bushenv.reference.planar:PlanarRubber")},
    ),
)
MODELS.add(
    "linear-torsion",
    ModelEntry(
        None,
        "the linear preset with the rotation a torsion (a car's arm pivot: the bush's geometry)",
        preset={"rotation": "torsion"},
        kind="linear",
        wider={3: Form(M + "planar_linear:PlanarLinear")},
    ),
)
MODELS.add(
    "rubber-torsion",
    ModelEntry(
        None,
        "the reference rubber with the rotation a torsion (HalfCar-v0's arm pivots); as a "
        "reference without its measurement chain",
        reference_preset={"measurement": False},
        preset={"rotation": "torsion"},
        kind="rubber",
        wider={3: Form("bushenv.reference.planar:PlanarRubber")},
    ),
)
MODELS.alias("reference", "rubber")  # the three-axis rubber's name in files written before
