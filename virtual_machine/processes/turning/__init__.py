"""Vibration turning (seed 004): the process of a "turning" job.

- setup: the turned surface the commanded path predicts (crests, chip breaking);
- simulate: the lathe turns with the feed vibration under its cutting forces: its path against the command, the
  surface it leaves, the forces and what they change (against the same run without them);
- run: the same, the turned surface also made by manifold3d and its crests held against the exact envelope
(:mod:`virtual_machine.processes.turning.stages`). A turning job has no `cut`: its surface comes from the lathe's path.
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

FILES = ("workpiece.stl", "measurement.json", "report.html")


class VibrationTurning(Process):
    kind = "turning"
    title = "vibration turning"
    stages: ClassVar[dict[str, type[StageOptions]]] = {
        "setup": StageOptions,
        "simulate": StageOptions,
        "run": RecordedOptions,
    }
    hints: ClassVar[dict[str, str]] = {"cut": "use `skive run`: the turned surface comes from the lathe's path"}

    def setup(self, job: Job, options: StageOptions | None = None) -> Product:
        from metrology.turned_surface import turned_surface_summary
        from virtual_machine.processes.turning.stages import format_prediction, ideal_setup

        doc = turned_surface_summary(ideal_setup(job), job.process.revolutions)
        return Product("setup", finite(doc), format_prediction(job))

    def simulate(
        self, job: Job, out: Path, options: StageOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        from virtual_machine.processes.turning.stages import format_run, simulate_summary

        doc, _, _ = simulate_summary(job)
        out.mkdir(parents=True, exist_ok=True)
        write_json(out / "simulation.json", doc)
        return Product("simulate", doc, format_run(doc), written(out, "simulation.json"), out)

    def run(
        self, job: Job, out: Path, options: RecordedOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        from virtual_machine.processes.turning.stages import format_run, run_turning

        rrd = self._options("run", options).rrd

        with reporter_or_default(reporter) as rep:
            doc = run_turning(job, Path(job.source), out, rrd, rep.stage)
        text = format_run(doc) + (
            f"\n\nwrote {out / 'workpiece.stl'}, measurement.json, report.html" + (f", {rrd}" if rrd else "")
        )
        return Product("run", doc, text, written(out, *FILES) + ([rrd] if rrd else []), out)
