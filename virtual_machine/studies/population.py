"""`skive check JOB --max-class N --confidence C`: the verdict for a population of machines and cutters, not one.

A Monte-Carlo study of the job (virtual_machine/studies/spec.py) draws ``samples`` machines from a size's geometric
tolerances (machine_models/geometry_tolerances.py) and, if asked, cutters from a tolerance class
(cutting/skiving/cutter_classes.py); each case runs as `skive run` (or `skive cut`) does. The population makes class N
or better with the share P of its cases (a case that fails to run counts against it); the verdict passes when P >= C.
Beside P the verdict gives its one-sided 95 % lower bound (Wilson's score interval: how far P may lie above the
population's share for so few samples), the class the share C of the cases reaches, the cases' class counts and the
source that limits the class (the error budget's largest variance share).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

from virtual_machine.studies.pipeline import StudyOutcome


def wilson_lower(p: float, n: int, z: float = 1.6449) -> float:
    """The one-sided lower bound of a share ``p`` seen in ``n`` samples (Wilson's score interval; z 1.645: 95 %)."""
    if n <= 0:
        return 0.0
    centre = p + z * z / (2 * n)
    spread = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return max(0.0, (centre - spread) / (1 + z * z / n))


def study_text(job: Path, samples: int, seed: int, machine: str, cutter_class: str | None, stage: str) -> str:
    """The study file of a population check."""
    import tomli_w

    study = {"base": str(job.resolve()), "method": "monte-carlo", "samples": samples, "seed": seed,
             "machine_tolerances": machine, "stage": stage}  # fmt: skip
    if cutter_class:
        study["cutter_class"] = cutter_class
    return tomli_w.dumps(study)


def population_verdict(outcome: StudyOutcome, max_class: int, confidence: float) -> dict[str, Any]:
    """The verdict on a population study's outcome (its cases graded at ``max_class``, the share ``confidence``)."""
    budget = outcome.budget
    counts = {int(c): int(k) for c, k in budget.class_counts.items()}
    total = outcome.total_cases
    ok = sum(counts.values())
    meets = sum(k for c, k in counts.items() if c <= max_class)
    p = meets / total if total else 0.0
    reached = None
    running = 0
    for c in sorted(counts):
        running += counts[c]
        if running >= confidence * total:
            reached = c
            break
    limiting = None
    worst = budget.limiting()
    if worst is not None and worst[1] is not None:
        param, part = worst
        limiting = {"parameter": param.name, "source": part.label, "key": part.key, "share": part.share}
    verdict: dict[str, Any] = {
        "max_class": max_class,
        "confidence": confidence,
        "class": reached if reached is not None and reached <= 11 else None,
        "pass": p >= confidence,
        "failures": [],
        "population": {
            "samples": total,
            "cases_failed": total - ok,
            "p_at_most": p,
            "p_lower_95": wilson_lower(p, total),
            "class_counts": {str(c): k for c, k in sorted(counts.items())},
            "limiting": limiting,
        },
    }
    if not verdict["pass"]:
        why = (f"P(class <= {max_class}) = {p:.2f} over {total} machines and cutters (95 % lower bound "
               f"{verdict['population']['p_lower_95']:.2f}), below the confidence {confidence:g}")  # fmt: skip
        if limiting:
            why += f"; limiting: {limiting['parameter']}, largest share {limiting['source']}"
        verdict["failures"].append({"parameter": "population", "reason": why})
    return verdict


def format_population(verdict: dict[str, Any], source: str) -> str:
    pop = verdict["population"]
    n, c = verdict["max_class"], verdict["confidence"]
    head = "PASS" if verdict["pass"] else "FAIL"
    reached = f"class {verdict['class']}" if verdict["class"] is not None else "worse than class 11"
    share = f"P(class <= {n}) = {pop['p_at_most']:.2f} over {pop['samples']} machines and cutters"
    bound = f"95 % lower bound {pop['p_lower_95']:.2f}; required {c:g}"
    lines = [f"{head}  {source}: {share} ({bound}); {c:.0%} of them reach {reached}"]
    counts = ", ".join(f"{'>11' if int(k) > 11 else k}: {v}" for k, v in pop["class_counts"].items())
    lines.append(f"  the cases' classes: {counts}" + (f"; {pop['cases_failed']} failed" if pop["cases_failed"] else ""))
    if pop["limiting"]:
        lim = pop["limiting"]
        share = f" ({lim['share']:.0%} of its variance)" if lim["share"] is not None else ""
        lines.append(f"  limiting: {lim['parameter']}; its largest source {lim['source']}{share}")
    return "\n".join(lines)
