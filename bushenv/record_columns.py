"""The columns of a record file of C coordinates: their names, units and plausibility limits,
and the reading of a header row (units in brackets, names in any order).

One coordinate: ``time,displacement,force`` (``bushenv.records``, exactly in that order). The
three in-plane coordinates:

    time,displacement_axial,displacement_radial,rotation,force_axial,force_radial,moment

in s, m, m, rad, N, N, N m unless a unit is written after a name in brackets, e.g.
``displacement_axial [mm]``, ``rotation [deg]``, ``moment [N mm]`` (``UNITS``), converted to SI
on load; the seven names may come in any order (a rig that writes each axis's displacement
beside its force is read as it is), each once, nothing else.
"""

from __future__ import annotations

import difflib
import re
from dataclasses import dataclass

import numpy as np

from bushenv.errors import BadInput

# units a header may state per kind of column, and their factor to SI
UNITS = {
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6},
    "displacement": {"m": 1.0, "mm": 1e-3, "um": 1e-6},
    "force": {"N": 1.0, "kN": 1e3},
    "rotation": {"rad": 1.0, "mrad": 1e-3, "deg": np.pi / 180.0},
    "moment": {"N m": 1.0, "Nm": 1.0, "N mm": 1e-3, "Nmm": 1e-3, "kN m": 1e3, "kNm": 1e3},
}
SI = {"displacement": "m", "rotation": "rad", "force": "N", "moment": "N m"}
# Plain-header plausibility (SI): beyond these the unit is almost surely wrong. Displacement 0.1
# m is eight times the test machine's stroke; rotation 0.5 rad (29 deg) over three times the
# rig's 0.15 rad, so a column in degrees passes only if it never leaves +-0.5 deg; force 1 MN
# forty times the machine's 25 kN.
PLAUSIBLE = {"displacement": 0.1, "rotation": 0.5, "force": 1.0e6, "moment": 1.0e5}
HINT = {
    "displacement": "millimetres? write 'displacement_axial [mm]' in the header",
    "rotation": "degrees? write 'rotation [deg]' in the header ('rotation [rad]' if it really "
    "is radians)",
    "force": "write the force unit in the header, e.g. 'force_axial [N]'",
    "moment": "N mm? write 'moment [N mm]' in the header",
}


class RecordError(BadInput):
    """A record file or record array is invalid; the message names file, line and value."""


# a column name with its unit in brackets or parentheses, e.g. "displacement [mm]"
NAME_UNIT = re.compile(r"^\s*(.*?)\s*[\[(]\s*([^\])]*?)\s*[\])]\s*$")


@dataclass(frozen=True)
class Columns:
    """The columns of a record of ``len(coords)`` coordinates: ``displacement`` and ``force``
    names in coordinate order, the kind of each (its unit table) and the coordinates' SI
    units."""

    coords: tuple[str, ...]
    displacement: tuple[str, ...]
    force: tuple[str, ...]
    displacement_kinds: tuple[str, ...]
    force_kinds: tuple[str, ...]

    @property
    def names(self) -> tuple[str, ...]:
        """The header in its written order: time, the displacements, the forces."""
        return ("time", *self.displacement, *self.force)

    @property
    def header_text(self) -> str:
        return ",".join(self.names)

    @property
    def kinds(self) -> tuple[str, ...]:
        return ("time", *self.displacement_kinds, *self.force_kinds)

    @property
    def units(self) -> tuple[str, ...]:
        return tuple(SI[k] for k in self.displacement_kinds)

    @property
    def force_units(self) -> tuple[str, ...]:
        return tuple(SI[k] for k in self.force_kinds)


ONE_AXIS = Columns(("deflection",), ("displacement",), ("force",), ("displacement",), ("force",))
THREE_AXES = Columns(
    ("axial", "radial", "rotation"),
    ("displacement_axial", "displacement_radial", "rotation"),
    ("force_axial", "force_radial", "moment"),
    ("displacement", "displacement", "rotation"),
    ("force", "force", "moment"),
)
LAYOUTS = {1: ONE_AXIS, 3: THREE_AXES}


def columns_of(n_coords: int, coords: tuple[str, ...] | None = None) -> Columns:
    """The columns of a record of ``n_coords`` coordinates (1 or 3 in files); ``coords``: a
    record's own coordinate names, for records of other counts made in memory."""
    if n_coords not in LAYOUTS and coords is not None and len(coords) == n_coords:
        return Columns(
            tuple(coords),
            tuple(f"displacement_{c}" for c in coords),
            tuple(f"force_{c}" for c in coords),
            ("displacement",) * n_coords,
            ("force",) * n_coords,
        )
    if n_coords not in LAYOUTS:
        raise RecordError(
            f"no record file format for {n_coords} coordinates; known: "
            + ", ".join(f"{c} ({LAYOUTS[c].header_text})" for c in LAYOUTS)
        )
    return LAYOUTS[n_coords]


def header_names(fields: list[str]) -> list[str]:
    """The column names of a header row, units in brackets dropped."""
    names = []
    for text in fields:
        m = NAME_UNIT.match(text)
        names.append((m.group(1) if m else text).strip())
    return names


def other_separator(fields: list[str]) -> str | None:
    """';' or a tab when a header row read with commas is one field split by it, else None."""
    if len(fields) == 1:
        for sep in (";", "\t"):
            if len(fields[0].split(sep)) > 1:
                return sep
    return None


def header_coordinates(fields: list[str]) -> int:
    """How many coordinates a header row is meant for: the layout whose column count it has or
    whose own names it uses (so a misspelt three-axis header gets that layout's message), else
    1 (the one-axis reader then names the problem)."""
    sep = other_separator(fields)
    fields = fields[0].split(sep) if sep else fields
    names = set(header_names(fields))
    for c, cols in LAYOUTS.items():
        own = set(cols.names) - set(ONE_AXIS.names)
        if c > 1 and (len(fields) == len(cols.names) or own & names):
            return c
    return 1


def column_order(path, fields: list[str], cols: Columns) -> tuple[np.ndarray, np.ndarray]:
    """(column of each of ``cols.names`` in the file, SI factor per name); the names may come
    in any order. ``RecordError`` naming the header problem."""
    names = header_names(fields)
    shown = ",".join(f.strip() for f in fields)
    expected = cols.header_text
    sep = other_separator(fields)
    if sep:
        sep = "tab" if sep == "\t" else repr(sep)
        raise RecordError(
            f"{path} line 1: header '{shown}' looks {sep}-separated; save the file with commas "
            f"between values and a point as the decimal mark ('{expected}')"
        )
    for c, other in LAYOUTS.items():
        if other is not cols and tuple(names) == other.names:
            raise RecordError(
                f"{path} line 1: header '{shown}' is a {'one' if c == 1 else c}-axis record's; "
                f"expected '{expected}' (give one-axis records to a one-axis fit, 3-axis ones to "
                "a 3-axis fit)"
            )
    kind = dict(zip(cols.names, cols.kinds, strict=True))
    for j, name in enumerate(names):
        if name not in kind:
            close = difflib.get_close_matches(name, cols.names, n=1)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise RecordError(
                f"{path} line 1: header '{shown}': column {j + 1} {name!r} is not a planar "
                f"record column{hint}; expected '{expected}', the names in any order, each "
                "once (units in brackets allowed, e.g. 'rotation [deg]')"
            )
        if names.index(name) != j:
            raise RecordError(
                f"{path} line 1: {name} appears twice in the header '{shown}' (columns "
                f"{names.index(name) + 1} and {j + 1}); name each column once"
            )
    missing = [n for n in cols.names if n not in names]
    if missing:
        raise RecordError(
            f"{path} line 1: header '{shown}' lacks {', '.join(missing)}; a planar record has "
            f"the {len(cols.names)} columns {expected}: write an axis the test held still as "
            "columns of zeros"
        )
    order = np.array([names.index(n) for n in cols.names])
    factors = np.ones(len(cols.names))
    for k, name in enumerate(cols.names):
        m = NAME_UNIT.match(fields[order[k]])
        if m:
            unit, table = m.group(2), UNITS[kind[name]]
            if unit not in table:
                raise RecordError(
                    f"{path} line 1: unknown unit {unit!r} for {name}; known: {', '.join(table)}"
                )
            factors[k] = table[unit]
    return order, factors
