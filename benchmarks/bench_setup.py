"""Benchmark (run on demand): time of the setup stage. Prints figures; asserts nothing.

python benchmarks/bench_setup.py
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from virtual_machine.job import load_job
from virtual_machine.setting.change_gears import choose_change_gears
from virtual_machine.setting.sheet import setup_sheet

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"


def timed(fn, repeat: int = 5) -> float:
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    targets = np.random.default_rng(1).uniform(0.1, 10.0, 200)
    choose_change_gears(1.0)
    t = timed(lambda: [choose_change_gears(float(x)) for x in targets], 1) / targets.size
    print(f"change-gear search (two stages, standard set): {t * 1e3:.2f} ms per ratio")
    for name in ("spur_external", "helical_internal"):
        t_load = timed(lambda name=name: load_job(JOBS / f"{name}.toml"), 3)
        job = load_job(JOBS / f"{name}.toml")
        t_int = timed(lambda job=job: job.skiving.edge_intrusion(), 3)
        t_sheet = timed(lambda job=job: [setup_sheet(job, s) for s in ("mechanical", "mechatronic")], 3)
        print(
            f"{name}: load + validate {t_load * 1e3:.0f} ms (interference check {t_int * 1e3:.0f} ms), "
            f"two setting sheets {t_sheet * 1e3:.0f} ms"
        )


if __name__ == "__main__":
    main()
