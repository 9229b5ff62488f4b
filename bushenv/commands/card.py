"""``bushenv card``: show a model's card and check it against its model file and records.

Exit 0 when the model file and every given record match the card; 2 (one line naming the
record or file) when one does not.
"""

from __future__ import annotations

import argparse

EXAMPLE = "bushenv card my_nn.npz train.csv held.csv"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("card", metavar="MODEL.npz|CARD.json", help="a model file or its card")
    p.add_argument(
        "records", nargs="*", metavar="RECORD.csv", help="record files to check against the card"
    )


def _metric_text(m: dict | None, coords: list[str]) -> str:
    """RMS ratio of a record: one figure for one coordinate, else one per coordinate."""
    from bushenv.identify.card_text import per_coordinate

    by = per_coordinate(m, coords)
    if not by:
        return ""
    cells = [
        f"{100 * v['rms_ratio']:.2f} %" if v["rms_ratio"] is not None else "-" for v in by.values()
    ]
    if len(cells) == 1:
        return f"RMS ratio {cells[0]}"
    return "RMS ratio " + ", ".join(f"{c} {x}" for c, x in zip(by, cells, strict=True))


def run(args: argparse.Namespace) -> int:
    from bushenv.identify.card import load_card
    from bushenv.identify.card_text import coordinates, coverage_lines

    card = load_card(args.card, records=args.records)
    d = card.data
    src = d["source"]
    print(
        f"{card.path}: model {d['model']} in {d['model_file']} (sha256 matches), "
        f"{d['sample_rate_hz']:.6g} Hz, made by {src['kind']} with bushenv {d['bushenv_version']}"
    )
    for r in card.records:
        score = _metric_text(r.get("metrics"), coordinates(d))
        checked = (
            " (checked)" if (r["file"] or r["name"]).endswith(tuple(card.checked_records)) else ""
        )
        print(
            f"  {r['role']:9s} {r['file'] or r['name']}  {r['duration_s']:.1f} s  {score}{checked}"
        )
    for line in coverage_lines(d):  # what the training records did not show
        print(f"  {line}")
    if args.records:
        print(f"{len(args.records)} record file(s) match the card")
    return 0
