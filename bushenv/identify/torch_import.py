"""Import a NARX network trained elsewhere in torch into a bushenv model ("nn" or "hybrid").

The network must have the NARX shape of ``models/narx.py``: Linear, Tanh, Linear (one hidden
layer) or Linear, Tanh, Linear, Tanh, Linear (two), the last with one output. It is read as
a ``state_dict`` (the Linear layers' ``weight`` and ``bias`` in layer order) or an
``nn.Sequential``, from an object or a file. Files are read with ``torch.load(...,
weights_only=True)`` allowing only ``Sequential``, ``Linear`` and ``Tanh`` (never a general
unpickle), and the network is never called: its tensors are copied into float64 arrays.

What the user states, because a file cannot say it:

- the lags ``(n_past_x, n_past_f)``;
- the scaling: xs = (x - x_offset_m) / x_scale_m, with x in m; the network's output and its
  past-output inputs are ys = (F - f_offset_n) / f_scale_n in N (for the hybrid F is the
  residual force F - k x - c v);
- the input order. bushenv's is ``[xs_t, xs_{t-1}, ..., xs_{t-nx}, ys_{t-1}, ..., ys_{t-nf}]``
  (``input_order="newest-first"``, ``block_order="x-then-f"``); ``"oldest-first"`` reverses
  each block, ``"f-then-x"`` puts the past outputs first;
- for the hybrid, the backbone k (N/m) and c (N s/m).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.identify.data import IdentificationError
from bushenv.models.base import PAPER_DT
from bushenv.models.hybrid import HybridBushing
from bushenv.models.narx import NarxBushing

INPUT_ORDERS = ("newest-first", "oldest-first")
BLOCK_ORDERS = ("x-then-f", "f-then-x")
SHAPE_TEXT = "Linear, Tanh, Linear[, Tanh, Linear] with one output"


class TorchImportError(IdentificationError):
    """A torch network that is not of the NARX shape, or import settings that do not fit it."""


@dataclass(frozen=True)
class NarxScaling:
    """xs = (x - x_offset_m) / x_scale_m; ys = (F - f_offset_n) / f_scale_n (F: the network's
    force, the residual for the hybrid)."""

    x_scale_m: float
    f_scale_n: float
    x_offset_m: float = 0.0
    f_offset_n: float = 0.0


@dataclass(frozen=True)
class Layer:
    name: str  # the weight's key (state_dict) or module index
    weight: np.ndarray  # (out, in)
    bias: np.ndarray  # (out,)


def load_torch_file(path: str | os.PathLike) -> Any:
    """A state_dict or an ``nn.Sequential`` read with ``weights_only=True`` (no code runs)."""
    import pickle

    import torch

    path = Path(path)
    if not path.is_file():
        raise TorchImportError(f"{path}: no such torch file")
    allowed = [torch.nn.Sequential, torch.nn.Linear, torch.nn.Tanh]
    try:
        with torch.serialization.safe_globals(allowed):
            return torch.load(path, map_location="cpu", weights_only=True)
    except pickle.UnpicklingError as exc:
        first = str(exc).strip().splitlines()[-1][:200]
        raise TorchImportError(
            f"{path}: refused by torch.load(weights_only=True): it holds more than tensors, "
            f"Sequential, Linear and Tanh ({first}); save the state_dict instead"
        ) from None
    except Exception as exc:  # a damaged or foreign file: torch raises many kinds
        raise TorchImportError(
            f"{path}: not a torch file torch.load can read ({type(exc).__name__}: {exc})"
        ) from None


def _array(t: Any, name: str, source: str) -> np.ndarray:
    import torch

    if not isinstance(t, torch.Tensor):
        raise TorchImportError(f"{source}: {name} is a {type(t).__name__}, expected a tensor")
    a = t.detach().cpu().to(torch.float64).numpy().copy()
    if not np.all(np.isfinite(a)):
        raise TorchImportError(f"{source}: tensor '{name}' holds NaN or inf")
    return a


def layers_of_state_dict(state: Mapping[str, Any], source: str) -> list[Layer]:
    """The Linear layers of a state_dict, in key order: ``<prefix>.weight`` and an optional
    ``<prefix>.bias`` per layer; any other key is refused."""
    prefixes: dict[str, dict[str, Any]] = {}
    for key, value in state.items():
        prefix, _, kind = str(key).rpartition(".")
        if kind not in ("weight", "bias"):
            raise TorchImportError(
                f"{source}: unexpected tensor '{key}'; a NARX state_dict holds only the weight "
                f"and bias of each Linear layer ({SHAPE_TEXT})"
            )
        prefixes.setdefault(prefix, {})[kind] = (str(key), value)
    layers = []
    for prefix, parts in prefixes.items():
        if "weight" not in parts:
            raise TorchImportError(f"{source}: '{prefix}.bias' has no '{prefix}.weight'")
        wname, w = parts["weight"]
        weight = _array(w, wname, source)
        if weight.ndim != 2:
            raise TorchImportError(
                f"{source}: tensor '{wname}' has shape {list(weight.shape)}, expected a 2-D "
                "Linear weight [out, in]"
            )
        bias = _array(parts["bias"][1], parts["bias"][0], source) if "bias" in parts else None
        layers.append(Layer(wname, weight, np.zeros(weight.shape[0]) if bias is None else bias))
    return layers


def layers_of_sequential(seq: Any, source: str) -> list[Layer]:
    """The Linear layers of an ``nn.Sequential`` of the NARX shape (checked module by module)."""
    import torch

    modules = list(seq)
    layers = []
    for i, mod in enumerate(modules):
        want = torch.nn.Linear if i % 2 == 0 else torch.nn.Tanh
        if type(mod) is not want:
            raise TorchImportError(
                f"{source}: module {i} is {type(mod).__name__}, expected {want.__name__} "
                f"(the NARX network is {SHAPE_TEXT})"
            )
        if want is torch.nn.Linear:
            bias = (
                _array(mod.bias, f"{i}.bias", source)
                if mod.bias is not None
                else np.zeros(mod.out_features)
            )
            layers.append(Layer(f"{i}.weight", _array(mod.weight, f"{i}.weight", source), bias))
    if len(modules) % 2 == 0:
        raise TorchImportError(f"{source}: ends with a Tanh; the output layer must be Linear")
    return layers


def _check_shapes(layers: list[Layer], n_in: int, lags: tuple[int, int], source: str) -> None:
    """Refuse a layer list that is not the NARX shape, naming the tensor and the shape wanted."""
    if len(layers) not in (2, 3):
        raise TorchImportError(
            f"{source}: {len(layers)} Linear layers, expected 2 or 3 ({SHAPE_TEXT})"
        )
    lag_text = f"1 + n_past_x + n_past_f inputs for lags {lags[0]},{lags[1]}"
    wanted_in = n_in
    for i, layer in enumerate(layers):
        last = i == len(layers) - 1
        out = 1 if last else layer.weight.shape[0]
        want = [out, wanted_in]
        if list(layer.weight.shape) != want:
            what = lag_text if i == 0 else f"the {wanted_in} units of the layer before"
            shown = f"[{'1' if last else 'H'}, {wanted_in}]"
            raise TorchImportError(
                f"{source}: tensor '{layer.name}' has shape {list(layer.weight.shape)}, "
                f"expected {shown} ({what}{'; one output' if last else ''})"
            )
        if layer.bias.shape != (out,):
            raise TorchImportError(
                f"{source}: the bias of '{layer.name}' has shape {list(layer.bias.shape)}, "
                f"expected [{out}]"
            )
        wanted_in = out


def input_permutation(
    n_past_x: int, n_past_f: int, input_order: str, block_order: str
) -> np.ndarray:
    """perm with ``w1_bushenv[:, j] = w1_user[:, perm[j]]`` (module docstring: the orders)."""
    if input_order not in INPUT_ORDERS:
        raise TorchImportError(f"input order must be one of {INPUT_ORDERS}, got {input_order!r}")
    if block_order not in BLOCK_ORDERS:
        raise TorchImportError(f"block order must be one of {BLOCK_ORDERS}, got {block_order!r}")
    nx1 = n_past_x + 1
    x_pos = np.arange(nx1) if input_order == "newest-first" else nx1 - 1 - np.arange(nx1)
    f_pos = (
        np.arange(n_past_f) if input_order == "newest-first" else n_past_f - 1 - np.arange(n_past_f)
    )
    if block_order == "x-then-f":
        return np.concatenate([x_pos, nx1 + f_pos])
    return np.concatenate([n_past_f + x_pos, f_pos])


def import_torch_narx(
    source: Any,
    lags: tuple[int, int],
    scaling: NarxScaling,
    model: str = "nn",
    k_n_per_m: float | None = None,
    c_ns_per_m: float | None = None,
    dt: float = PAPER_DT,
    input_order: str = "newest-first",
    block_order: str = "x-then-f",
) -> NarxBushing:
    """A ``NarxBushing`` ("nn") or ``HybridBushing`` ("hybrid") from a torch NARX network.

    ``source``: a state_dict, an ``nn.Sequential``, or a path to a file holding either. The
    result behaves as the torch network run free on its own outputs (tested to 1e-9 of the
    peak force); save it with ``.save(path)``.
    """
    label = os.fspath(source) if isinstance(source, str | os.PathLike) else "network"
    obj = load_torch_file(source) if isinstance(source, str | os.PathLike) else source
    nx, nf = (int(v) for v in lags)
    if nx < 1 or nf < 1:
        raise TorchImportError(f"lags must be >= 1 past displacement and force, got {lags}")
    layers = _layers(obj, label)
    _check_shapes(layers, 1 + nx + nf, (nx, nf), label)
    perm = input_permutation(nx, nf, input_order, block_order)
    h = layers[:-1]
    common = dict(
        x_offset_m=scaling.x_offset_m,
        x_scale_m=scaling.x_scale_m,
        f_offset_n=scaling.f_offset_n,
        f_scale_n=scaling.f_scale_n,
        w1=h[0].weight[:, perm],
        b1=h[0].bias,
        w2=h[1].weight if len(h) == 2 else np.zeros((0, h[0].weight.shape[0])),
        b2=h[1].bias if len(h) == 2 else np.zeros(0),
        w_out=layers[-1].weight[0],
        b_out=float(layers[-1].bias[0]),
        n_past_x=nx,
        n_past_f=nf,
        dt=dt,
    )
    if model == "hybrid":
        if k_n_per_m is None or c_ns_per_m is None:
            raise TorchImportError("a hybrid needs its backbone: k (N/m) and c (N s/m)")
        return HybridBushing(k_n_per_m=k_n_per_m, c_ns_per_m=c_ns_per_m, **common)
    if model != "nn":
        raise TorchImportError(f"model must be 'nn' or 'hybrid', got {model!r}")
    if k_n_per_m is not None or c_ns_per_m is not None:
        raise TorchImportError("k and c are the hybrid's backbone; a pure nn takes neither")
    return NarxBushing(**common)


def _layers(obj: Any, label: str) -> list[Layer]:
    import torch

    if isinstance(obj, torch.nn.Sequential):
        return layers_of_sequential(obj, label)
    if isinstance(obj, torch.nn.Module):
        raise TorchImportError(
            f"{label}: a {type(obj).__name__} module; pass its state_dict() or an "
            f"nn.Sequential ({SHAPE_TEXT})"
        )
    if isinstance(obj, Mapping):
        return layers_of_state_dict(obj, label)
    raise TorchImportError(
        f"{label}: holds a {type(obj).__name__}, expected a state_dict or an nn.Sequential"
    )
