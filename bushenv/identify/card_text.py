"""A model card for people: the markdown beside the model file, and the lines ``bushenv fit``
and ``bushenv card`` print (the records beyond the training range, the held combinations it
never showed, the network against its backbone alone). Any number of coordinates."""

from __future__ import annotations

from typing import Any

WORSE_BY = 0.05  # a network worse than its backbone alone by more than this share is warned of
BEYOND = 0.05  # a held-out record past the training deflection by more than this share is named
THREE = ("axial", "radial", "rotation")  # the coordinates of three-axis cards without ``coords``
FORCE_UNIT = {"rotation": "N m"}  # a coordinate's force unit where it is not N


def coordinates(card: dict[str, Any]) -> list[str]:
    """The card's coordinates: its ``coords``, else those its first record's metrics name (a
    card written before ``coords``)."""
    if card.get("coords"):
        return list(card["coords"])
    for r in card.get("records", []):
        m = r.get("metrics") or {}
        if m and "rms_ratio" not in m:
            return list(m)
    return ["deflection"]


def per_coordinate(metrics: dict | None, coords: list[str]) -> dict[str, dict]:
    """A record's metrics by coordinate (one coordinate's are stored flat)."""
    if not metrics:
        return {}
    return {coords[0]: metrics} if "rms_ratio" in metrics else metrics


def _pct(v: float | None) -> str:
    return "-" if v is None else f"{100 * v:.2f}"


def card_markdown(card: dict[str, Any]) -> str:
    """The card for people: what, from which records, how well (per coordinate), with which
    options."""
    src = card["source"]
    coords = coordinates(card)
    lines = [
        f"# Model card: {card['model_file']}",
        "",
        f"- model: **{card['model']}** over {len(coords)} coordinate(s) ({', '.join(coords)}), "
        f"{card['sample_rate_hz']:.6g} Hz (dt = {card['dt_s']:.6g} s); sha256 "
        f"`{card['model_sha256']}`",
        f"- made by: {src['kind']} with bushenv {card['bushenv_version']} on {card['created']}",
    ]
    if src["kind"] == "fit":
        lines.append(f"- seed {src['seed']}, wall time {src['wall_time_s']:.1f} s")
        if src.get("stopped"):
            early = "**stopped early** by the time limit: " if src.get("time_limited") else ""
            lines.append(f"- training ended: {early}{src['stopped']}")
        if src.get("budget_used"):
            used = ", ".join(f"{k} {v}" for k, v in src["budget_used"].items())
            lines.append(f"- budget used: {used}")
        if src.get("choice"):
            lines.append(f"- network chosen on validation: {src['choice']['summary']}")
        if src.get("note"):
            lines.append(f"- **note**: {src['note']}")
        lines += [f"- {k}: {v}" for k, v in (src.get("info") or {}).items()]
    else:
        lines.append(f"- torch file `{src['torch_file']}`, sha256 `{src['torch_sha256']}`")
    lines += [f"- note: {n}" for n in card.get("notes", [])]
    if card.get("parameters"):
        lines += ["", "## Parameters", "", "| parameter | value | unit |", "|---|---:|---|"]
        params = card["parameters"].items()
        lines += [f"| {k} | {p['value']:.6g} | {p['unit']} |" for k, p in params]
    lines += _records_table(card["records"], coords)
    beyond = coverage_lines(card)
    if beyond:
        lines += ["", "## Held-out records beyond the training range", ""]
        lines += [f"- {line}" for line in beyond]
    if card.get("holds"):
        from bushenv.certify.range_holds import describe

        units = ["rad" if c == "rotation" else "m" for c in coords]
        lines += ["", "## Holds over the training range", ""] + describe(card["holds"], units)
    if card.get("backbone"):
        lines += ["", "## The network against its backbone alone", ""] + backbone_lines(card)
    lines += ["", "## Options", "", "| option | value |", "|---|---|"]
    lines += [f"| {k} | {v} |" for k, v in src.get("options", {}).items()]
    for name in card.get("plots", []):
        lines += ["", f"![{name}]({name})"]
    return "\n".join(lines) + "\n"


def _records_table(records: list[dict[str, Any]], coords: list[str]) -> list[str]:
    if not records:
        return ["", "No records: the model was not identified here."]
    out = [
        "",
        "## Records",
        "",
        "Free run from rest on each record, per coordinate. RMS ratio and ESR: seed 000 eqs "
        "8-9; MAX: largest error over the largest measured |f| (Table 3); NRMSE: RMS error over "
        "the standard deviation of the measured force.",
        "",
        "| record | role | coordinate | rate Hz | duration s | RMS ratio % | ESR % | MAX % | "
        "max error | NRMSE % | sha256 |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---|",
    ]
    for r in records:
        digest = (r.get("sha256") or r.get("data_sha256") or "")[:16]
        by_coord = per_coordinate(r.get("metrics"), coords) or {c: None for c in coords}
        for c, m in by_coord.items():
            cells = (
                [_pct(m["rms_ratio"]), _pct(m["esr"]), _pct(m.get("max_error_ratio")),
                 f"{m['max_error']:.4g} {FORCE_UNIT.get(c, 'N')}", _pct(m.get("nrmse"))]
                if m else [""] * 5
            )  # fmt: skip
            out.append(
                f"| {r['file'] or r['name']} | {r['role']} | {c} | {r['sample_rate_hz']:.6g} | "
                f"{r['duration_s']:.2f} | {' | '.join(cells)} | `{digest}` |"
            )
    return out


def backbone_lines(card: dict[str, Any]) -> list[str]:
    """The model and its backbone alone on the held-out records, worst RMS (MAX) per
    coordinate, and the coordinates where the network makes the worst RMS ratio worse by more
    than ``WORSE_BY``."""
    coords = coordinates(card)
    held = [r for r in card["records"] if r["role"] == "held-out"]
    mine = _worst((per_coordinate(r["metrics"], coords) for r in held), coords)
    theirs = _worst(
        (per_coordinate(r["metrics"], coords) for r in card["backbone"]["records"]), coords
    )
    line = (
        f"held-out records, worst RMS ratio (MAX) % {' / '.join(coords)}: {card['model']} "
        f"{_cells(mine, coords)}; its backbone alone ({card['backbone']['model']}) "
        f"{_cells(theirs, coords)}"
    )
    worse = [
        c
        for c in coords
        if None not in (mine[c][0], theirs[c][0]) and mine[c][0] > (1 + WORSE_BY) * theirs[c][0]
    ]
    if not worse:
        return [line]
    return [
        line,
        f"warning: on records it never saw the network makes the {', '.join(worse)} worse "
        f"than its backbone alone: the backbone ({card['backbone']['model']}) may be the "
        "better model there",
    ]


def coverage_lines(card: dict[str, Any]) -> list[str]:
    """What the training records showed (held combinations), and the held-out records that go
    beyond it: beyond the largest deflection in some coordinate by more than ``BEYOND``, or
    holding a combination training never held: their figures judge extrapolation, not the
    fit's range."""
    from bushenv.identify.coverage import coverage_summary

    span = card.get("training_range")
    if not span:
        return []
    cov = card.get("coverage")
    out = coverage_summary(cov) if cov and (cov["held_shown"] or cov["held_not_shown"]) else []
    for r in card["records"]:
        if r.get("not_shown"):
            out.append(
                f"not shown: {r['file'] or r['name']} holds {'; '.join(sorted(r['not_shown']))}, "
                "which the training records never held: its figures judge a use the model was "
                "not shown"
            )
    for r in card["records"]:
        peak = r.get("peak_deflection") or (
            {next(iter(span)): r["max_abs_displacement_m"]}
            if "max_abs_displacement_m" in r
            else None
        )
        if r["role"] != "held-out" or not peak:
            continue
        ratios = {c: peak[c] / span[c] for c in span if span[c] > 0}
        beyond = {c: x for c, x in ratios.items() if x > 1 + BEYOND}
        beyond |= {c: None for c in span if span[c] == 0 and peak[c] > 0}
        if beyond:
            shown = ", ".join(
                f"{c} {x:.2f}x" if x is not None else f"{c} (never moved in training)"
                for c, x in beyond.items()
            )
            out.append(
                f"extrapolation: {r['file'] or r['name']} goes beyond the training records' "
                f"largest deflection ({shown}): its figures judge the model outside the range it "
                "was identified on, where a fit's error grows fast (docs/planar.md)"
            )
    return out


def _worst(metrics, coords: list[str]) -> dict[str, list[float | None]]:
    """Per coordinate [worst RMS ratio, worst MAX] over per-record metrics."""
    out: dict[str, list[float | None]] = {c: [None, None] for c in coords}
    for m in metrics:
        for c in coords:
            for k, key in enumerate(("rms_ratio", "max_error_ratio")):
                v = m[c][key]
                if v is not None and (out[c][k] is None or v > out[c][k]):
                    out[c][k] = v
    return out


def _cells(worst: dict[str, list[float | None]], coords: list[str]) -> str:
    return " / ".join(f"{_pct(worst[c][0])} ({_pct(worst[c][1])})" for c in coords)
