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


def _metric_text(m: dict | None) -> str:
    """RMS ratio of a record: one figure, or per axis on a planar card."""
    if not m:
        return ""
    if "rms_ratio" in m:
        return f"RMS ratio {100 * m['rms_ratio']:.2f} %"
    cells = [
        f"{c} {100 * m[c]['rms_ratio']:.2f} %" if m[c]["rms_ratio"] is not None else f"{c} -"
        for c in m
    ]
    return "RMS ratio " + ", ".join(cells)


def run(args: argparse.Namespace) -> int:
    from bushenv.identify.card import CARD_FORMAT, load_card
    from bushenv.planar.card import CARD_FORMAT as PLANAR_FORMAT

    card = load_card(args.card, records=args.records, formats=(CARD_FORMAT, PLANAR_FORMAT))
    d = card.data
    src = d["source"]
    print(
        f"{card.path}: model {d['model']} in {d['model_file']} (sha256 matches), "
        f"{d['sample_rate_hz']:.6g} Hz, made by {src['kind']} with bushenv {d['bushenv_version']}"
    )
    for r in card.records:
        score = _metric_text(r.get("metrics"))
        checked = (
            " (checked)" if (r["file"] or r["name"]).endswith(tuple(card.checked_records)) else ""
        )
        print(
            f"  {r['role']:9s} {r['file'] or r['name']}  {r['duration_s']:.1f} s  {score}{checked}"
        )
    if d.get("format") == PLANAR_FORMAT:  # held-out records that judged extrapolation
        from bushenv.planar.card import coverage_lines

        for line in coverage_lines(d):
            print(f"  {line}")
    if args.records:
        print(f"{len(args.records)} record file(s) match the card")
    return 0
