"""Benchmark (run on demand): a 100-case Monte Carlo of a job on local Dask workers (issue 43: the default job,
2 workers, bar <= 15 min, goal <= 5 min), and what N workers would take.

    python benchmarks/bench_monte_carlo.py                                   # default job, 100 cases, 2 workers
    python benchmarks/bench_monte_carlo.py --samples 40 --stage cut --job assets/jobs/spur_external.toml

The machines are drawn from the job's size's geometric tolerances and the cutters from class A (a study's
``machine_tolerances = "job"``, ``cutter_class = "A"``); each case runs as `skive run` (``--stage run``) or `skive
cut`. Prints the wall time, the cases per minute, the mean time of one case on its worker, the time the scheduler and
the workers' start add (wall x workers - the cases' own time), then the same study's time on N workers from those
(the cases are independent: wall(N) = start + cases x per-case / N), and the cases' class distribution.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from virtual_machine.studies import pipeline

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--job", type=Path, default=ROOT / "assets" / "jobs" / "default.toml")
    ap.add_argument("--samples", type=int, default=100)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--stage", choices=("run", "cut"), default="run")
    ap.add_argument("--cutter-class", default="A", help='AA, A, B, or "none": the job\'s own cutter')
    ap.add_argument("--target", type=int, default=None, help="P(class <= target) (default: the base's class)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="skive-bench-mc-") as tmp:
        path = Path(tmp) / "study.toml"
        path.write_text(
            f'base = "{args.job.resolve()}"\nmethod = "monte-carlo"\nsamples = {args.samples}\nseed = 1\n'
            f'machine_tolerances = "job"\nstage = "{args.stage}"\n'
            + (f'cutter_class = "{args.cutter_class}"\n' if args.cutter_class != "none" else "")
        )
        t0 = time.perf_counter()
        last = [t0]

        def progress(done: int, failed: int, total: int, left: float | None) -> None:
            now = time.perf_counter()
            if now - last[0] > 60 or done == total:
                print(f"  {done}/{total} cases ({failed} failed), {now - t0:.0f} s", flush=True)
                last[0] = now

        out = pipeline.run(path, Path(tmp) / "out", args.workers, None, args.target, progress)
        wall = time.perf_counter() - t0
        walls = [r["wall_s"] for r in out.run.results.values()]
        own = sum(walls)
        per_case = own / len(walls)
        start = max(wall - own / args.workers, 0.0)
        rate = len(walls) / wall * 60
        print(f"{args.job.name}, {args.samples} cases ({args.stage}), {args.workers} local workers: {wall:.0f} s "
              f"= {wall / 60:.1f} min, {rate:.2f} cases/min; one case {per_case:.1f} s on its worker; "
              f"start and scheduling {start:.0f} s")  # fmt: skip
        for n in (1, 2, 4, 8, 16, 32):
            print(f"  on {n:2d} workers: ~{(start + args.samples * per_case / n) / 60:5.1f} min")
        b = out.budget
        counts = ", ".join(f"{c}: {k}" for c, k in sorted(b.class_counts.items()))
        print(f"  the cases' classes: {counts}")
        for n in sorted(b.class_counts):
            print(f"  P(class <= {n}) = {b.p_at_most(n):.2f}")
        worst = b.limiting()
        if worst is not None:
            p, part = worst
            label = f"; its largest variance share: {part.label} ({part.share:.0%})" if part and part.share else ""
            print(f"  limiting: {p.name}, 95th percentile {p.stacked:.2f} um (class {p.stacked_class}){label}")
        for p in b.parameters:
            top = max(p.parts, key=lambda q: q.share or 0.0, default=None)
            if top is not None and top.share:
                print(f"  {p.name}: mean {p.base:.2f}, 95th percentile {p.stacked:.2f} um; largest share "
                      f"{top.label} {top.share:.0%}, residual {p.residual_share or 0:.0%}")  # fmt: skip


if __name__ == "__main__":
    main()
