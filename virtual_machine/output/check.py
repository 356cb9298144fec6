"""skive check: is the gear a job makes within an ISO 1328-1 class? The verdict and the parameters that fail."""

from __future__ import annotations

import math
from typing import Any

from cutting.gear import Gear
from metrology import tolerances as iso


def class_verdict(doc: dict[str, Any], gear: Gear, max_class: int) -> dict[str, Any]:
    """The verdict on a measurement document: ``pass``, the gear's class, and per failing parameter its value
    [um], its class (None: worse than class 11) and what class ``max_class`` allows [um]. A gear ISO 1328-1
    cannot grade (e.g. b < 4 mm) fails with that reason."""
    max_class = iso.check_class(max_class)
    block = doc["iso1328"]
    out: dict[str, Any] = {"max_class": max_class, "class": None, "failures": []}
    if block.get("error"):
        out["failures"].append({"parameter": "ISO 1328-1", "reason": block["error"]})
        out["pass"] = False
        return out
    classes, measured = block["class"], block["measured"]
    allowed = iso.tolerances(max_class, gear.teeth, gear.mn, gear.face_width, math.degrees(gear.beta))
    for name, cls in classes.items():
        if name == "overall" or (cls is not None and cls <= max_class):
            continue
        out["failures"].append(
            {"parameter": name, "measured_um": measured[name], "class": cls, "allowed_um": allowed[name]}
        )
    out["class"] = classes.get("overall")
    out["pass"] = not out["failures"]
    return out


def format_verdict(verdict: dict[str, Any], source: str) -> str:
    n = verdict["max_class"]
    if verdict["pass"]:
        return f"PASS  {source}: ISO 1328-1 class {verdict['class']} (required: class {n} or better)"
    lines = [f"FAIL  {source}: required ISO 1328-1 class {n} or better; the gear is class {verdict['class']}"]
    for f in verdict["failures"]:
        if "reason" in f:
            lines.append(f"  {f['parameter']}: {f['reason']}")
        else:
            cls = f"class {f['class']}" if f["class"] is not None else "worse than class 11"
            lines.append(
                f"  {f['parameter']}: {f['measured_um']:.2f} um is {cls}; class {n} allows {f['allowed_um']:g} um"
            )
    return "\n".join(lines)
