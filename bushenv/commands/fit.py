"""``bushenv fit``: identify a model from measured records; write it, its card and figures.

The model choices are the registered models with an identification (``MODELS``), and each
model's own flags are built from its options dataclass (``ModelEntry.options``): one flag per
field, its help and default from the field. A flag several models share (``--time-budget-s``)
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
from bushenv.record_rates import one_rate

EXAMPLE = "bushenv fit train1.csv train2.csv --model hybrid --validate held.csv --out my_hybrid.npz"
DEST = "option_"  # argparse dest prefix of the model options


def model_options() -> dict[str, list[tuple[str, Any]]]:
    """Option name -> [(model, dataclass field)] for every model with an identification; the
    planar (3-axis) models' owners read "NAME (3-axis)"."""
    from bushenv.commands.fit_planar import PLANAR_LABEL
    from bushenv.models import MODELS, names_for

    table: dict[str, list[tuple[str, Any]]] = defaultdict(list)
    for name in fittable_models():
        for f in option_fields(options_class(name)):
            table[f.name].append((name, f))
    for name in names_for(3, fittable=True):
        for f in option_fields(MODELS[name].options_class(3)):
            table[f.name].append((name + PLANAR_LABEL, f))
    return dict(table)


def model_choices() -> list[str]:
    """``--model``: the one-axis fittable models, then the planar ones not named alike."""
    from bushenv.models import names_for

    one = fittable_models()
    return one + [n for n in names_for(3, fittable=True) if n not in one]


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
        help="model to identify (required); on 3-axis records a planar model (PLANAR_MODELS)",
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


def chosen_options(args: argparse.Namespace) -> dict[str, str]:
    """The model options given on the command line (name -> text); refuses another model's."""
    from bushenv.cli import CliError

    table = model_options()
    given = {k[len(DEST) :]: v for k, v in vars(args).items() if k.startswith(DEST)}
    for name in given:
        models = [m for m, _ in table[name]]
        if args.model not in models:
            own = [flag_of(n) for n, o in table.items() if args.model in (m for m, _ in o)]
            raise CliError(
                f"{flag_of(name)} is not an option of model {args.model} (it is one of "
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
    from bushenv.cli import CliError
    from bushenv.commands.fit_planar import planar_records, run_planar
    from bushenv.identify import fit
    from bushenv.identify.card import save_fit
    from bushenv.identify.data import check_model_rate, check_same_rate
    from bushenv.planar.records import HEADER_TEXT
    from bushenv.records import load_csv

    out = _check_paths(args)
    if planar_records(args):
        given = {k[len(DEST) :]: v for k, v in vars(args).items() if k.startswith(DEST)}
        return run_planar(args, out, given)
    if args.model not in fittable_models():
        raise CliError(
            f"model {args.model} is a 3-axis model: its records have the header "
            f"'{HEADER_TEXT}'; for one-axis records choose one of {', '.join(fittable_models())}"
        )
    given = chosen_options(args)
    train = [load_csv(p) for p in args.train]
    held = [load_csv(p) for p in args.validate or []]
    train, held = one_rate([train, held], args.resample, "fit")
    dt = check_same_rate(train, what="training records")
    for i, rec in enumerate(held):
        check_model_rate(rec, dt, i)
    say = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    if say:
        seconds = sum(r.duration_s for r in train)
        say(f"fit {args.model} on {len(train)} record(s), {seconds:.1f} s at {1 / dt:.6g} Hz")
    result = fit(train, args.model, given, seed=args.seed, progress=say or False)
    card = save_fit(result, out, held, plots=not args.no_plots)
    print(summary(card, out))
    return 0


def summary(card: dict[str, Any], out: Path) -> str:
    """What ``bushenv fit`` prints on stdout: files written and held-out metrics."""
    from bushenv.identify.card import card_paths

    src = card["source"]
    json_path, md_path = card_paths(out)
    lines = [
        f"model {card['model']} -> {out} (card {json_path.name}, {md_path.name}; "
        f"{len(card['plots'])} figures)",
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
    # full names, the column as wide as the longest (the card's paths, relative to it)
    names = [str(out.parent / r["file"]) if r["file"] else r["name"] for r in card["records"]]
    names = [os.path.normpath(n) for n in names]
    width = max(30, *(len(n) for n in names))
    lines += [
        "",
        f"{'record':{width}s} {'role':9s} {'RMS ratio %':>12s} {'ESR %':>8s} {'max err N':>10s} "
        f"{'NRMSE %':>8s}",
    ]
    for name, r in zip(names, card["records"], strict=True):
        m = r["metrics"]
        lines.append(
            f"{name:{width}s} {r['role']:9s} {100 * m['rms_ratio']:12.2f} "
            f"{100 * m['esr']:8.3f} {m['max_error']:10.1f} {100 * m['nrmse']:8.2f}"
        )
    return "\n".join(lines)
