"""Benchmark (run on demand): what the Rerun recording costs a run, against issue 44's bars.

    python benchmarks/bench_recording.py                                   # the default job
    python benchmarks/bench_recording.py --job assets/jobs/spur_external.toml

Runs the job twice in this process, with a recording and without (the order alternated over ``--repeat`` pairs, the
first run of the process warming the caches first), and prints the wall times, the time the recording adds, the
recording's size and its blank snapshots. Bars (docs/skiving-run.md): the default job's recording adds <= 1.5 s
(goal 0.5 s); spur_external's recording <= 200 MB (goal 80 MB).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from rerun.chunk import RrdReader

from virtual_machine.job import default_job_path
from virtual_machine.processes.skiving.run import run_job

BLANK = "/machine/work_spindle/blank_frame/blank/"


def timed(job: Path, out: Path, rrd: Path | None) -> float:
    t0 = time.perf_counter()
    run_job(job, out, rrd)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--job", type=Path, default=default_job_path())
    ap.add_argument("--repeat", type=int, default=2)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        timed(a.job, root / "warm", None)  # caches and compiled kernels: not the recording's cost
        with_rrd, without = [], []
        for k in range(a.repeat):
            order = (True, False) if k % 2 == 0 else (False, True)
            for recorded in order:
                rrd = root / f"run{k}.rrd" if recorded else None
                (with_rrd if recorded else without).append(timed(a.job, root / f"out{k}{recorded}", rrd))
        rrd = root / "run0.rrd"
        size = rrd.stat().st_size / 1e6
        chunks = RrdReader(rrd).stream().to_chunks()
        passes = {c.entity_path for c in chunks if c.entity_path.startswith(BLANK)}
        blank = [c.to_record_batch() for c in chunks if c.entity_path.startswith(BLANK) and not c.is_static]
        # a row with vertices is a snapshot (a pass's stock is cleared when the next one shows: a row without)
        vertices = [
            b.column("Mesh3D:vertex_positions").to_pylist()
            for b in blank
            if "Mesh3D:vertex_positions" in b.schema.names
        ]
        snapshots = sum(1 for rows in vertices for v in rows if v)
    added = min(with_rrd) - min(without)
    best = f"{min(with_rrd):.1f} s with the recording, {min(without):.1f} s without (best of {a.repeat})"
    print(f"skive run {a.job}: {best}")
    print(f"  the recording adds {added:.2f} s (bar for the default job 1.5 s, goal 0.5 s)")
    shots = f"{snapshots} blank snapshots in {len(passes)} passes"
    print(f"  recording {size:.1f} MB (bar for spur_external 200 MB, goal 80 MB); {shots}")


if __name__ == "__main__":
    main()
