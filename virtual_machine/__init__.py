"""virtual_machine: the simulated machine and its processes; this package's names are skive's Python API.

    from virtual_machine import load_job, run
    result = run(load_job("assets/jobs/default.toml"), out="out")
    result.measurement["iso1328"]["class"]["overall"]

``setup``, ``simulate``, ``cut``, ``run``, ``measure`` and ``study`` do what the `skive` commands of those names
do (:mod:`virtual_machine.api`); :data:`PROCESSES` holds the processes by job kind.
"""

from virtual_machine.api import cut, load_job, measure, run, setup, simulate, study
from virtual_machine.processes import PROCESSES, Process, Product, process_for

__all__ = [
    "PROCESSES",
    "Process",
    "Product",
    "cut",
    "load_job",
    "measure",
    "process_for",
    "run",
    "setup",
    "simulate",
    "study",
]
