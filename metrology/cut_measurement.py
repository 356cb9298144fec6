"""Measuring a cut: the exact swept surface for micrometre truth, the mesh beside it, and how far they differ.

The gear of a cut is what its passages removed. Its exact swept surface (the caller hands it over, e.g.
:class:`cutting.skiving.exact_sweep.SweptVolumes`: no chord error) is the workpiece measured first; the manifold
solid the booleans left (gear.stl, cut to an engineering tolerance) is measured the same way, and the two are
compared point by point along the same traces: they may differ by the mesh's sweep error, which the cut reports as
a bound.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from cutting.errors import InputError, UnmeasurableError
from cutting.gear import Gear
from metrology.measure import MeasureOptions, measure_gear
from metrology.sections import MeshData
from metrology.workpiece import Workpiece

UM = 1e3


def measure_cut(
    gear: Gear,
    exact: Workpiece,
    mesh: MeshData | None,
    opt: MeasureOptions,
    sweep_bound: float,
    mesh_name: str = "gear.stl",
    simplification: float = 0.0,
) -> tuple[dict[str, Any], dict[str, Any] | None]:
    """The measurement of ``exact``, the cut's exact swept surface as its caller made it (the document ``skive
    cut``/``run`` write), with a ``mesh`` block comparing it to the measurement of ``mesh`` (None: not measured);
    and that mesh measurement. ``sweep_bound`` [mm]: the mesh's reported sweep error in the passes that shape the
    flanks; ``simplification`` [mm]: how far the file's simplification may have moved its surface besides
    (``cutting/gear_file.py``)."""
    doc = measure_gear(exact, gear, opt, exact.name)
    if mesh is None:
        return doc, None
    try:
        mesh_doc = measure_gear(mesh, gear, opt, mesh_name)
    except (UnmeasurableError, InputError) as exc:  # the file failed, not the gear: the exact measurement stands
        doc["mesh"] = unmeasured_mesh(mesh_name, str(exc), len(mesh.faces))
        return doc, None
    doc["mesh"] = compare(doc, mesh_doc, gear, sweep_bound, mesh_name, len(mesh.faces), simplification)
    return doc, mesh_doc


def unmeasured_mesh(name: str, error: str, triangles: int | None = None) -> dict[str, Any]:
    """The ``mesh`` block of a mesh the measuring machine could not take (not closed, a ball that cannot seat on
    its facets): why, beside the exact measurement, which does not depend on it."""
    return {"name": name, "triangles": triangles, "error": error}


def trace_difference(exact: dict[str, Any], mesh: dict[str, Any]) -> float:
    """Largest |e_exact - e_mesh| [mm] over the profile and helix traces both measurements hold (the same
    nominal probe points: mid-section profiles and the helices of every tooth, both flanks)."""
    worst = 0.0
    for kind in ("profile", "helix"):
        for side, e in exact["_traces"][kind].items():
            d = np.abs(np.asarray(e) - np.asarray(mesh["_traces"][kind][side]))
            if np.isfinite(d).any():
                worst = max(worst, float(np.nanmax(d)))
    return worst


def compare(
    exact: dict[str, Any],
    mesh: dict[str, Any],
    gear: Gear,
    sweep_bound: float,
    name: str,
    triangles: int,
    simplification: float = 0.0,
) -> dict[str, Any]:
    """The mesh's measurement beside the exact one: every ISO 1328 value and the size, the differences (exact -
    mesh, um), and the largest pointwise difference of the traces against the mesh's bound (transverse): its sweep
    error plus its simplification, both along the surface normal."""
    measured = mesh["iso1328"]["measured"]
    ex = exact["iso1328"]["measured"]
    size = {"M_dK_um": (exact["thickness"]["over_balls"]["M_dK_mm"] - mesh["thickness"]["over_balls"]["M_dK_mm"]) * UM}
    if exact["thickness"]["span"].get("W_k_mm") is not None:
        size["W_k_um"] = (exact["thickness"]["span"]["W_k_mm"] - mesh["thickness"]["span"]["W_k_mm"]) * UM
    worst = trace_difference(exact, mesh) * UM
    bound = (sweep_bound + simplification) * UM / math.cos(gear.base_helix_angle)  # the bound holds along the normal
    return {
        "name": name,
        "triangles": triangles,
        "sweep_bound_um": sweep_bound * UM,
        "simplification_um": simplification * UM,
        "measured": measured,
        "class": (mesh["iso1328"].get("class") or {}).get("overall"),
        "difference_um": {k: ex[k] - measured[k] for k in ex},
        "size_difference_um": size,
        "trace_difference_um": worst,
        "trace_bound_um": bound,
        "within_bound": bool(worst <= bound + 0.05),
    }
