"""``bushenv import-nn``: a torch NARX network (state_dict or nn.Sequential file) to a model file.

The scaling, lags and input order are stated by flags (``torch_import.py`` explains each);
the model file gets a card beside it naming the torch file's sha256 and every setting.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bushenv.models.base import PAPER_DT

EXAMPLE = (
    "bushenv import-nn weights.pt --lags 5,5 --x-scale-m 0.002 --f-scale-n 900 --out my_nn.npz"
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    from bushenv.identify.torch_import import BLOCK_ORDERS, INPUT_ORDERS

    p.add_argument("weights", metavar="WEIGHTS.pt", help="torch state_dict or nn.Sequential file")
    p.add_argument("--out", required=True, metavar="MODEL.npz", help="model file to write")
    p.add_argument(
        "--model", choices=("nn", "hybrid"), default="nn", help="what the net is (default: nn)"
    )
    p.add_argument(
        "--lags", required=True, metavar="NX,NF", help="past displacements, past forces (required)"
    )
    for sym, unit, what in (("x", "m", "displacement"), ("f", "n", "force")):
        p.add_argument(
            f"--{sym}-scale-{unit}",
            type=float,
            default=None,
            metavar="X",
            help=f"{what} scale, {'m' if unit == 'm' else 'N'}: scaled = ({what} - offset) / "
            f"scale (default: none; this or --{sym}-range-{unit} is required)",
        )
        p.add_argument(
            f"--{sym}-offset-{unit}",
            type=float,
            default=None,
            metavar="X",
            help=f"{what} offset, {'m' if unit == 'm' else 'N'} (default: 0)",
        )
        p.add_argument(
            f"--{sym}-range-{unit}",
            default=None,
            metavar="LO,HI",
            help=f"instead of scale and offset: the {what} range mapped to [-1, 1] (mapminmax; "
            f"write --{sym}-range-{unit}=-LO,HI when LO is negative; default: none)",
        )
    for flag, what in (("--k-n-per-m", "stiffness, N/m"), ("--c-ns-per-m", "damping, N s/m")):
        p.add_argument(
            flag,
            type=float,
            default=None,
            metavar="X",
            help=f"hybrid backbone {what} (default: none; required for a hybrid)",
        )
    p.add_argument(
        "--rate-hz", type=float, default=1.0 / PAPER_DT, help="sample rate, Hz (default: 204.8)"
    )
    p.add_argument(
        "--input-order",
        choices=INPUT_ORDERS,
        default=INPUT_ORDERS[0],
        help="order within each input block (default: newest-first: x_t, x_t-1, ...)",
    )
    p.add_argument(
        "--block-order",
        choices=BLOCK_ORDERS,
        default=BLOCK_ORDERS[0],
        help="displacements before past forces or after (default: x-then-f)",
    )
    p.add_argument(
        "--force", action="store_true", help="replace an existing model file and its card"
    )


def _pair(text: str, flag: str, kind: type = float) -> tuple:
    from bushenv.cli import CliError

    parts = [t.strip() for t in text.split(",")]
    try:
        if len(parts) != 2:
            raise ValueError
        return tuple(kind(t) for t in parts)
    except ValueError:
        raise CliError(f"{flag} takes two comma-separated numbers, got {text!r}") from None


def _scale(args: argparse.Namespace, sym: str, unit: str) -> tuple[float, float]:
    """(offset, scale) of one signal from --*-scale/--*-offset or --*-range."""
    from bushenv.cli import CliError
    from bushenv.models.narx import scaling_of

    scale = getattr(args, f"{sym}_scale_{unit}")
    offset = getattr(args, f"{sym}_offset_{unit}")
    rng = getattr(args, f"{sym}_range_{unit}")
    flags = f"--{sym}-scale-{unit}", f"--{sym}-range-{unit}"
    if (scale is None) == (rng is None):
        raise CliError(f"give either {flags[0]} (and an offset) or {flags[1]}, exactly one")
    if rng is not None:
        if offset is not None:
            raise CliError(f"--{sym}-offset-{unit} goes with {flags[0]}, not with {flags[1]}")
        lo, hi = _pair(rng, flags[1])
        if not hi > lo:
            raise CliError(f"{flags[1]} {rng!r}: HI must exceed LO")
        return scaling_of(lo, hi)
    if not scale > 0:
        raise CliError(f"{flags[0]} must be positive, got {scale}")
    return (offset or 0.0), scale


def run(args: argparse.Namespace) -> int:
    from bushenv.cli import CliError
    from bushenv.identify.card import card_paths, new_card, sha256_file, write_card
    from bushenv.identify.torch_import import NarxScaling, import_torch_narx

    out = Path(args.out)
    if out.suffix != ".npz":
        raise CliError(f"--out {out}: a model file name ends in .npz")
    existing = [str(p) for p in (out, *card_paths(out)) if p.exists()]
    if existing and not args.force:
        raise CliError(f"{', '.join(existing)} exist(s); pass --force to replace")
    if not args.rate_hz > 0:
        raise CliError(f"--rate-hz must be positive, got {args.rate_hz}")
    lags = _pair(args.lags, "--lags", int)
    x_off, x_sc = _scale(args, "x", "m")
    f_off, f_sc = _scale(args, "f", "n")
    scaling = NarxScaling(x_scale_m=x_sc, f_scale_n=f_sc, x_offset_m=x_off, f_offset_n=f_off)
    model = import_torch_narx(
        args.weights,
        lags,
        scaling,
        model=args.model,
        k_n_per_m=args.k_n_per_m,
        c_ns_per_m=args.c_ns_per_m,
        dt=1.0 / args.rate_hz,
        input_order=args.input_order,
        block_order=args.block_order,
    )
    model.save(out)
    settings = {
        "lags": list(lags),
        **{k: getattr(scaling, k) for k in ("x_offset_m", "x_scale_m", "f_offset_n", "f_scale_n")},
        "input_order": args.input_order,
        "block_order": args.block_order,
        "k_n_per_m": args.k_n_per_m,
        "c_ns_per_m": args.c_ns_per_m,
    }
    source = {
        "kind": "torch-import",
        "torch_file": str(args.weights),
        "torch_sha256": sha256_file(args.weights),
        "options": settings,
    }
    json_path, _ = write_card(new_card(model, out, source), out)
    print(
        f"model {model.name} {model.hidden} lags {lags[0]},{lags[1]} at {args.rate_hz:.6g} Hz "
        f"-> {out} (card {json_path.name}); network force bound {model.nn_bound():.1f} N"
    )
    return 0
