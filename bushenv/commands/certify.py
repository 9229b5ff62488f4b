"""``bushenv certify``: hold-stability and passivity certificates of a NARX model of any
number of coordinates (``bushenv.certify``: holds on a grid of deflection vectors).

Writes DIR/certificate.json and the plots that apply (static force, spectral radius, its map
over each pair of coordinates, the least loss eigenvalue); prints a summary on stdout and
progress on stderr. Exits as a test runner does: 0 when the certificate passes (holds and
passivity), 1 when it fails, 2 on bad input. The span of the holds is the judge's range, by
the attack's rule for any number of coordinates (``certify_setup``: 1.5 x the training records'
peak on the reference's card, else the model's, within the machine), the machine's only for the
shipped models, ``--stroke-mm`` / ``--rotation-mrad`` on top; without a reference only the
reference-free parts run, and the summary says what needs one.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bushenv.certify.certificate import certify
from bushenv.certify.network import CertifyError, narx_net
from bushenv.certify.options import CertifyOptions
from bushenv.certify.plots import certificate_plots
from bushenv.commands.certify_setup import Setup, setup
from bushenv.models import get_model
from bushenv.persist import write_json
from bushenv.progress import Progress

EXAMPLE = "bushenv certify hybrid --axis radial --reference rubber --out runs/certify-radial"
DEFAULTS = CertifyOptions()


def _mm_list(text: str) -> tuple[float, ...]:
    try:
        vals = tuple(float(v) * 1e-3 for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated mm values, got {text!r}"
        ) from None
    if not vals:
        raise argparse.ArgumentTypeError("expected at least one value")
    return vals


def _fmt_mm(vals: tuple[float, ...]) -> str:
    return ",".join(f"{v * 1e3:g}" for v in vals)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from bushenv.models import AXES

    parser.add_argument(
        "model",
        metavar="MODEL",
        help="nn, hybrid or a NARX model file (.npz) of any number of coordinates",
    )
    parser.add_argument(
        "--reference",
        default=None,
        help="registered name, model file or 'none': what the static force and the loss "
        "eigenvalues are compared with, of the model's coordinates (default: rubber for a "
        "registered model; none for a model file, then the static comparison is not made)",
    )
    parser.add_argument(
        "--trust-reference",
        action="store_true",
        help="certify against a reference that failed its vetting (marked in the certificate)",
    )
    parser.add_argument("--axis", default="axial", choices=AXES, help="(default: axial)")
    parser.add_argument(
        "--holds",
        type=int,
        default=DEFAULTS.holds,
        help="held deflections in all, >= 3; over C coordinates about holds^(1/C) per "
        f"coordinate, odd (default: {DEFAULTS.holds})",
    )
    parser.add_argument(
        "--stroke-mm",
        type=float,
        default=None,
        help="holds span -S..+S mm in every translation (default: the model card's stroke, 1.5 x "
        "its records' -- the reference's card, else the model's -- within the machine; "
        f"{DEFAULTS.stroke_m * 1e3:g}, the machine's, for the shipped models)",
    )
    parser.add_argument(
        "--rotation-mrad",
        type=float,
        default=None,
        help="holds span -R..+R mrad in every rotation (default: as --stroke-mm's)",
    )
    parser.add_argument(
        "--at-mm",
        type=_mm_list,
        default=(),
        help="one coordinate: held displacements to certify besides the grid, mm, e.g. 0.53,4 "
        "(default: none)",
    )
    parser.add_argument(
        "--hold-s",
        type=float,
        default=DEFAULTS.hold_s,
        help=f"length of every simulated hold, s (default: {DEFAULTS.hold_s:g})",
    )
    parser.add_argument(
        "--velocity",
        default=DEFAULTS.velocity,
        choices=("central", "backward"),
        help="velocity the hybrid's damper sees in K: central (simulate, the machine) or "
        "backward (the rigs) (default: central)",
    )
    parser.add_argument(
        "--passivity-mm",
        type=_mm_list,
        default=DEFAULTS.passivity_holds_m,
        help="one coordinate: holds about which K is computed, mm (over several: rest and "
        f"+-half the span along each) (default: {_fmt_mm(DEFAULTS.passivity_holds_m)})",
    )
    parser.add_argument(
        "--sine-mm",
        type=float,
        default=DEFAULTS.reference_amplitude_m * 1e3,
        help="amplitude of the sines that measure the reference's K, mm (rotations: the same "
        "fraction of 0.05 rad as of 2 mm) "
        f"(default: {DEFAULTS.reference_amplitude_m * 1e3:g})",
    )
    parser.add_argument(
        "--energy-mm",
        type=_mm_list,
        default=DEFAULTS.energy_amplitudes_m,
        help="one coordinate: amplitudes of the sines judged for the energy criterion, mm "
        f"(default: {_fmt_mm(DEFAULTS.energy_amplitudes_m)})",
    )
    parser.add_argument("--out", required=True, metavar="DIR", help="folder for the results")
    parser.add_argument("--force", action="store_true", help="replace an existing certificate")
    parser.add_argument("--quiet", action="store_true", help="no progress on stderr")


def _progress(quiet: bool):
    """``report(stage, fraction_done)`` on the shared progress lines (stderr, time left)."""
    progress = Progress(total=1.0, quiet=quiet, every_s=0.0)

    def report(stage: str, fraction: float) -> None:
        progress.update(fraction, stage)

    return report


def run(args: argparse.Namespace) -> int:
    if args.holds < 3:
        raise CertifyError(f"--holds must be >= 3, got {args.holds}")
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise CertifyError(f"--out {out}: exists and is not a folder")
    target = out / "certificate.json"
    if target.exists() and not args.force:
        raise CertifyError(f"{target} exists; pass --force to replace it")
    model = get_model(args.model, axis=args.axis, coords=None)
    try:
        narx_net(model)
    except CertifyError as exc:
        raise CertifyError(f"{args.model}: {exc}") from None
    how = setup(args, model)
    opts = CertifyOptions(
        holds=args.holds,
        extra_holds_m=args.at_mm,
        span=how.span,
        hold_s=args.hold_s,
        velocity=args.velocity,
        passivity_holds_m=args.passivity_mm,
        reference_amplitude_m=args.sine_mm * 1e-3,
        energy_amplitudes_m=args.energy_mm,
    )
    report = _progress(args.quiet)
    cert = certify(model, how.reference, opts, progress=report)
    doc = cert.document
    doc["model"]["source"] = str(args.model)
    doc["model"]["axis"] = args.axis
    doc["settings"]["span_source"] = how.span_source
    doc["reference"] = {
        "source": how.reference_spec,
        "class": None if how.reference is None else type(how.reference).__name__,
    }
    doc["judge"] = how.judge
    report("plots", 0.99)
    out.mkdir(parents=True, exist_ok=True)
    paths = certificate_plots(cert, out, how.title)
    write_json(target, doc)
    _summary(doc, [target, *paths], how)
    s = doc["summary"]
    return 0 if s["passes_holds"] and s["passes_passivity"] else 1


def _ranges(ranges: list[list[float]]) -> str:
    return "[" + ", ".join(f"{a * 1e3:+.3g}..{b * 1e3:+.3g} mm" for a, b in ranges) + "]"


def _hz_bands(bands: list[list[float]]) -> str:
    return "[" + ", ".join(f"{a:.1f}-{b:.1f} Hz" for a, b in bands) + "]"


def _where(s: dict, key: str) -> str:
    """The holds of a summary entry: ranges over one coordinate, a count over several."""
    ranges = s.get(f"{key}_ranges_m")
    return "" if ranges is None else " " + _ranges(ranges)


def _summary(doc: dict, paths: list[Path], how: Setup) -> None:
    s = doc["summary"]
    print(f"holds over {how.span_text} ({how.span_source}); reference: {how.reference_line}")
    if how.reference is None:
        print(
            "no reference: wrong sign is judged against the deflection (a passive bushing's "
            "static force points away from rest: q . f >= 0, F x >= 0 for one coordinate); "
            "the static force's size (off the reference's) needs one and was not compared; "
            "pass --reference NAME|FILE"
        )
    print(
        f"holds: {s['holds']} ({doc['settings']['per_coordinate']} per coordinate), settling "
        f"stably {s['holds_settling_stably']}, more than one fixed point "
        f"{s['holds_with_more_than_one']}, no stable one {s['holds_without_a_stable_one']}, "
        f"departing {s['departing_holds']}, oscillating {s['oscillating_holds']}, folds "
        f"{s['folds']}; wrong sign {s['wrong_sign_holds']}{_where(s, 'wrong_sign')}, static "
        f"force off {s['static_off_holds']}{_where(s, 'static_off')}"
    )
    least = s["least_loss_eigenvalue_j"]
    print(
        f"passivity: {s['non_passive_holds']} of {s['passivity_holds']} holds non-passive "
        f"(least loss eigenvalue {'n/a' if least is None else f'{least:.3g} J'}); non-passive "
        f"at rest: {_hz_bands(s['non_passive_bands_hz_at_rest'])}; hold certificate "
        f"{'passes' if s['passes_holds'] else 'FAILS'}, passivity "
        f"{'passes' if s['passes_passivity'] else 'FAILS'}"
    )
    for p in paths:
        print(p)
