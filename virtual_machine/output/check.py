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


def junit_xml(results: list[tuple[str, dict[str, Any] | None, float, str | None]], max_class: int) -> str:
    """The verdicts as a JUnit XML report (the format CI dashboards read): one test case per job, named by its path;
    a failure per parameter over the class (parameter, measured value, tolerance, class) or the reason the gear
    failed (cannot be graded or measured); the model's scope as the case's output. ``results``: (job, verdict with
    its ``model_scope`` or None, wall seconds, error text or None) per job."""
    import xml.etree.ElementTree as ET

    from virtual_machine.output.model_scope import scope_lines

    failed = sum(1 for _, v, _, err in results if err is not None or not (v or {}).get("pass"))
    suite = ET.Element(
        "testsuite",
        name=f"skive check --max-class {max_class}",
        tests=str(len(results)),
        failures=str(failed),
        errors="0",
        time=f"{sum(r[2] for r in results):.3f}",
    )
    for job, verdict, seconds, error in results:
        case = ET.SubElement(suite, "testcase", classname="skive.check", name=job, time=f"{seconds:.3f}")
        if error is not None:
            ET.SubElement(case, "failure", message=error, type="UnmeasurableGear").text = error
            continue
        for f in verdict["failures"]:
            if "reason" in f:
                text = f"{f['parameter']}: {f['reason']}"
            else:
                cls = f"class {f['class']}" if f["class"] is not None else "worse than class 11"
                text = (
                    f"{f['parameter']}: measured {f['measured_um']:.2f} um, tolerance {f['allowed_um']:g} um "
                    f"(class {max_class}); the gear's {f['parameter']} is {cls}"
                )
            ET.SubElement(case, "failure", message=text, type=f"ISO1328-{f['parameter']}").text = text
        scope = verdict.get("model_scope")
        if "population" in verdict:  # `--confidence`: a population's verdict
            from virtual_machine.studies.population import format_population

            out = [format_population(verdict, job)]
        else:
            out = [format_verdict(verdict, job)] + (scope_lines(scope) if scope else [])
        ET.SubElement(case, "system-out").text = "\n".join(out)
    ET.indent(suite)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(suite, encoding="unicode") + "\n"
