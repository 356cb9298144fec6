"""Benchmark (run on demand): what the machine's geometric errors and thermal drift cost a run (issue 43: bar <= 5 %,
goal ~0).

    python benchmarks/bench_geometry.py                  # the default job, 3 runs each way, alternating
    options: --job JOB (a skiving job file), --repeat N

Runs `skive run` (no recording) on the job as it is and with every geometric error and both encoders set
([machine.model.geometry], docs/machine_geometry.md) and the machine warm (machine.thermal_state, the thermal model's
defaults), alternating, and prints each run's wall time, the best of each and their ratio. The errors change no lever
arm of the machine's dynamics: what they cost is the terms of the forward kinematics per pose, the drift at each
recorded instant and the encoders' two sines per servo tick.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from virtual_machine.job import default_job_path
from virtual_machine.processes.skiving.run import run_job

#: every geometric error at a size a gear-cutting machine can have (docs/machine_geometry.md's keys and units)
EVERY_ERROR = """
[machine.model.geometry]
shaft_angle_error = 0.01
centre_distance_offset = 0.004
cutter_offset_error = -0.02
carriage_squareness_x = 0.01
carriage_squareness_y = -0.02
lead_screw_periodic_error = 0.003
work_spindle_radial_error = 0.005
work_spindle_tilt_error = 0.02
tool_encoder_eccentricity = 5.0
work_encoder_eccentricity = 5.0
"""


def _run(job: Path) -> float:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        run_job(job, Path(tmp) / "out", None)
        return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--job", type=Path, default=default_job_path())
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        errored = Path(tmp) / f"{a.job.stem}_geometry.toml"
        text = a.job.read_text()
        warm = 'thermal_state = "warm"\n'
        if "[machine]\n" in text:
            text = text.replace("[machine]\n", "[machine]\n" + warm, 1)
        else:
            text += "\n[machine]\n" + warm
        errored.write_text(text + EVERY_ERROR)
        _run(a.job)  # the first run of a process loads the kernels: not counted
        times: dict[str, list[float]] = {"exact": [], "as built": []}
        for _ in range(a.repeat):
            times["exact"].append(_run(a.job))
            times["as built"].append(_run(errored))
    for name, ts in times.items():
        print(f"{name:9s} " + "  ".join(f"{t:.2f} s" for t in ts) + f"   best {min(ts):.2f} s")
    ratio = min(times["as built"]) / min(times["exact"])
    print(f"the geometry's cost: {100 * (ratio - 1):+.1f} % (bar <= 5 %, goal ~0)")


if __name__ == "__main__":
    main()
