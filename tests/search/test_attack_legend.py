"""The attack's table explains every column and every line it prints."""

import re

from bushenv.search.campaign_report import COLUMNS, format_table, legend_lines, report_markdown


def _row(diverged: bool) -> dict:
    cov = {"step": {"profiles": 3, "peak_mm_min": 0.5, "peak_mm_max": 4.0, "max_rate_m_per_s": 1}}
    ff = {
        "family": "step",
        "verdict": {"first_criterion": "static"},
        "reference_in_envelope": False,
    }
    return {
        "diverged": diverged,
        "evaluations": 16,
        "evaluations_to_failure": 2 if diverged else None,
        "seconds_to_failure": 0.5 if diverged else None,
        "worst_deviation": 1.3,
        "worst_robustness": -0.4 if diverged else 0.2,
        "first_failure": ff if diverged else None,
        "coverage": cov,
    }


def _report() -> dict:
    check = {"check": "holds", "passed": True, "verdict": "pass", "detail": "every hold settles"}
    return {
        "arguments": {"seed": 0},
        "reference": {"spec": "rubber"},
        "criteria": {"run": ["deviation", "static"], "why": "all, against the reference"},
        "judge": {
            "reference": "rubber",
            "vetting": {"passed": True, "verdict": "passed", "checks": [check]},
            "envelope": {
                "max_abs_displacement_m": 0.0125,
                "max_abs_velocity_m_per_s": 1.2,
                "source": "the judged stroke and velocity",
            },  # fmt: skip
        },
        "notes": ["static not judged: an example"],
        "models": {
            "nn": {"role": "target", "searchers": {"random": _row(True), "cma": _row(False)}},
            "linear": {"role": "control", "searchers": {"random": _row(False)}},
        },
        "hold_stage": {
            "run": True,
            "listed": 2,
            "confirmed": 1,
            "holds": [
                {"x_mm": 4.0, "listed_as": ["wrong_sign"], "confirmed": True, "criterion": "static"}
            ],
        },  # fmt: skip
        "recheck": {"profiles": 3, "linear": {"diverged": 0}},
        "shrunk": [
            {"shrink": None, "verdicts": {"nn": {"diverged": True}}},
            {
                "failed_model": "nn",
                "family": "step",
                "verdicts": {"nn": {"diverged": True}},
                "shrink": {"final": {"segments": 2, "samples": 9, "peak_um": 4000.0}},
            },  # fmt: skip
        ],
        "scales": {
            "stroke_m": 0.0125,
            "velocity_m_per_s": 1.2,
            "force_floor_n": 200.0,
            "force_limit_n": 25e3,
            "source": "test",
        },  # fmt: skip
    }


def _legend(printed: str) -> tuple[list[str], list[str]]:
    """(column names, line keys) as the printed legend gives them."""
    lines = printed.splitlines()
    a = lines.index("what the columns say:")
    b = lines.index("what the lines around it say:")
    names = [re.split(r"\s{2,}", ln.strip())[0] for ln in lines[a + 1 : b] if ln[2] != " "]
    keys = [ln.strip().split(":")[0] for ln in lines[b + 1 :] if ln[2] != " "]
    return names, keys


def test_every_printed_column_has_a_legend_line():
    printed = format_table(_report(), "nn")
    lines = printed.splitlines()
    k = next(i for i, ln in enumerate(lines) if set(ln) == {"-"})
    header = lines[k - 1]
    names, _ = _legend(printed)
    rest = header
    for name in names:
        assert name in rest, f"legend names {name!r}, the table prints no such column"
        rest = rest.replace(name, "", 1)
    assert rest.strip() == "", f"printed columns without a legend line: {rest.split()}"
    assert "worst dev" in names and "robustness" in names


def test_every_line_around_the_table_has_a_legend_line():
    printed = format_table(_report(), "nn")
    _, keys = _legend(printed)
    table = printed.split("\nwhat the columns say:")[0].splitlines()
    k = next(i for i, ln in enumerate(table) if set(ln) == {"-"})
    rows = set(range(k - 1, k + 4))  # the header, the dashes and the three rows
    for i, line in enumerate(table):
        if i in rows or not line or line.startswith(" "):
            continue
        assert any(line.startswith(key) for key in keys), f"no legend for: {line!r}"
    assert "certificate holds" in keys and "covered on" in keys


def test_the_legend_is_one_list_shared_with_report_md():
    md = report_markdown(_report(), "nn", [])
    assert "what the columns say" not in md  # the markdown has its own table of them
    for c in COLUMNS:
        assert f"| {c.name} | {c.meaning.replace('|', chr(92) + '|')} |" in md
    rows = [ln for ln in md.splitlines() if ln.startswith("| ")]
    assert all(ln.replace("\\|", "").count("|") == 3 for ln in rows)  # two cells each
    assert len(legend_lines()) > len(COLUMNS)


def test_a_report_without_a_reference_prints_the_legend_too():
    r = _report()
    r["reference"], r["judge"], r["hold_stage"] = {"spec": None}, {"reference": None}, None
    printed = format_table(r, "nn")
    assert "judge: no reference" in printed
    names, keys = _legend(printed)
    assert "judge" in keys and "certificate holds" not in keys
    assert len(names) == len(COLUMNS)
