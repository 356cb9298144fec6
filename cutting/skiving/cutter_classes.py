"""The cutter's tolerance classes (AA, A, B): how far a cutter of each class may deviate, per module (issue 43).

Skiving and shaper cutters are bought by the accuracy classes of the gear-cutting tool standards; the figures here
are DIN 3968's for single-thread hobs (the table a tool maker prints: Tungaloy's gear-cutting catalogue, "Tolerances /
DIN 3968, Accuracy requirements for single thread hobs", pp. 45-46, docs.steelcam.org/tungaloy/
katalog-tungaloy-zubofrezerovanie-page45 and -page46), taken for the skiving cutter's like quantities, since the
shaper-cutter table (DIN 1829) was not at hand: the classes' steps are the same series. Each is a tolerance [um] on:

    radial_runout   the radial runout of the teeth's tips (frk)          -> CutterErrors.radial_runout (TIR)
    axial_runout    the axial runout of the hub face (fpa)                -> CutterErrors.axial_runout
    pitch           the adjacent spacing of the cutting faces (+-, ftN)   -> CutterErrors.pitch (single deviations)
    profile         the tooth profile deviation (FfS)                     -> CutterErrors.profile_slope / _form

A study draws cutters of a class from them (cutting/skiving/tooling.py: random_pitch for the pitch).
"""

from __future__ import annotations

import bisect

#: the table's module ranges: (lo, hi] [mm]
MODULE_EDGES = (0.63, 1.0, 1.6, 2.5, 4.0, 6.3, 10.0, 16.0, 25.0, 40.0)
CLASSES = ("AA", "A", "B")
#: the table prints one series for the tips' radial runout (frk) and the cutting faces' adjacent spacing (ftN)
_TIPS_AND_FACES = {
    "AA": (10, 10, 12, 16, 20, 25, 32, 40, 50),
    "A": (12, 16, 20, 25, 32, 40, 50, 63, 80),
    "B": (25, 32, 40, 50, 63, 80, 100, 125, 160),
}
#: per quantity and class, the tolerance [um] in each module range (DIN 3968, via the catalogue cited above)
TABLE: dict[str, dict[str, tuple[int, ...]]] = {
    "radial_runout": _TIPS_AND_FACES,
    "axial_runout": {
        "AA": (3, 3, 3, 3, 3, 4, 5, 5, 6),
        "A": (3, 3, 3, 5, 5, 8, 8, 10, 10),
        "B": (4, 4, 4, 6, 6, 10, 10, 12, 12),
    },
    "pitch": _TIPS_AND_FACES,
    "profile": {
        "AA": (6, 6, 6, 8, 10, 12, 14, 18, 22),
        "A": (10, 11, 12, 14, 16, 20, 25, 32, 40),
        "B": (20, 22, 25, 28, 32, 40, 50, 63, 80),
    },
}


def cutter_tolerances(cutter_class: str, module: float) -> dict[str, float]:
    """The tolerances [mm] of a cutter of ``cutter_class`` ("AA", "A" or "B") for ``module`` [mm]; ValueError naming
    what is wrong for another class or a module outside the table (0.63-40 mm)."""
    if cutter_class not in CLASSES:
        raise ValueError(f"cutter class {cutter_class!r}: use one of {', '.join(CLASSES)}")
    if not MODULE_EDGES[0] < module <= MODULE_EDGES[-1]:
        raise ValueError(f"module {module:g} mm: the cutter classes' table covers {MODULE_EDGES[0]:g}-40 mm")
    k = bisect.bisect_left(MODULE_EDGES, module) - 1  # (lo, hi] ranges
    return {name: row[cutter_class][k] * 1e-3 for name, row in TABLE.items()}
