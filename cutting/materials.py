"""Workpiece materials: Kienzle's specific cutting force from the table in ``assets/materials.toml``.

kc = kc1.1 * h^(-mc) [N/mm^2] for an uncut chip thickness h [mm]; the main cutting force of a chip of width b
is Fc = kc * b * h. The table's values hold for a rake angle of +6 deg; :func:`rake_factor` corrects for the
cutter's (1.5 % per degree for steel, the handbook's rule).
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

from cutting.errors import InputError, Problem

MATERIALS_PATH = Path(__file__).resolve().parent.parent / "assets" / "materials.toml"

#: Rake angle of the table's reference tool [deg] and the change of kc per degree of rake (steel)
REFERENCE_RAKE_DEG = 6.0
KC_PER_RAKE_DEG = 0.015

#: Thinnest chip [mm] at which kc is evaluated: the power law is fitted on chips of ~0.1..1.5 mm and grows
#: without bound below them; thinner chips take the kc of this thickness (see :meth:`Material.kc`).
H_MIN = 0.01


@dataclass(frozen=True)
class Material:
    """One row of the table: ``kc11`` [N/mm^2] and ``mc`` of Kienzle's law, with the source of the values."""

    key: str
    name: str
    kc11: float
    mc: float
    source: str

    def kc(self, h: float) -> float:
        """Specific cutting force [N/mm^2] at chip thickness ``h`` [mm] (at least :data:`H_MIN`)."""
        return self.kc11 * max(h, H_MIN) ** (-self.mc)


def rake_factor(rake_deg: float) -> float:
    """kc of a tool with rake ``rake_deg`` relative to the table's +6 deg tool (more negative rake cuts harder)."""
    return 1.0 - KC_PER_RAKE_DEG * (rake_deg - REFERENCE_RAKE_DEG)


def load_materials(path: Path = MATERIALS_PATH) -> dict[str, Material]:
    """Every material of the table, checked: positive kc1.1, 0 <= mc < 1, a source for each."""
    with open(path, "rb") as f:
        rows = tomllib.load(f).get("materials", {})
    problems, out = [], {}
    for key, row in rows.items():
        kc11, mc, source = row.get("kc11"), row.get("mc"), row.get("source")
        if not isinstance(kc11, int | float) or kc11 <= 0:
            problems.append(Problem(f"materials.{key}.kc11", kc11, "must be a positive number", "N/mm^2, e.g. 2100"))
        if not isinstance(mc, int | float) or not 0 <= mc < 1:
            problems.append(Problem(f"materials.{key}.mc", mc, "must lie in [0, 1)", "Kienzle's exponent, e.g. 0.26"))
        if not source:
            problems.append(Problem(f"materials.{key}.source", source, "every value needs its source", "cite it"))
        if not problems:
            out[key] = Material(key, str(row.get("name", key)), float(kc11), float(mc), str(source))
    if problems:
        raise InputError(problems, str(path))
    return out


def material(key: str, path: Path = MATERIALS_PATH) -> Material:
    """The material ``key`` (e.g. the job's ``process.material``); an unknown key lists the known ones."""
    table = load_materials(path)
    if key not in table:
        raise InputError(
            Problem(
                "process.material",
                key,
                f"not in the material table {path.name}",
                f"use one of {', '.join(sorted(table))} or add a row with kc11, mc and their source",
            )
        )
    return table[key]
