"""A measured gear as `skive diagnose` reads it: skive's measurement.json (its ``traces`` and ``pitch`` blocks), or a
CSV of profile and helix traces and single pitch deviations per tooth and flank (its format: docs/diagnose.md).

Both give the same :class:`MeasuredGear`: the gear's identity (teeth, normal module, helix angle: what the job's gear
is checked against), and per flank the profile traces over roll length, the helix traces over the face and the
single pitch deviations, each tooth's by its number (1..z), in micrometres (+: material on the flank).
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from cutting.errors import InputError, Problem

SIDES = ("left", "right")
KINDS = ("profile", "helix", "pitch")
#: the CSV's header lines: "# key = value" (the gear's identity), then the column row
CSV_GEAR_KEYS = ("teeth", "normal_module_mm", "helix_angle_deg")
CSV_COLUMNS = ("kind", "flank", "tooth", "position_mm", "deviation_um")


@dataclass
class Trace:
    """One measured line: positions [mm] (roll length for a profile, z from mid face for a helix) and deviations
    [um], ascending in position."""

    position: np.ndarray
    deviation: np.ndarray


@dataclass
class MeasuredGear:
    """A measured gear: where it came from, its identity, and per (kind, flank) each tooth's trace (profile,
    helix) or single pitch deviation f_pi [um] (pitch), keyed by the tooth's number."""

    source: str
    teeth: int
    normal_module: float
    helix_angle_deg: float
    traces: dict[tuple[str, str], dict[int, Trace]] = field(default_factory=dict)
    pitch: dict[str, dict[int, float]] = field(default_factory=dict)

    def range(self, kind: str) -> tuple[float, float] | None:
        """The positions the ``kind`` traces cover (the narrowest tooth's), None without any."""
        spans = [(t.position[0], t.position[-1]) for side in SIDES for t in self.traces.get((kind, side), {}).values()]
        if not spans:
            return None
        return max(s[0] for s in spans), min(s[1] for s in spans)


def read_measured(path: Path) -> MeasuredGear:
    """skive's measurement.json (``.json``) or the documented CSV (``.csv``); a clear error for anything else."""
    if not path.is_file():
        raise InputError(Problem(str(path), None, "no such file", "give a measurement.json or a CSV of traces"))
    if path.suffix.lower() == ".json":
        try:
            doc = json.loads(path.read_text())
        except json.JSONDecodeError as exc:
            raise InputError(Problem(str(path), None, f"not JSON ({exc})", "give skive's measurement.json")) from None
        return from_document(doc, str(path))
    if path.suffix.lower() == ".csv":
        return read_csv(path)
    fix = "give measurement.json or a .csv (docs/diagnose.md)"
    raise InputError(Problem(str(path), path.suffix, "not a measurement skive reads", fix))


def from_document(doc: dict[str, Any], source: str) -> MeasuredGear:
    """A measurement document (measurement.json, or a study case's) as a measured gear."""
    gear, traces = doc.get("gear"), doc.get("traces")
    if not isinstance(gear, dict) or not isinstance(traces, dict):
        raise InputError(
            Problem(source, None, "holds no gear and traces blocks",
                    "give the measurement.json of a skive cut, run or measure of this version (it keeps the traces)")
        )  # fmt: skip
    z = int(gear["teeth"])
    out = MeasuredGear(source, z, float(gear["normal_module_mm"]), float(gear["helix_angle_deg"]))
    # skive numbers the teeth from the one its datum found first; the physical tooth (the nominal index) is what
    # makes two of its measurements comparable tooth by tooth, and a once-per-turn source's phase the same
    first = int(((doc.get("evaluation") or {}).get("datum") or {}).get("tooth_1_index", 0))

    def number(k: int) -> int:
        return (k + first) % z + 1

    for kind, where in (("profile", "L_mm"), ("helix", "z_mm")):
        block = traces.get(kind, {})
        x = np.asarray(block.get(where, []), dtype=float)
        for side in SIDES:
            rows = block.get(side, [])
            out.traces[(kind, side)] = {
                number(k): _trace(x, np.array([np.nan if v is None else v for v in row], dtype=float))
                for k, row in enumerate(rows)
            }
    for side in SIDES:
        f_pi = (doc.get("pitch", {}).get(side) or {}).get("f_pi") or []
        out.pitch[side] = {number(k): float(v) for k, v in enumerate(f_pi) if v is not None and math.isfinite(v)}
    return out


def _trace(x: np.ndarray, y: np.ndarray) -> Trace:
    keep = np.isfinite(x) & np.isfinite(y)
    order = np.argsort(x[keep])
    return Trace(x[keep][order], y[keep][order])


def read_csv(path: Path) -> MeasuredGear:
    """The documented CSV (docs/diagnose.md): "# key = value" lines for the gear's identity, the columns
    kind,flank,tooth,position_mm,deviation_um, one row per point (a pitch row has no position)."""
    head: dict[str, str] = {}
    rows: list[list[str]] = []
    with path.open(newline="") as fh:
        for line in fh:
            if line.startswith("#"):
                key, sep, value = line[1:].partition("=")
                if sep:
                    head[key.strip()] = value.strip()
                continue
            if line.strip():
                rows.append(line)
    problems = [
        Problem(f"{path}: # {k}", None, "missing", f"add a line '# {k} = <value>' before the columns")
        for k in CSV_GEAR_KEYS
        if k not in head
    ]
    if problems:
        raise InputError(problems)
    try:
        out = MeasuredGear(
            str(path), int(head["teeth"]), float(head["normal_module_mm"]), float(head["helix_angle_deg"])
        )
    except ValueError as exc:
        why = f"a gear line is not a number ({exc})"
        raise InputError(Problem(str(path), None, why, "see docs/diagnose.md")) from None
    reader = csv.reader(rows)
    header = next(reader, None)
    if header is None or tuple(c.strip() for c in header) != CSV_COLUMNS:
        raise InputError(Problem(str(path), header, "not the expected columns", "the row: " + ",".join(CSV_COLUMNS)))
    points: dict[tuple[str, str, int], list[tuple[float, float]]] = {}
    for n, row in enumerate(reader, start=2):
        where = f"{path}: row {n}"
        if len(row) != len(CSV_COLUMNS):
            raise InputError(Problem(where, row, f"{len(row)} cells", f"{len(CSV_COLUMNS)}: " + ",".join(CSV_COLUMNS)))
        kind, side = row[0].strip(), row[1].strip()
        if kind not in KINDS or side not in SIDES:
            raise InputError(Problem(where, row, "unknown kind or flank", f"kinds {KINDS}, flanks {SIDES}"))
        try:
            tooth = int(row[2])
            deviation = float(row[4])
            position = float(row[3]) if kind != "pitch" else math.nan
        except ValueError:
            fix = "the tooth an integer, the position and the deviation numbers"
            raise InputError(Problem(where, row, "not a number", fix)) from None
        if not 1 <= tooth <= out.teeth:
            raise InputError(Problem(where, tooth, f"not a tooth of a {out.teeth}-tooth gear", "number teeth 1..z"))
        if kind == "pitch":
            out.pitch.setdefault(side, {})[tooth] = deviation
        else:
            points.setdefault((kind, side, tooth), []).append((position, deviation))
    for (kind, side, tooth), pts in points.items():
        a = np.array(pts, dtype=float)
        out.traces.setdefault((kind, side), {})[tooth] = _trace(a[:, 0], a[:, 1])
    if not out.traces and not out.pitch:
        raise InputError(Problem(str(path), None, "holds no measured rows", "see docs/diagnose.md for the format"))
    return out


def write_csv(measured: MeasuredGear, path: Path) -> Path:
    """A measured gear as the documented CSV (what a gear measuring machine's export is converted to)."""
    with path.open("w", newline="") as fh:
        fh.write("# skive measured gear (docs/diagnose.md)\n")
        fh.write(f"# teeth = {measured.teeth}\n# normal_module_mm = {measured.normal_module!r}\n")
        fh.write(f"# helix_angle_deg = {measured.helix_angle_deg!r}\n")
        w = csv.writer(fh)
        w.writerow(CSV_COLUMNS)
        for (kind, side), teeth in measured.traces.items():
            for tooth, tr in sorted(teeth.items()):
                points = zip(tr.position, tr.deviation, strict=True)
                w.writerows([kind, side, tooth, repr(float(x)), repr(float(y))] for x, y in points)
        for side, values in measured.pitch.items():
            w.writerows(["pitch", side, tooth, "", repr(v)] for tooth, v in sorted(values.items()))
    return path
