"""``bushenv fit`` on 3-axis records: the records' header decides, the planar models fit.

A record whose header names the planar columns (``bushenv.planar.records.HEADER``) is a 3-axis
record; ``bushenv fit`` then takes ``--model`` among the kinds ``MODELS`` can identify over three
coordinates and writes the model
file and its per-axis card (``bushenv.planar.card``). Training and held-out records must all
be of one kind.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from bushenv.planar.records import HEADER_TEXT
from bushenv.record_files import record_coordinates

PLANAR_LABEL = " (3-axis)"  # how the planar models own their flags in ``bushenv fit --help``


def planar_records(args: argparse.Namespace) -> bool:
    """True when every record given is 3-axis, False when none is; refuses a mix (CliError)."""
    from bushenv.cli import CliError

    paths = [*args.train, *(args.validate or [])]
    kinds = {p: record_coordinates(p) == 3 for p in paths}
    planar = [p for p, k in kinds.items() if k]
    if not planar:
        return False
    single = [p for p, k in kinds.items() if not k]
    if single:
        raise CliError(
            f"{planar[0]} is a 3-axis record but {single[0]} is not ({len(planar)} 3-axis, "
            f"{len(single)} other): give records of one kind to one fit, the 3-axis ones with "
            f"the header '{HEADER_TEXT}'"
        )
    return True


def planar_options(args: argparse.Namespace, given: dict[str, str]) -> dict[str, str]:
    """The given options, checked against the planar model's own (CliError naming the flag)."""
    from bushenv.cli import CliError
    from bushenv.identify.options import flag_of, option_fields
    from bushenv.planar.fitting import options_class

    own = [f.name for f in option_fields(options_class(args.model))]
    for name in given:
        if name not in own:
            raise CliError(
                f"{flag_of(name)} is not an option of the 3-axis model {args.model}; it takes: "
                f"{', '.join(flag_of(n) for n in own) or 'no options'}"
            )
    return given


def run_planar(args: argparse.Namespace, out: Path, given: dict[str, Any]) -> int:
    """Load the 3-axis records, identify, write the model and its card, print the summary."""
    from bushenv.cli import CliError
    from bushenv.models import names_for
    from bushenv.planar.card import save_planar_fit
    from bushenv.planar.fitting import fit_planar, length_problem
    from bushenv.planar.records import load_planar_csv, start_notes
    from bushenv.records import STEP_RTOL

    if args.model not in names_for(3, fittable=True):
        raise CliError(
            f"model {args.model} has no 3-axis identification; for 3-axis records choose "
            f"one of: {', '.join(names_for(3, fittable=True))}"
        )
    if args.resample is not None:
        raise CliError("--resample is for one-axis records; give 3-axis records at one rate")
    given = planar_options(args, given)
    train = [load_planar_csv(p) for p in args.train]
    held = [load_planar_csv(p) for p in args.validate or []]
    dt = train[0].dt
    for rec in train[1:] + held:
        if abs(rec.dt - dt) > STEP_RTOL * dt:
            raise CliError(
                f"{rec.source} is sampled at {1 / rec.dt:.6g} Hz (line 3 on), {train[0].source} "
                f"at {1 / dt:.6g} Hz: check both time columns' units ('time [ms]'), then give "
                "3-axis records at one rate (resample them first)"
            )
    short = length_problem(args.model, given, {r.source: r.time.size for r in train})
    if short:
        raise CliError(short)
    say = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    notes = [n for rec in train + held for n in start_notes(rec)]
    for note in notes:
        print(f"note: {note}", file=sys.stderr, flush=True)
    if say:
        seconds = sum(r.time.size * dt for r in train)
        say(f"fit {args.model} (3-axis) on {len(train)} record(s), {seconds:.1f} s at "
            f"{1 / dt:.6g} Hz")  # fmt: skip
    result = fit_planar([(r.q, r.f) for r in train], args.model, given, dt, args.seed, say)
    card = save_planar_fit(result, out, train, held, notes, plots=not args.no_plots)
    print(summary(card, out))
    return 0


def summary(card: dict[str, Any], out: Path) -> str:
    """What ``bushenv fit`` prints for a 3-axis fit: files and per-axis metrics."""
    from bushenv.identify.card import card_paths
    from bushenv.models.planar_base import COORDS

    json_path, md_path = card_paths(out)
    src = card["source"]
    lines = [
        f"model {card['model']} (3-axis) -> {out} (card {json_path.name}, {md_path.name})",
        f"identified in {src['wall_time_s']:.1f} s, seed {src['seed']}",
    ]
    if card.get("holds"):
        from bushenv.planar.range_holds import describe

        lines += describe(card["holds"])
    if card.get("backbone"):
        from bushenv.planar.card import backbone_lines

        lines += backbone_lines(card)
    from bushenv.planar.card import coverage_lines

    lines += coverage_lines(card)
    if card.get("plots"):
        lines.append(f"figures: {', '.join(card['plots'])}")
    lines += [f"{k}: {v}" for k, v in src["info"].items()]
    if card.get("notes"):
        lines.append(f"{len(card['notes'])} note(s) on the records, in the card (shown above)")
    names = [r["file"] or r["name"] for r in card["records"]]
    width = max(30, *(len(n) for n in names))
    lines += ["", f"{'record':{width}s} {'role':9s} {'axis':9s} {'RMS ratio %':>12s} "
              f"{'ESR %':>8s} {'MAX %':>8s}"]  # fmt: skip
    for name, r in zip(names, card["records"], strict=True):
        for c in COORDS:
            m = r["metrics"][c]
            cells = [
                "-" if m[k] is None else f"{100 * m[k]:.2f}"
                for k in ("rms_ratio", "esr", "max_error_ratio")
            ]
            lines.append(
                f"{name:{width}s} {r['role']:9s} {c:9s} {cells[0]:>12s} {cells[1]:>8s} "
                f"{cells[2]:>8s}"
            )
    return "\n".join(lines)
