"""Benchmark (run on demand): the machine loop's own cost per servo tick, beside MuJoCo's step and the controllers.

    python benchmarks/bench_loop.py [--job default] [--seconds 2.0] [--repeat 5]
    PYTHONPATH=/path/to/other/checkout python benchmarks/bench_loop.py   # the same figures of another version

Runs the job's skiving machine (no cutting: `simulate`) for ``--seconds`` of machine time, ``--repeat`` times, and
splits each tick's wall time into MuJoCo's step (``mj_step`` as the integrator calls it), the structure's controllers
(its ``tick``) and the rest: the loop, the CNC's program, the records and the checks. Both timed parts are wrapped
alike in every version, so the rest is comparable between checkouts; prints the best of the repeats in ns per tick.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import virtual_machine.runtime.integrator as integrator
from virtual_machine.job import load_job
from virtual_machine.runtime.machine_run import simulate
from virtual_machine.structures.mechatronic import MechatronicS4

JOBS = Path(__file__).resolve().parents[1] / "assets" / "jobs"


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--job", default="default")
    ap.add_argument("--seconds", type=float, default=2.0)
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    job = load_job(JOBS / f"{a.job}.toml")
    spent = {"step": 0.0, "control": 0.0}
    clock = time.perf_counter
    step, tick = integrator._mj_step, MechatronicS4.tick

    def timed_step(*args):
        t0 = clock()
        step(*args)
        spent["step"] += clock() - t0

    def timed_tick(self, *args):
        t0 = clock()
        out = tick(self, *args)
        spent["control"] += clock() - t0
        return out

    integrator._mj_step = timed_step
    MechatronicS4.tick = timed_tick
    best = None
    for _ in range(a.repeat):
        spent.update(step=0.0, control=0.0)
        t0 = clock()
        rec = simulate(job, duration=a.seconds)
        wall = clock() - t0
        n = len(rec.t)
        row = (wall / n, spent["step"] / n, spent["control"] / n)
        best = row if best is None or row[0] < best[0] else best
    total, mj, ctrl = (v * 1e9 for v in best)
    print(f"{a.job}: {len(rec.t)} ticks of {a.seconds:g} s machine time, best of {a.repeat}")
    print(f"  per tick: {total:8.0f} ns in all")
    print(f"            {mj:8.0f} ns MuJoCo's step ({mj / total:.0%})")
    print(f"            {ctrl:8.0f} ns the controllers ({ctrl / total:.0%})")
    print(f"            {total - mj - ctrl:8.0f} ns the loop, the program, the records and the checks")


if __name__ == "__main__":
    main()
