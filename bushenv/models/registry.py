"""``MODELS``: the one list of bushing models. Adding a model = one module + one line here.

Each entry names the model class and, where the model can be identified from measured records,
its identification function (``bushenv fit``, ``bushenv reproduce`` and the diagnosis
baselines read it from here), whether trained defaults ship with the package (one file per
axis in ``bushenv/data/models``), and the preset options the model takes when it stands as
the *reference* of a verdict. Entries are ``"module:attribute"`` strings, imported on first
use, so this module imports no model (and no torch).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from bushenv.models.base import ModelError
from bushenv.registry import Registry, load_entry_point


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
    hybrid : str or None
        The hybrid ``bushenv attack`` rechecks and attacks beside this model (default:
        ``hybrid``): the papers' NN goes with the papers' hybrid.
    also : tuple of str
        Models rechecked on every profile that broke this one, in their own rows.
    kind : str or None
        For a preset of another model's class (``nn-paper`` is an ``nn`` network trained
        another way): the registered name of that class, which its files carry. None: the
        entry's own name.
    """

    entry_point: str | type
    summary: str
    fit: Any = None
    options: Any = None
    shipped: bool = False
    reference_preset: dict[str, Any] = field(default_factory=dict)
    hybrid: str | None = None
    also: tuple[str, ...] = ()
    kind: str | None = None

    def model_class(self) -> type:
        ep = self.entry_point
        return load_entry_point(ep) if isinstance(ep, str) else ep

    def fit_function(self) -> Any:
        return load_entry_point(self.fit) if isinstance(self.fit, str) else self.fit

    def options_class(self) -> Any:
        return load_entry_point(self.options) if isinstance(self.options, str) else self.options


MODELS: Registry[ModelEntry] = Registry("model", ModelError)
MODELS.add(
    "linear",
    ModelEntry(
        "bushenv.models.linear:LinearBushing",
        "Kelvin-Voigt spring and dashpot, F = k x + c v (seed 000 eqs 1-3)",
        fit="bushenv.identify.linear:fit_linear",
        options="bushenv.identify.options:NoOptions",
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
    ),
)
MODELS.add(
    "rubber",
    ModelEntry(
        "bushenv.reference.rubber:RubberBushing",
        "the reference rubber bushing (bushenv/reference); as a reference without its "
        "measurement chain",
        reference_preset={"measurement": False},
    ),
)
