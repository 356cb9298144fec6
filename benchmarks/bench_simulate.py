"""Benchmark (run on demand): simulated machine time per wall second, per structure, and where the time goes.

    python benchmarks/bench_simulate.py [--job spur_external] [--seconds S]

For each structure the job's machine runs its whole part program for the finishing pass (run-up, infeed, the
feed stroke over the face, retract, return), or only its first ``--seconds``; prints machine s / wall s and
the split of the loop between the physics (mj_step), the controllers (the structure's tick) and the rest (CNC
program, recording).
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import mujoco

from virtual_machine.job import load_job
from virtual_machine.runtime.machine_run import simulate

STRUCTURES = (
    ("mechatronic", "equal-coordinates"),
    ("mechatronic", "master-slave"),
    ("mechanical", "equal-coordinates"),
    ("hydraulic-differential", "equal-coordinates"),
    ("hydraulic-shaft", "equal-coordinates"),
)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--job", default="spur_external")
    ap.add_argument("--seconds", type=float, default=None, help="machine time per structure (default: the pass)")
    ap.add_argument(
        "--fast",
        action="store_true",
        help="the trade-off profile: physics 4 kHz (stage modes kept below 650 Hz: softer work stage, heavier rotors) "
        "and a 2 kHz servo, against the default 8 kHz / 4 kHz",
    )
    a = ap.parse_args()
    params, substeps = None, 2
    if a.fast:
        from machine_models.parameters import ARCSEC, DriveStage, SkivingMachineParams

        params = dataclasses.replace(
            SkivingMachineParams(),
            timestep=2.5e-4,
            work_motor_inertia=8e-3,
            work_drive=DriveStage(0.5, 4e5, 20 * ARCSEC, 60.0),
            guitar_shaft_inertia=5e-3,
            hydraulic_motor_inertia=4e-3,
        )
    base = load_job(f"assets/jobs/{a.job}.toml")
    # the finishing pass alone: one pass at the full depth has the finishing pass's geometry and feed
    depth = sum(base.process.passes)
    base = dataclasses.replace(base, process=dict(base.process, passes=[depth]))
    what = "the whole finishing pass" if a.seconds is None else f"the first {a.seconds:.1f} s of the finishing pass"
    print(f"{a.job}: {what} per structure (run-up, infeed, stroke, retract, return)")
    print(
        f"{'structure':40s} {'machine s':>9} {'wall s':>7} {'x real':>7} {'physics':>8} {'control':>8} {'other':>7} "
        f"{'sync':>13}"
    )
    for structure, sync in STRUCTURES:
        job = dataclasses.replace(base, machine=dict(base.machine, structure=structure, synchronization=sync))
        timing: dict[str, float] = {}
        t0 = time.perf_counter()
        rec = simulate(job, params, duration=a.seconds, timing=timing, servo_substeps=substeps)
        wall = time.perf_counter() - t0
        machine = float(rec.t[-1])
        other = wall - timing["physics"] - timing["control"]
        print(
            f"{structure + ' / ' + sync:40s} {machine:9.2f} {wall:7.2f} {machine / wall:7.1f} "
            f"{timing['physics'] / wall:8.0%} {timing['control'] / wall:8.0%} {other / wall:7.0%} "
            f"{rec.sync_stats('cut').get('rms_about_mean_um', float('nan')):11.3f} um"
        )
    rates = "physics 4 kHz, servo 2 kHz" if a.fast else "physics 8 kHz (2 sub-steps per 4 kHz servo tick)"
    print(f"mujoco {mujoco.__version__}; {rates}")


if __name__ == "__main__":
    main()
