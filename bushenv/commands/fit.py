"""``bushenv fit``: identify a model from measured records; write it, its card and figures.

The records say how many coordinates C the bushing has (one: ``time,displacement,force``;
three: axial, radial, rotation); ``--model`` is a kind in ``MODELS`` and the identification is
the one that kind has over C (``bushenv.identify.fit``). Each kind's flags are built from its
options dataclass (``ModelEntry.options``, one per C it is identified over): one flag per
field, its help and default from the field. A flag several models share (``--time-limit-s``)
is declared once and shows each model's default.
"""

from __future__ import annotations

import argparse
import os
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

from bushenv.commands.options import add_resample_option
from bushenv.identify import fittable_models, options_class
from bushenv.identify.options import describe, flag_of, option_fields

EXAMPLE = "bushenv fit train1.csv train2.csv --model hybrid --validate held.csv --out my_hybrid.npz"
DEST = "option_"  # argparse dest prefix of the model options


def coordinate_counts() -> list[int]:
    """Every number of coordinates some registered kind is identified over."""
    from bushenv.models import MODELS

    return sorted({c for e in MODELS.values() for c in e.coordinate_counts() if e.fits(c)})


def owner(name: str, coords: int) -> str:
    """How ``--help`` and the errors name a kind's form: ``nn``, ``nn (3-axis)``."""
    return name if coords == 1 else f"{name} ({coords}-axis)"


def model_options() -> dict[str, list[tuple[str, Any]]]:
    """Option name -> [(owner, dataclass field)] for every kind's identification over every
    number of coordinates (owners as ``owner`` names them)."""
    table: dict[str, list[tuple[str, Any]]] = defaultdict(list)
    for c in coordinate_counts():
        for name in fittable_models(c):
            for f in option_fields(options_class(name, c)):
                table[f.name].append((owner(name, c), f))
    return dict(table)


def model_choices() -> list[str]:
    """``--model``: every kind identified over some number of coordinates."""
    return list(dict.fromkeys(n for c in coordinate_counts() for n in fittable_models(c)))


def _option_help(owners: list[tuple[str, Any]]) -> str:
    f = owners[0][1]
    defaults: dict[str, list[str]] = defaultdict(list)
    for model, fld in owners:
        defaults[describe(fld.default)].append(model)
    if len(defaults) == 1:
        default = f"default: {next(iter(defaults))}"
    else:
        default = "default: " + "; ".join(f"{', '.join(m)} {d}" for d, m in defaults.items())
    return f"{f.metadata['help']} ({default})"


def _metavar(f: Any) -> str:
    choices = f.metadata.get("choices")
    if choices:
        return "{" + ",".join(choices) + "}"
    if isinstance(f.default, tuple):
        return "V[,V...]" if f.default and isinstance(f.default[0], str) else "N[,N...]"
    return "N" if isinstance(f.default, int) else "X"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("train", nargs="*", metavar="TRAIN.csv", help="training record files")
    p.add_argument(
        "--model",
        required=True,
        choices=model_choices(),
        help="model to identify (required): a kind whose form over the records' coordinates "
        "has an identification",
    )
    p.add_argument("--out", required=True, metavar="MODEL.npz", help="model file to write")
    p.add_argument(
        "--validate",
        nargs="*",
        default=None,
        metavar="HELD.csv",
        help="held-out record files: metrics and figures on the card (default: none)",
    )
    p.add_argument("--seed", type=int, default=0, help="training seed (default: 0)")
    p.add_argument(
        "--force", action="store_true", help="replace an existing model file and its card"
    )
    p.add_argument("--no-plots", action="store_true", help="write no figures")
    add_resample_option(p)
    p.add_argument("--quiet", action="store_true", help="no progress lines on stderr")
    groups: dict[tuple[str, ...], Any] = {}
    for name, owners in model_options().items():
        models = tuple(dict.fromkeys(m for m, _ in owners))
        if models not in groups:
            groups[models] = p.add_argument_group(f"options of {', '.join(models)}")
        groups[models].add_argument(
            flag_of(name),
            dest=DEST + name,
            default=argparse.SUPPRESS,
            metavar=_metavar(owners[0][1]),
            help=_option_help(owners),
        )


def chosen_options(args: argparse.Namespace, coords: int = 1) -> dict[str, str]:
    """The model options given on the command line (name -> text); refuses another model's,
    or one the kind does not take over ``coords`` coordinates."""
    from bushenv.cli import CliError

    table = model_options()
    mine = owner(args.model, coords)
    what = "model" if coords == 1 else f"the {coords}-axis model"
    given = {k[len(DEST) :]: v for k, v in vars(args).items() if k.startswith(DEST)}
    for name in given:
        models = [m for m, _ in table[name]]
        if mine not in models:
            own = [flag_of(n) for n, o in table.items() if mine in (m for m, _ in o)]
            raise CliError(
                f"{flag_of(name)} is not an option of {what} {args.model} (it is one of "
                f"{', '.join(models)}); {args.model} takes: {', '.join(own) or 'no options'}"
            )
    return given


def _check_paths(args: argparse.Namespace) -> Path:
    from bushenv.cli import CliError
    from bushenv.identify.card import card_paths

    if not args.train:
        raise CliError("no training records given: bushenv fit TRAIN.csv [MORE.csv ...] ...")
    if args.validate is not None and not args.validate:
        raise CliError("--validate needs at least one held-out record file")
    out = Path(args.out)
    if out.suffix != ".npz":
        raise CliError(f"--out {out}: a model file name ends in .npz")
    if out.is_dir():
        raise CliError(f"--out {out}: is a folder; give a file name ending in .npz")
    existing = [str(p) for p in (out, *card_paths(out)) if p.exists()]
    if existing and not args.force:
        raise CliError(f"{', '.join(existing)} exist(s); pass --force to replace")
    if args.seed < 0:
        raise CliError(f"--seed must be >= 0, got {args.seed}")
    return out


def run(args: argparse.Namespace) -> int:
    from bushenv.identify import fit
    from bushenv.identify.card import save_fit
    from bushenv.identify.data import check_model_rate, check_same_coordinates, check_same_rate
    from bushenv.record_files import load_record
    from bushenv.record_notes import start_notes
    from bushenv.record_rates import one_rate

    out = _check_paths(args)
    train = [load_record(p) for p in args.train]
    held = [load_record(p) for p in args.validate or []]
    coords = len(check_same_coordinates(train + held, what="training and held-out records"))
    options_class(args.model, coords)  # the kind has an identification over these records
    given = chosen_options(args, coords)
    train, held = one_rate([train, held], args.resample, "fit")
    dt = check_same_rate(train, what="training records")
    for i, rec in enumerate(held):
        check_model_rate(rec, dt, i)
    notes = [n for rec in train + held for n in start_notes(rec)]
    for note in notes:
        print(f"note: {note}", file=sys.stderr, flush=True)
    say = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    if say:
        seconds = sum(r.duration_s for r in train)
        say(f"fit {owner(args.model, coords)} on {len(train)} record(s), {seconds:.1f} s at "
            f"{1 / dt:.6g} Hz")  # fmt: skip
    result = fit(train, args.model, given, seed=args.seed, progress=say or False)
    card = save_fit(result, out, held, plots=not args.no_plots, notes=notes)
    print(summary(card, out))
    return 0


def summary(card: dict[str, Any], out: Path) -> str:
    """What ``bushenv fit`` prints on stdout: files written, what the card says of the
    identification, and the metrics of every record (per coordinate where the card has them)."""
    from bushenv.identify.card import card_paths
    from bushenv.identify.card_text import coordinates, per_coordinate

    src = card["source"]
    json_path, md_path = card_paths(out)
    lines = [
        f"model {card['model']} -> {out} (card {json_path.name}, {md_path.name}; "
        f"{len(card.get('plots') or [])} figures)",
        f"identified in {src['wall_time_s']:.1f} s, seed {src['seed']}",
    ]
    if src.get("time_limited"):
        lines.append(f"stopped early: {src['stopped']} (the card records the budget used)")
    if src.get("choice"):
        lines.append(f"network chosen on validation: {src['choice']['summary']}")
    if src.get("note"):
        lines.append(f"note: {src['note']}")
    if card.get("parameters"):
        params = card["parameters"].items()
        lines.append(
            "parameters: " + ", ".join(f"{k} = {p['value']:.6g} {p['unit']}" for k, p in params)
        )
    lines += _card_lines(card)
    lines += [f"{k}: {v}" for k, v in (src.get("info") or {}).items()]
    if card.get("notes"):
        lines.append(f"{len(card['notes'])} note(s) on the records, in the card (shown above)")
    # full names, the column as wide as the longest (the card's paths, relative to it)
    names = [str(out.parent / r["file"]) if r["file"] else r["name"] for r in card["records"]]
    names = [os.path.normpath(n) for n in names]
    width = max(30, *(len(n) for n in names))
    coords = coordinates(card)
    lines += ["", f"{'record':{width}s} {'role':9s} {'coordinate':10s} {'RMS ratio %':>12s} "
              f"{'ESR %':>8s} {'max err':>10s} {'MAX %':>7s} {'NRMSE %':>8s}"]  # fmt: skip
    for name, r in zip(names, card["records"], strict=True):
        for coord, m in per_coordinate(r["metrics"], coords).items():
            err = m.get("max_error")
            cells = [_pct(m.get("rms_ratio")), _pct(m.get("esr")),
                     "-" if err is None else f"{err:.1f}", _pct(m.get("max_error_ratio")),
                     _pct(m.get("nrmse"))]  # fmt: skip
            lines.append(
                f"{name:{width}s} {r['role']:9s} {coord:10s} {cells[0]:>12s} {cells[1]:>8s} "
                f"{cells[2]:>10s} {cells[3]:>7s} {cells[4]:>8s}"
            )
    return "\n".join(lines)


def _pct(v: float | None) -> str:
    return "-" if v is None else f"{100 * v:.2f}"


def _card_lines(card: dict[str, Any]) -> list[str]:
    """The card's findings on the model's range: holds, backbone alone, coverage."""
    from bushenv.certify.range_holds import describe
    from bushenv.identify.card_text import backbone_lines, coordinates, coverage_lines
    from bushenv.models import MODELS

    lines = []
    if card.get("holds"):
        units = MODELS[card["model"]].model_class(len(coordinates(card))).units
        lines += describe(card["holds"], units)
    lines += backbone_lines(card) if card.get("backbone") else []
    return lines + coverage_lines(card)
