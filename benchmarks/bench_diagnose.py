"""Benchmark (run on demand): `skive diagnose` on a study held in the case store (issue 43: bar <= 10 s, goal
<= 2 s), and the study's first run that fills the store.

    python benchmarks/bench_diagnose.py                          # the default job
    python benchmarks/bench_diagnose.py --job assets/jobs/spur_external.toml --workers 2

A gear of the job is cut with three geometric errors and measured (measurement.json); the first diagnosis runs the
sensitivity study (16 cases, stage "exact") into a fresh case store, the next ones take it from the store. Each
timed diagnosis runs as the command does (`skive diagnose MEASURED --job JOB --json` in a new process: its imports
and the job's parse included) and in this process (the API, after the imports). Prints each time and the causes.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

from virtual_machine import api
from virtual_machine.job import parse_job
from virtual_machine.processes.skiving.machine_added import exact_measurement

ROOT = Path(__file__).resolve().parents[1]
ERRORS = {"shaft_angle_error": 0.04, "work_encoder_eccentricity": 25.0, "work_encoder_phase": 120.0,
          "carriage_squareness_y": -0.15}  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--job", type=Path, default=ROOT / "assets" / "jobs" / "default.toml")
    ap.add_argument("--workers", type=int, default=0, help="the first run's Dask workers (0: in this process)")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="skive-bench-diagnose-") as tmp:
        tmp_path = Path(tmp)
        lines = "\n".join(f"{k} = {v!r}" for k, v in ERRORS.items())
        text = args.job.read_text() + f"\n[machine.model.geometry]\n{lines}\n"
        measured = tmp_path / "measurement.json"
        measured.write_text(json.dumps(exact_measurement(parse_job(tomllib.loads(text), "bench"))))
        store = tmp_path / "cases"
        t0 = time.perf_counter()
        first = api.diagnose(measured, args.job, tmp_path / "first", cache=store, workers=args.workers)
        print(f"{args.job.name}: the first diagnosis (the study's {first.cases} cases run, {args.workers} workers): "
              f"{time.perf_counter() - t0:.1f} s", flush=True)  # fmt: skip
        for k in range(args.repeat):
            t0 = time.perf_counter()
            out = subprocess.run(
                [sys.executable, "-m", "virtual_machine.cli", "diagnose", str(measured), "--job", str(args.job),
                 "--out", str(tmp_path / f"cli{k}"), "--cache", str(store), "--json"],
                capture_output=True, text=True, check=True,
            )  # fmt: skip
            cli = time.perf_counter() - t0
            t0 = time.perf_counter()
            again = api.diagnose(measured, args.job, tmp_path / f"api{k}", cache=store)
            print(f"  from the store: the command {cli:.2f} s, the API {time.perf_counter() - t0:.2f} s "
                  f"({again.reused} of {again.cases} cases reused)", flush=True)  # fmt: skip
        for c in json.loads(out.stdout)["causes"]:
            print(f"  {c['key']}: {c['value']:.4g} {c['unit']} (confidence {c['confidence']:.2f})")


if __name__ == "__main__":
    main()
