"""Face tooth contours by continuous indexing (seed 004): the process of a "face_contour" job.

- setup: the setting sheet (setting angle lambda, |V| along the slot, the flat-bottom e, the straight-slot ratio);
- simulate: the face-contour machine (MuJoCo, its electronic gearbox) cuts the slots: its synchronisation;
- cut: the ideal kinematics cut the first ``process.slots_cut`` slots, measured exactly and on the solid;
- run: the machine cuts them; the slots are cut and measured from the motion it recorded
(:mod:`virtual_machine.processes.face_contour.stages`).
"""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

from metrology.charts import finite
from virtual_machine.job import Job
from virtual_machine.output.json_file import write_json
from virtual_machine.output.progress import Reporter
from virtual_machine.processes.base import Process, Product, reporter_or_default, written
from virtual_machine.processes.options import RecordedOptions, StageOptions

FILES = ("coupling.stl", "measurement.json", "report.html")


class FaceContour(Process):
    kind = "face_contour"
    title = "face contour (continuous indexing)"
    stages: ClassVar[dict[str, type[StageOptions]]] = {
        "setup": StageOptions,
        "simulate": StageOptions,
        "cut": StageOptions,
        "run": RecordedOptions,
    }

    def setup(self, job: Job, options: StageOptions | None = None) -> Product:
        from cutting.face_contour.slots import setting_sheet
        from virtual_machine.processes.face_contour.stages import format_setting_sheet, tool_speed

        return Product("setup", finite(setting_sheet(job.coupling, tool_speed(job))), format_setting_sheet(job))

    def simulate(
        self, job: Job, out: Path, options: StageOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        from virtual_machine.processes.face_contour.stages import format_simulation, simulate_face_job

        _, summary = simulate_face_job(job)
        out.mkdir(parents=True, exist_ok=True)
        write_json(out / "simulation.json", summary)
        return Product("simulate", summary, format_simulation(summary), written(out, "simulation.json"), out)

    def cut(
        self, job: Job, out: Path, options: StageOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        from virtual_machine.processes.face_contour.stages import cut_face_job, format_result

        with reporter_or_default(reporter) as rep:
            doc = cut_face_job(job, out, rep.stage)
        text = format_result(doc) + f"\n\nwrote {out / 'coupling.stl'}, measurement.json"
        return Product("cut", doc, text, written(out, *FILES), out)

    def run(
        self, job: Job, out: Path, options: RecordedOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        from virtual_machine.processes.face_contour.stages import format_result, run_face_job

        rrd = self._options("run", options).rrd

        with reporter_or_default(reporter) as rep:
            doc = run_face_job(job, Path(job.source), out, None, rep.stage, rrd)
        text = format_result(doc) + (
            f"\n\nwrote {out / 'coupling.stl'}, measurement.json, report.html" + (f", {rrd}" if rrd else "")
        )
        return Product("run", doc, text, written(out, *FILES) + ([rrd] if rrd else []), out)
