"""Form milling of spatially modified teeth by the copying method (seed 003): the process of a "form_milling" job.

- setup: the profiled mill and the path table with its corrections
(:func:`virtual_machine.processes.form_milling.stages.plan_job`);
- cut: the ideal machine follows the planned path exactly
(:func:`virtual_machine.processes.form_milling.stages.cut_form_job`);
- run: the simulated form-milling machine (MuJoCo, its CNC) follows it, iterated on what it cut
  (:func:`virtual_machine.processes.form_milling.stages.run_form_job`).
A form-milling job has no separate `simulate`: its machine is simulated with its cut.
"""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

from metrology.charts import finite
from virtual_machine.job import Job
from virtual_machine.output.progress import Reporter
from virtual_machine.processes.base import Process, Product, reporter_or_default, written
from virtual_machine.processes.options import RecordedOptions, StageOptions

FILES = ("gear.stl", "measurement.json", "report.html", "charts/*.png", "*.png")


class FormMilling(Process):
    kind = "form_milling"
    title = "form milling (copying method)"
    stages: ClassVar[dict[str, type[StageOptions]]] = {
        "setup": StageOptions,
        "cut": StageOptions,
        "run": RecordedOptions,
    }
    hints: ClassVar[dict[str, str]] = {
        "simulate": "a form-milling job's machine is simulated with its cut: use `skive run`"
    }

    def setup(self, job: Job, options: StageOptions | None = None) -> Product:
        from virtual_machine.processes.form_milling.stages import format_plan, plan_job

        plan = plan_job(job, checks=0)
        return Product("setup", finite(plan.summary()), format_plan(plan))

    def cut(
        self, job: Job, out: Path, options: StageOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        from virtual_machine.output.formatting import format_gear_stl, format_measurement
        from virtual_machine.processes.form_milling.stages import cut_form_job, format_copying

        with reporter_or_default(reporter) as rep:
            doc = cut_form_job(job, out, rep.stage)
        text = "\n".join(
            [
                format_measurement(doc, str(out / "gear.stl")),
                format_copying(doc),
                format_gear_stl(doc["cut"]["gear_stl"]),
            ]
        )
        return Product("cut", doc, text, written(out, *FILES), out)

    def run(
        self, job: Job, out: Path, options: RecordedOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        from virtual_machine.output.formatting import format_measurement
        from virtual_machine.processes.form_milling.stages import format_copying, run_form_job

        rrd = self._options("run", options).rrd

        rep = reporter_or_default(reporter)
        bars: list = []

        def announce(name: str) -> None:
            rep.stage(name)
            if name.startswith("machine"):
                bars.append(rep.task("form-milling machine", 1.0, "of the program", value_format="{:.3f}"))

        def progress(fraction: float) -> None:
            if bars:
                bars[-1].update_to(fraction)

        with rep:
            doc = run_form_job(job, Path(job.source), out, rrd, progress, announce)
        wall = sum(v for k, v in doc["run"]["durations_s"].items() if k != "machine")
        text = "\n".join(
            [
                format_measurement(doc, str(out / "gear.stl")),
                format_copying(doc),
                f"\nrun: {doc['run']['durations_s']['machine']:.1f} s of machine time in {wall:.1f} s; wrote "
                f"{out / 'gear.stl'}, measurement.json, report.html, charts/" + (f", {rrd}" if rrd else ""),
            ]
        )
        return Product("run", doc, text, written(out, *FILES) + ([rrd] if rrd else []), out)
