"""Thread cutting on the lathe (seed 001's thread group): the process of a "thread" job.

- setup: the setting sheet of the thread group (:mod:`virtual_machine.setting.sheet`);
- simulate: one threading stroke on the lathe (:mod:`virtual_machine.runtime.lathe_run`): its lead error;
- run: the same stroke, and the lead of the thread the carriage's path cuts measured as a thread measuring machine
  reports it (its deviation along the thread: mean, peak to peak, drift) in measurement.json.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import ClassVar

from virtual_machine.job import Job
from virtual_machine.output.json_file import write_json
from virtual_machine.output.progress import Reporter
from virtual_machine.processes.base import Process, Product, run_identity, written
from virtual_machine.processes.options import MachineSimulateOptions, RecordedOptions, SheetOptions, StageOptions
from virtual_machine.processes.sheets import sheet_product


class ThreadCutting(Process):
    kind = "thread"
    title = "thread cutting"
    stages: ClassVar[dict[str, type[StageOptions]]] = {
        "setup": SheetOptions,
        "simulate": MachineSimulateOptions,
        "run": RecordedOptions,
    }
    hints: ClassVar[dict[str, str]] = {"cut": "use `skive run`: the thread is cut by the lathe's simulated stroke"}

    def setup(self, job: Job, options: SheetOptions | None = None) -> Product:
        # the thread group's sheet comes from the same setting sheets as skiving's
        return sheet_product(job, self._options("setup", options).structure)

    def simulate(
        self, job: Job, out: Path, options: MachineSimulateOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        o = self._options("simulate", options)
        job = o.machine_of(job)
        return _stroke(job, out, o.duration, measurement=False, rrd=o.rrd)

    def run(
        self, job: Job, out: Path, options: RecordedOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        return _stroke(job, out, None, measurement=True, rrd=self._options("run", options).rrd)


def _stroke(job: Job, out: Path, duration: float | None, measurement: bool, rrd: Path | None = None) -> Product:
    """One threading stroke on the lathe, its lead error (simulation.json, thread_motion.npz, scene.xml); with
    ``measurement`` also measurement.json: the lead of the thread the carriage's path cuts; with ``rrd`` the
    stroke's signals as a Rerun recording."""
    import numpy as np

    from machine_models.parameters import override
    from machine_models.thread_lathe import ThreadLatheParams, build_thread_lathe_spec
    from virtual_machine.job import flatten_model
    from virtual_machine.output import motion_io
    from virtual_machine.runtime.lathe_run import simulate_thread
    from virtual_machine.setting.thread_layout import thread_layout

    params = override(ThreadLatheParams(), flatten_model(job.machine.model))  # the job's own lathe
    t0 = time.perf_counter()
    rec = simulate_thread(job, params, duration=duration)
    wall = time.perf_counter() - t0
    out.mkdir(parents=True, exist_ok=True)
    motion_io.write_model(build_thread_lathe_spec(thread_layout(job, params), params).to_xml(), out)
    np.savez_compressed(
        out / "thread_motion.npz",
        t=rec.t,
        b1=rec.b1,
        p2=rec.p2,
        tv=rec.tv,
        torque=rec.torque,
        lead_error_um=rec.lead_error_um,
        on_thread=rec.on_thread,
    )
    drift, travel = rec.drift() if rec.on_thread.sum() > 2 else (0.0, 0.0)
    doc = {
        "job": job.source,
        "form": rec.form,
        "lead_mm": rec.lead,
        "machine_seconds": float(rec.t[-1]),
        "wall_seconds": wall,
        "lead_error_on_thread": rec.stats(),
        "lead_drift_um": drift,
        "travel_mm": travel,
    }
    write_json(out / "simulation.json", doc)
    if rrd is not None:
        from virtual_machine.output.recorder import APP_ID, Recorder

        with Recorder(rrd, APP_ID, **run_identity(job)) as r:
            r.series("lathe/spindle", rec.t, rec.b1, ["B1 [rad]"])
            r.series("lathe/carriage", rec.t, rec.p2, ["P2 [mm]"])
            r.series("lathe/lead_error", rec.t, rec.lead_error_um, ["lead error [um]"])
            r.series("lathe/torque", rec.t, rec.torque, ["M1 [N m]", "M2 [N m]"])
    data = doc
    if measurement:
        lead = {"lead_mm": rec.lead, "form": rec.form, **(doc["lead_error_on_thread"] or {}), "drift_um": drift}
        data = {"thread": lead, "run": doc}
        write_json(out / "measurement.json", data)
    s = doc["lead_error_on_thread"]
    lines = [
        f"THREAD SIMULATION  {job.source}  ({rec.form}), lead {rec.lead} mm",
        f"{doc['machine_seconds']:.2f} s of machine time in {wall:.1f} s wall",
    ]
    if s:
        lines.append(
            f"lead error on the thread: mean {s['mean_um']:.3f} um, p-p {s['peak_to_peak_um']:.3f} um, "
            f"drift {drift:+.3f} um over {abs(travel):.1f} mm"
        )
    names = ["thread_motion.npz", "simulation.json", *(["measurement.json"] if measurement else []), "scene.xml"]
    lines.append("written: " + ", ".join([*(str(out / f) for f in names), *([str(rrd)] if rrd else [])]))
    files = written(out, "thread_motion.npz", "simulation.json", "measurement.json", "*.xml") + ([rrd] if rrd else [])
    # the CLI's --json of `skive simulate` prints the stroke's summary, as before
    return Product("run" if measurement else "simulate", data if measurement else doc, "\n".join(lines), files, out)
