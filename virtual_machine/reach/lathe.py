"""Whether a thread or turning job is within the lathe's reach (machine_models/thread_lathe.py:
``spindle_speed_limit``, ``swing_diameter``, ``carriage_travel``): as the lathe's CNC refuses a spindle speed above
its limit and a stroke beyond its travel, and a workpiece over its swing does not fit, skive refuses such a job
before the stroke, naming the limit, what the job needs and what would hold it."""

from __future__ import annotations

import math

from cutting.errors import MachineLimitError, Problem
from machine_models.parameters import RPM
from machine_models.thread_lathe import ThreadLatheParams, ThreadLayout
from virtual_machine.job import Job, TurningJob
from virtual_machine.output.formatting import three_figures
from virtual_machine.reach.limits import Limit, refuse

#: the servo tick's physics sub-steps (virtual_machine/runtime/lathe_run.py: simulate_thread's default)
SERVO_SUBSTEPS = 2
#: the fewest servo ticks per cycle of a feed vibration
MIN_SAMPLES = 20


def check_lathe_reach(job: Job, params: ThreadLatheParams, lay: ThreadLayout, t_end: float) -> None:
    """Refuse (MachineLimitError) a stroke of ``t_end`` [s] laid out by ``lay`` that needs more than the lathe
    ``params`` gives: its spindle speed, its workpiece diameter, the carriage's travel over the stroke, a feed
    vibration its servo can sample."""
    section = "turning" if job.kind == "turning" else "thread"
    feed = lay.lead * lay.spindle_speed / (2 * math.pi)  # m/s of the carriage
    travel = max(lay.length + 2 * lay.approach, lay.approach + feed * t_end)
    limits = (
        Limit(
            "spindle_speed_limit",
            lay.spindle_speed,
            params.spindle_speed_limit,
            "rad/s",
            f"the spindle B1 turns at {three_figures(lay.spindle_speed / RPM)} rpm, above its top speed "
            f"{three_figures(params.spindle_speed_limit / RPM)} rpm",
            "a lower process.cutting_speed",  # required of thread and turning jobs; it sets the spindle speed
        ),
        Limit(
            "swing_diameter",
            lay.diameter,
            params.swing_diameter,
            "m",
            f"the workpiece's {three_figures(lay.diameter * 1e3)} mm diameter exceeds its swing "
            f"{three_figures(params.swing_diameter * 1e3)} mm",
            f"a smaller {section}.diameter",
        ),
        Limit(
            "carriage_travel",
            travel,
            params.carriage_travel,
            "m",
            f"the stroke (the {section}'s length, the run-up's travel and the clearance) of "
            f"{three_figures(travel * 1e3)} mm exceeds the carriage's travel "
            f"{three_figures(params.carriage_travel * 1e3)} mm",
            f"a shorter {section}.length" + (" or fewer process.revolutions" if section == "turning" else ""),
        ),
    )
    vibration = job.vibration if isinstance(job, TurningJob) else None  # a thread has no feed vibration
    if vibration is not None:
        # the feed servo follows tens of Hz (docs/face-contours-and-turning.md); a command sampled fewer than
        # MIN_SAMPLES times per cycle by the servo tick is no vibration at all
        tick = 1.0 / (params.timestep * SERVO_SUBSTEPS)
        frequency = vibration.cycles_per_rev * lay.spindle_speed / (2 * math.pi)
        most = tick / MIN_SAMPLES / frequency * vibration.cycles_per_rev
        if frequency > tick / MIN_SAMPLES:
            raise MachineLimitError(
                Problem(
                    "vibration.cycles_per_rev",
                    vibration.cycles_per_rev,
                    f"the vibration at {three_figures(frequency)} Hz is sampled fewer than {MIN_SAMPLES} times a "
                    f"cycle by the lathe's {three_figures(tick)} Hz servo (its feed axis follows tens of Hz)",
                    f"use fewer vibration.cycles_per_rev (at most {most:.3g} here) or a lower process.cutting_speed",
                ),
                job.source,
            )
    refuse("lathe", limits, source=job.source)
