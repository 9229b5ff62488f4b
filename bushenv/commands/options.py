"""Options several commands share (``--resample``): argparse lives in the command layer."""

from __future__ import annotations

import argparse
import math

from bushenv.record_rates import KEEP


def resample_value(text: str) -> float | str:
    """``--resample``'s value: a rate in Hz, or ``keep``."""
    if text.strip().lower() == KEEP:
        return KEEP
    try:
        hz = float(text)
    except ValueError:
        hz = math.nan
    if not (math.isfinite(hz) and hz > 0):
        raise argparse.ArgumentTypeError(f"expected a positive rate in Hz or 'keep', got {text!r}")
    return hz


def add_resample_option(parser: argparse.ArgumentParser, keep: bool = False) -> None:
    """``--resample HZ`` (and ``keep`` when the command can judge each record at its rate)."""
    extra = "; 'keep': each record at its own rate (linear baseline only)" if keep else ""
    parser.add_argument(
        "--resample",
        type=resample_value,
        default=None,
        metavar="HZ",
        help="bring records at different sample rates to HZ by linear interpolation (no "
        f"anti-alias filter: low-pass first when going coarser){extra}; without it such "
        "records are refused",
    )
