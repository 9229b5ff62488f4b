"""The files of one diagnosis: report.json, report.md, plots and the predictions (CSV).

Below both the one-axis report (``report.py``) and the report of several coordinates
(``coordinates_report.py``, which writes one of these per coordinate).
"""

from __future__ import annotations

import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from bushenv.diagnose.plots import make_plots
from bushenv.persist import write_text


def json_safe(obj: Any) -> Any:
    """Plain JSON values; non-finite numbers become None."""
    if isinstance(obj, dict):
        return {k: json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [json_safe(v) for v in obj]
    if isinstance(obj, float | np.floating):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def write_predictions(pred: dict[str, Any], path: Path) -> None:
    cols = ("time", "force_measured", "force_baseline", "force_augmented")
    data = np.column_stack([np.asarray(pred[c], dtype=np.float64) for c in cols])
    text = io.StringIO()
    np.savetxt(text, data, delimiter=",", header=",".join(cols), comments="", fmt="%.10g")
    write_text(path, text.getvalue())


def write_report(result: dict[str, Any], out: Path) -> None:
    """report.json, report.md, plots and predictions/<stem>.csv under ``out``."""
    from bushenv.diagnose.markdown import markdown

    out.mkdir(parents=True, exist_ok=True)
    (out / "predictions").mkdir(exist_ok=True)
    for pred in result["predictions"]:
        write_predictions(pred, out / "predictions" / f"{pred['name']}.csv")
    data = {k: v for k, v in result.items() if k != "predictions"}
    data["predictions"] = [f"predictions/{p['name']}.csv" for p in result["predictions"]]
    data["plots"] = make_plots(result, out)
    write_text(out / "report.json", json.dumps(json_safe(data), indent=2) + "\n")
    write_text(out / "report.md", markdown(data))
