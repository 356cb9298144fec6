"""Whether a form-milling job is within its machine's reach (machine_models/form_mill.py:
``workpiece_diameter_limit``, ``z_travel``, ``mill_diameter_limit``) and whether its mill fits
the space at all (``mill.clearance``): checked before the plan, so that `skive cut` and `skive run` refuse such a job
with what is wrong and what would hold it, instead of planning a path of that size."""

from __future__ import annotations

import math

from cutting.errors import Problem
from virtual_machine.job import Job
from virtual_machine.output.formatting import three_figures
from virtual_machine.reach.limits import Limit, refuse
from virtual_machine.setting.machine_layout import workpiece_diameter


def check_form_reach(job: Job, params) -> None:
    """Refuse (MachineLimitError) a form-milling job beyond the machine ``params`` (FormMillParams) or whose clearance
    leaves no mill in the space."""
    g, m = job.gear, job.mill
    problems = []
    space = math.pi * g.mn / math.cos(g.helix_angle) / 2  # the space's width on the reference circle [mm]
    if m["clearance"] >= space:
        problems.append(
            Problem(
                "mill.clearance",
                m["clearance"],
                f"a clearance of at least the space's width on the reference circle (pi m_t / 2 = {space:.3f} mm) "
                "leaves no mill in the space",
                f"give mill.clearance well below {space:.3f} mm (a few tenths of a millimetre is usual)",
            )
        )
    d = m.get("diameter") or 0.0  # the finger's is fitted to the space (its largest diameter)
    stroke = g.face_width / math.cos(g.helix_angle) + d  # the face and the mill's reach past both ends [mm]
    limits = (
        Limit(
            "workpiece_diameter_limit",
            workpiece_diameter(g) * 1e-3,
            params.workpiece_diameter_limit,
            "m",
            f"the workpiece's {three_figures(workpiece_diameter(g))} mm diameter exceeds what the table takes, "
            f"{three_figures(params.workpiece_diameter_limit * 1e3)} mm",
            "a smaller gear",
        ),
        Limit(
            "z_travel",
            stroke * 1e-3,
            params.z_travel,
            "m",
            f"a pass's stroke (the face and the mill's reach past its ends) of about {three_figures(stroke)} mm "
            f"exceeds the Z slide's travel {three_figures(params.z_travel * 1e3)} mm",
            "a narrower gear.face_width or a smaller mill",
        ),
        Limit(
            "mill_diameter_limit",
            d * 1e-3,
            params.mill_diameter_limit,
            "m",
            f"a mill of {three_figures(d)} mm exceeds what the spindle carries, "
            f"{three_figures(params.mill_diameter_limit * 1e3)} mm",
            "a smaller mill.diameter",
        ),
    )
    refuse("form-milling machine", limits, problems, job.source)
