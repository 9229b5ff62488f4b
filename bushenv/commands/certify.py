"""``bushenv certify``: hold-stability and passivity certificates of a NARX model, of one
coordinate or of several (``bushenv.planar.certificate``: holds on a grid of deflection vectors).

Writes DIR/certificate.json and three plots (static force, spectral radius, Im K); prints a
summary on stdout and progress on stderr. Exits as a test runner does: 0 when the certificate
passes (holds and passivity), 1 when it fails, 2 on bad input. The reference and the stroke
come from the one judging setup (``bushenv.judge``): the stroke is the model card's (1.5 x its
records'), the papers' +-12.5 mm only for the shipped models, ``--stroke-mm`` on top; without a
reference only the reference-free parts run, and the summary says what needs one.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from bushenv.certify.certificate import CertifyOptions, certify
from bushenv.certify.network import CertifyError, narx_net
from bushenv.certify.plots import passivity_plot, spectral_radius_plot, static_force_plot
from bushenv.judge import ScaleFlags, build_judge
from bushenv.models import MODELS, get_model
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
        help="nn, hybrid or a NARX model file (.npz) of one or three coordinates",
    )
    parser.add_argument(
        "--reference",
        default=None,
        help="registered name, model file or 'none': what the static force and Im K are "
        "compared with (default: rubber for a registered model; none for a model file, then "
        "the static comparison is not made)",
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
        help=f"held displacements over the stroke, >= 3 (default: {DEFAULTS.holds})",
    )
    parser.add_argument(
        "--stroke-mm",
        type=float,
        default=None,
        help="holds span -S..+S mm (default: the model card's stroke, 1.5 x its records'; "
        f"{DEFAULTS.stroke_m * 1e3:g}, the machine's, for the shipped models)",
    )
    parser.add_argument(
        "--rotation-mrad",
        type=float,
        default=None,
        help="three-axis models: holds span -R..+R mrad in rotation (default: 1.5 x the "
        "card's training range)",
    )
    parser.add_argument(
        "--at-mm",
        type=_mm_list,
        default=(),
        help="held displacements to certify besides the grid, mm, e.g. 0.53,4 (default: none)",
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
        help="holds about which K is computed, mm "
        f"(default: {_fmt_mm(DEFAULTS.passivity_holds_m)})",
    )
    parser.add_argument(
        "--sine-mm",
        type=float,
        default=DEFAULTS.reference_amplitude_m * 1e3,
        help="amplitude of the sines that measure the reference's K, mm "
        f"(default: {DEFAULTS.reference_amplitude_m * 1e3:g})",
    )
    parser.add_argument(
        "--energy-mm",
        type=_mm_list,
        default=DEFAULTS.energy_amplitudes_m,
        help="amplitudes of the sines judged for the energy criterion, mm "
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
    if model.n_coords > 1:
        return _run_vector(args, model, out, target)
    try:
        narx_net(model)
    except CertifyError as exc:
        raise CertifyError(f"{args.model}: {exc}") from None
    judge = build_judge(
        args.model,
        args.reference,
        axis=args.axis,
        dt=model.dt,
        flags=ScaleFlags(stroke_mm=args.stroke_mm),
        trust_reference=args.trust_reference,
        model_object=model,
    )
    reference = judge.reference
    if args.stroke_mm is None and args.model not in MODELS and "card" not in judge.scales.source:
        raise CertifyError(
            f"{args.model}: no model card to take the stroke from (and the papers' +-12.5 mm "
            "is the shipped models' only); give --stroke-mm S, the stroke the model is for"
        )
    opts = CertifyOptions(
        holds=args.holds,
        extra_holds_m=args.at_mm,
        stroke_m=judge.scales.stroke_m,
        hold_s=args.hold_s,
        velocity=args.velocity,
        passivity_holds_m=args.passivity_mm,
        reference_amplitude_m=args.sine_mm * 1e-3,
        energy_amplitudes_m=args.energy_mm,
    )
    report = _progress(args.quiet)
    cert = certify(model, reference, opts, progress=report)
    doc = cert.document
    doc["model"]["source"] = str(args.model)
    doc["model"]["axis"] = args.axis
    doc["reference"] = {
        "source": judge.reference_spec,
        "class": None if reference is None else type(reference).__name__,
    }
    doc["judge"] = judge.describe()
    report("plots", 0.99)
    out.mkdir(parents=True, exist_ok=True)
    name = f"{Path(args.model).name} ({args.axis})"
    paths = [
        static_force_plot(cert, out / "static_force.png", f"{name}: static force in a hold"),
        spectral_radius_plot(cert, out / "spectral_radius.png", f"{name}: hold stability"),
        passivity_plot(cert, out / "passivity.png", f"{name}: small-signal Im K"),
    ]
    write_json(target, doc)
    _summary(doc, [target, *paths], judge)
    s = doc["summary"]
    return 0 if s["passes_holds"] and s["passes_passivity"] else 1


def _vector_span(args: argparse.Namespace, model) -> tuple[tuple[float, ...], str]:
    """The holds' half-width per coordinate: 1.5 x the card's training range (the one-axis
    stroke rule), else --stroke-mm for translations and --rotation-mrad for rotations."""
    from bushenv.identify.card import card_paths

    given = {"m": args.stroke_mm, "rad": args.rotation_mrad}
    if all(given[u] is not None for u in model.units):
        return tuple(given[u] * 1e-3 for u in model.units), "--stroke-mm/--rotation-mrad"
    card = card_paths(args.model)[0]
    if Path(args.model).suffix == ".npz" and card.is_file():
        import json

        span = json.loads(card.read_text()).get("training_range")
        if span:
            out = [
                1.5 * span[c] if given[u] is None else given[u] * 1e-3
                for c, u in zip(model.coords, model.units, strict=True)
            ]
            return tuple(out), f"1.5 x the training range of {card.name}"
    missing = " and ".join(
        f for f, u in (("--stroke-mm", "m"), ("--rotation-mrad", "rad")) if given[u] is None
    )
    raise CertifyError(
        f"{args.model}: no model card with a training range beside it to take the holds' span "
        f"from; give {missing} (the deflections the bushing is used at)"
    )


def _run_vector(args: argparse.Namespace, model, out: Path, target: Path) -> int:
    """The certificate over C > 1 coordinates (``bushenv.planar.certificate``): holds on a grid of
    deflection vectors, wrong sign without a reference, passivity as a matrix test."""
    from bushenv.planar.certificate import (
        VectorOptions,
        certify_vector,
        per_coordinate,
        radius_plot,
    )

    if args.reference not in (None, "none"):
        raise CertifyError(
            f"--reference {args.reference}: a three-axis certificate compares with no reference "
            "yet (wrong sign is judged against the deflection, q . f >= 0); drop --reference"
        )
    span, source = _vector_span(args, model)
    opts = VectorOptions(span, per_coordinate(args.holds, model.n_coords))
    doc, grid = certify_vector(model, opts, progress=_progress(args.quiet))
    doc["model"] = {"source": str(args.model), "name": model.name, "dt_s": model.dt}
    doc["settings"]["span_source"] = source
    out.mkdir(parents=True, exist_ok=True)
    plot = radius_plot(doc, grid, out / "spectral_radius.png", f"{Path(args.model).name}: holds")
    write_json(target, doc)
    s = doc["summary"]
    units = ["mrad" if u == "rad" else "mm" for u in model.units]
    shown = ", ".join(
        f"{c} +-{v * 1e3:.4g} {u}" for c, v, u in zip(model.coords, span, units, strict=True)
    )
    print(f"holds over {shown} ({source}); no reference: wrong sign is q . f < 0")
    print(
        f"holds: {s['holds']} ({opts.per_coordinate} per coordinate), settling stably "
        f"{s['holds_settling_stably']}, more than one fixed point {s['holds_with_more_than_one']}, "
        f"no stable one {s['holds_without_a_stable_one']}, fold crossings {s['fold_crossings']}, "
        f"wrong sign {s['wrong_sign_holds']}"
    )
    print(
        f"passivity: {s['non_passive_holds']} of {s['passivity_holds']} holds non-passive "
        f"(least loss eigenvalue {s['least_loss_eigenvalue_j']:.3g} J); hold certificate "
        f"{'passes' if s['passes_holds'] else 'FAILS'}, passivity "
        f"{'passes' if s['passes_passivity'] else 'FAILS'}"
    )
    print(target)
    print(plot)
    return 0 if s["passes_holds"] and s["passes_passivity"] else 1


def _mm_ranges(ranges: list[list[float]]) -> str:
    return "[" + ", ".join(f"{a * 1e3:+.3g}..{b * 1e3:+.3g} mm" for a, b in ranges) + "]"


def _hz_bands(bands: list[list[float]]) -> str:
    return "[" + ", ".join(f"{a:.1f}-{b:.1f} Hz" for a, b in bands) + "]"


def _summary(doc: dict, paths: list[Path], judge) -> None:
    s = doc["summary"]
    print(
        f"stroke +-{judge.scales.stroke_m * 1e3:.4g} mm ({judge.scales.source}); reference: "
        f"{judge.reference_spec or 'none'}"
        + ("" if judge.vetting is None else f", vetting {judge.vetting.headline()}")
    )
    if judge.reference is None:
        print(
            "no reference: wrong sign is judged against the deflection (a passive bushing's "
            "static force has the sign of x); the static force's size (off the reference's) "
            "needs one and was not compared; pass --reference NAME|FILE"
        )
    print(
        f"holds: {s['holds']}, settling stably {s['holds_settling_stably']}, departing "
        f"{s['departing_holds']}, oscillating {s['oscillating_holds']}, folds {s['folds']}; "
        f"wrong sign {s['wrong_sign_holds']} {_mm_ranges(s['wrong_sign_ranges_m'])}, static "
        f"force off {s['static_off_holds']} {_mm_ranges(s['static_off_ranges_m'])}"
    )
    print(
        f"non-passive at rest: {_hz_bands(s['non_passive_bands_hz_at_rest'])}; "
        f"hold certificate {'passes' if s['passes_holds'] else 'FAILS'}, passivity "
        f"{'passes' if s['passes_passivity'] else 'FAILS'}"
    )
    for p in paths:
        print(p)
