"""The scenario table of docs/skiving-run.md, re-measured (run on demand): every scenario of assets/jobs/scenarios/
on the simulated machine, as skive run does it (machine, forces, dexel cut, the exact swept surface of the motion it
made).

    python benchmarks/scenario_table.py                  # all scenarios (~10 min on 2 cores)
    python benchmarks/scenario_table.py lead_screw_error # some of them (the baseline and the ideal cut always run)

Per scenario: the sync error while cutting (RMS, p-p, mean), its drift against the carriage over the face [um/mm]
and the helix change that drift predicts (-drift x L_beta cos(alpha_t)), the measured f_Hbeta (mean of the teeth)
left / right, its change against the ideal cut split into the part opposite on the flanks and the part alike,
F_p, f_falpha and the ISO 1328-1 class. tests/test_scenarios.py asserts the theory; this prints the figures.
"""

from __future__ import annotations

import math
import sys
import time
from pathlib import Path

import numpy as np

from cutting.skiving.edge import make_edge
from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.sampled_motion import sampled_passes
from cutting.skiving.trajectory import ideal_passes
from metrology.measure import measure_gear
from virtual_machine.job import load_job
from virtual_machine.processes.skiving.cosim import cosimulate

SCENARIOS = Path(__file__).resolve().parents[1] / "assets" / "jobs" / "scenarios"
BASELINE = "helical_mechatronic"


def drift_um_per_mm(sim, face_width: float) -> float:
    """Slope of the sync error against the carriage while the mesh point crosses the face [um/mm]."""
    rec = sim.record
    s, e = rec.q[rec.cutting, 2], rec.sync_um[rec.cutting]
    over = np.abs(s) < face_width / 2
    return float(np.polyfit(s[over], e[over], 1)[0])


def base_tangent_length(job, doc) -> float:
    g = job.gear
    z0, z1 = doc["evaluation"]["helix_z_mm"]
    return (z1 - z0) * math.cos(math.atan(math.tan(g.alpha_n) / math.cos(g.beta)))


def helix(doc) -> tuple[float, float]:
    return doc["helix"]["left"]["f_Hbeta_mean"], doc["helix"]["right"]["f_Hbeta_mean"]


def main() -> None:
    names = sys.argv[1:] or sorted(p.stem for p in SCENARIOS.glob("*.toml"))
    base_job = load_job(SCENARIOS / f"{BASELINE}.toml")
    edge = make_edge(base_job.skiving, base_job.cutter_options.edge)
    ideal = measure_gear(SweptVolumes(base_job.gear, edge, ideal_passes(base_job.skiving)), base_job.gear)
    il, ir = helix(ideal)
    m = ideal["iso1328"]["measured"]
    print(
        f"ideal cut of {BASELINE}: f_Hbeta {il:+.2f} / {ir:+.2f} um, F_p {m['F_p']:.2f}, f_falpha "
        f"{m['f_falpha']:.2f} um, class {ideal['iso1328']['class']['overall']}"
    )
    measured = {}
    for name in names:
        t0 = time.perf_counter()
        job = load_job(SCENARIOS / f"{name}.toml")
        sim = cosimulate(job)
        doc = measure_gear(SweptVolumes(job.gear, sim.edge, sampled_passes(job.skiving, sim.record.passes)), job.gear)
        stats = sim.record.sync_stats("cut")
        drift = drift_um_per_mm(sim, job.gear.face_width)
        left, right = helix(doc)
        opposite, alike = ((left - il) - (right - ir)) / 2, ((left - il) + (right - ir)) / 2
        m = doc["iso1328"]["measured"]
        print(
            f"{name:24s} sync {stats['rms_um']:.2f} um RMS, {stats['peak_to_peak_um']:.1f} p-p, mean "
            f"{stats['mean_um']:+.2f}; drift {drift:+.2f} um/mm predicts {-drift * base_tangent_length(job, doc):+.2f}"
            f" um; f_Hbeta {left:+.2f} / {right:+.2f} um (opposite {opposite:+.2f}, alike {alike:+.2f} against the "
            f"ideal cut); f_Halpha {doc['profile']['left']['f_Halpha_mean']:+.2f} / "
            f"{doc['profile']['right']['f_Halpha_mean']:+.2f} um; F_p {m['F_p']:.2f}, f_p {m['f_p']:.2f}, F_r "
            f"{m['F_r']:.2f}, f_falpha {m['f_falpha']:.2f} um; class "
            f"{doc['iso1328']['class']['overall']}; {len(sim.loads)} engagements, {time.perf_counter() - t0:.0f} s",
            flush=True,
        )
        measured[name] = m
    if BASELINE in measured:  # the largest change of any ISO 1328 value against the baseline, per scenario
        for name, m in measured.items():
            worst = max(m, key=lambda k: abs(m[k] - measured[BASELINE][k]))
            change = m[worst] - measured[BASELINE][worst]
            print(f"{name:24s} largest change of an ISO value against the baseline: {worst} {change:+.2f} um")


if __name__ == "__main__":
    main()
