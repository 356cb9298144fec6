"""The setting sheet as a setup stage's product, for the processes whose sheets come from
:mod:`virtual_machine.setting.sheet` (skiving's S1-S4, the thread group of seed 001)."""

from __future__ import annotations

from metrology.charts import finite
from virtual_machine.job import Job
from virtual_machine.output.formatting import format_sheet
from virtual_machine.processes.base import Product
from virtual_machine.setting.sheet import setup_sheet


def sheet_product(job: Job, structure: str | None = None) -> Product:
    """The setting sheet of ``job`` (``structure``: another than the job's) as the setup stage's product."""
    sheet = setup_sheet(job, structure)
    return Product("setup", finite(sheet.to_json()), format_sheet(sheet, job.source))
