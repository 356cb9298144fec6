"""Benchmark (run on demand): a study's throughput on Dask, cases per minute with 1 and 2 local workers.

    python benchmarks/bench_study.py                 # 6 cases of the default job (lead-screw error varied)
    python benchmarks/bench_study.py --cases 4 --base assets/jobs/scenarios/helical_mechatronic.toml
    python benchmarks/bench_study.py --workers 1 2 4

The same study runs from scratch once per worker count (a LocalCluster each time; its start is included). Prints
wall time, cases per minute, the mean wall time of one case on its worker, and the parallel efficiency against one
worker, then what a cluster of N such nodes would do for a 1000-case Monte-Carlo study at the measured per-node
rate (independent cases: the throughput scales with the nodes until the scheduler's ~1 ms per task matters).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from virtual_machine.studies.design import cases
from virtual_machine.studies.runner import run_study
from virtual_machine.studies.spec import load_study

ROOT = Path(__file__).resolve().parents[1]


def study_text(base: Path, n: int) -> str:
    values = ", ".join(f"{1e-4 * (i + 1):.1e}" for i in range(n - 1))
    return (
        f'base = "{base.resolve()}"\nmethod = "one-at-a-time"\n'
        f'[[vary]]\nkey = "machine.model.lead_screw_pitch_error"\nvalues = [{values}]\n'
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cases", type=int, default=6)
    ap.add_argument("--base", type=Path, default=ROOT / "assets" / "jobs" / "default.toml")
    ap.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="skive-bench-study-") as tmp:
        path = Path(tmp) / "study.toml"
        path.write_text(study_text(args.base, args.cases))
        study = load_study(path)
        todo = cases(study)
        print(f"{len(todo)} cases of {args.base.name}", flush=True)
        rates = {}
        for n in args.workers:
            t0 = time.perf_counter()
            run = run_study(study, todo, Path(tmp) / f"w{n}", workers=n)
            wall = time.perf_counter() - t0
            walls = [r["wall_s"] for r in run.results.values()]
            failed = sum(r["status"] != "ok" for r in run.results.values())
            rates[n] = len(todo) / wall * 60
            eff = rates[n] / (rates[args.workers[0]] * n / args.workers[0])
            print(
                f"  {n} worker(s): {wall:6.1f} s, {rates[n]:5.2f} cases/min, one case {sum(walls) / len(walls):5.1f} s "
                f"on its worker, {failed} failed, parallel efficiency {eff:4.0%}",
                flush=True,
            )
        best = max(rates, key=rates.get)
        per_node = rates[best]
        print(f"one {best}-worker node: {per_node:.2f} cases/min", flush=True)
        for nodes in (1, 10, 100):
            minutes = 1000 / (per_node * nodes)
            print(f"  1000-case Monte Carlo on {nodes:3d} such nodes: {minutes:7.1f} min", flush=True)


if __name__ == "__main__":
    main()
