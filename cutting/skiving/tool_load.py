"""The load on each cutter tooth, pass by pass, from the chips the cut really took (the dexel removal's): its largest
uncut chip thickness, its cutting path in the material and its chip energy. A cutter's runout and pitch deviations
load its teeth unequally; tool life follows the most loaded one.

The cutting path of an engagement is the cutting speed at the pitch point times the time the tooth spends in the
blank's envelope; the chip energy is Kienzle's kc(h) times the chip's volume at its mean thickness h, with the
handbook's rake factor at 0 deg: a per-tooth figure to compare the teeth by. The run's own chip energy, from the
oblique model at each element's working angles (:mod:`cutting.forces`), is measurement.json's
``run.forces.chip_energy_J`` (within ~15 % of this on the shipped jobs, tests/test_cosim.py).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence

from cutting.materials import Material, rake_factor
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.passages import Chip

#: the rake angle of this per-tooth estimate [deg] (the run's force model takes each element's working rake)
FORCE_MODEL_RAKE = 0.0


def tool_load(chips: Sequence[Chip], setup: SkivingSetup, material: Material) -> list[dict]:
    """Per pass: each cutter tooth's engagements, largest chip thickness [mm], cutting path [m] and chip energy
    [J], and the spread of the largest chip over the teeth (most loaded over least). Chips without a thickness
    (the manifold removal's) give none."""
    speed = setup.cutting_speed / 60.0  # m/s at the pitch point
    factor = rake_factor(FORCE_MODEL_RAKE)
    teeth: dict[int, dict[int, dict]] = defaultdict(dict)
    for c in chips:
        if c.volume <= 0 or c.thickness_max is None:
            continue
        row = teeth[c.pass_index].setdefault(
            c.cutter_tooth, {"tooth": c.cutter_tooth, "engagements": 0, "h": 0.0, "path": 0.0, "energy": 0.0}
        )
        row["engagements"] += 1
        row["h"] = max(row["h"], c.thickness_max)
        row["path"] += speed * max(c.end - c.start, 0.0)
        row["energy"] += material.kc(c.thickness_mean or c.thickness_max) * factor * c.volume * 1e-3
    out = []
    for k in sorted(teeth):
        rows = [teeth[k][z] for z in sorted(teeth[k])]
        hs = [r["h"] for r in rows]
        out.append(
            {
                "pass": k + 1,
                "chip_thickness_max_mm": max(hs),
                "chip_thickness_spread": max(hs) / min(hs) if min(hs) > 0 else None,
                "most_loaded_tooth": rows[hs.index(max(hs))]["tooth"],
                "teeth": [
                    {
                        "tooth": r["tooth"],
                        "engagements": r["engagements"],
                        "chip_thickness_max_mm": r["h"],
                        "cut_length_m": r["path"],
                        "chip_energy_J": r["energy"],
                    }
                    for r in rows
                ],
            }
        )
    return out
