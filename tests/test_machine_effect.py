"""What the machine did (virtual_machine/processes/skiving/machine_effect.py): the forces per pass, the displacement at
the generating point, and the static deflection's known answer on the gear."""

from __future__ import annotations

import math
from unittest import mock

import numpy as np
import pytest
from small_jobs import small_job

from virtual_machine.job import load_job
from virtual_machine.processes.skiving.machine_effect import FEED, flank_normals, generating_point_displacement
from virtual_machine.processes.skiving.run import run_job

#: a roughing pass and a finishing pass of 0.25 mm on the 18-tooth m1 gear, 4 mm face
SMALL = small_job(sweep_error=0.02, axial_feed=0.4, face_width=4.0).replace("passes = [2.25]", "passes = [2.0, 0.25]")
#: one soft mode at the tool along the centre distance: 20 N/um (issue 42's proof), 150 Hz, zeta 0.05
K = 2.0e7
SOFT = SMALL + (
    '\n[[machine.model.loop]]\nat = "tool"\ndirection = [1.0, 0.0, 0.0]\nfrequency = 150.0\ndamping = 0.05\n'
    f"stiffness = {K}\n"
)


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    """The job on the default machine and with the soft mode: each run's document and co-simulation."""
    import virtual_machine.processes.skiving.run as run_module

    tmp = tmp_path_factory.mktemp("effect")
    out, cosimulate = [], run_module.cosimulate
    sims = []

    def keep(*args, **kwargs):
        sims.append(cosimulate(*args, **kwargs))
        return sims[-1]

    for name, text in (("rigid", SMALL), ("soft", SOFT)):
        path = tmp / f"{name}.toml"
        path.write_text(text)
        with mock.patch.object(run_module, "cosimulate", keep):
            doc = run_job(path, tmp / name)
        out.append((load_job(path), doc, sims[-1]))
    return out


def _at_section(job, doc, sim):
    """While the finishing pass's cutter passes the span's section (the helix range's end, +-0.3 mm): the mean radial
    force on the tool [N] and the mean displacement normal to the flanks at the generating point [um]."""
    rec, rows = sim.record, sim.load_rows
    z = doc["evaluation"]["helix_z_mm"][1]
    last = len(job.skiving.passes) - 1
    turn = np.interp(rows[:, 0], rec.t, rec.q[:, 1]) + job.skiving.work_phase
    radial = -(np.cos(turn) * rows[:, 1] - np.sin(turn) * rows[:, 2])
    near = (np.abs(np.interp(rows[:, 0], rec.t, rec.q[:, 2]) - z) < 0.3) & (
        np.interp(rows[:, 0], rec.t, rec.pass_index) > last - 0.5
    )
    _, index, disp = generating_point_displacement(rec, job.skiving)
    p3 = rec.q[rec.segment == FEED, 2]
    there = (np.abs(p3 - z) < 0.3) & (index == last)
    return float(radial[near].mean()), float((disp[there] @ flank_normals(job.skiving).T).mean())


@pytest.mark.slow
def test_a_soft_radial_loop_pushes_the_tool_off_the_flanks_by_its_static_deflection(pair) -> None:
    """The finishing pass's radial force F on the tool pushes it out by delta = F / k on the soft mode: at the
    generating point the tool stands delta sin(alpha_n) further off each flank than on the rigid machine (within
    5 %: the loop's static deflection in the run), and the teeth come out thicker: the span grows.

    Issue 42's proof asks the span's change to be 2 delta sin(alpha_n) within 20 % in a steady cut (spur_external):
    here, on a 4 mm face that holds no steady engagement, it is 8.7 um against 11.0 um (0.79 of it), and on an 8 mm
    face 0.45 of it: the flank at the span's section is finished while the cutter enters the face, earlier than
    the cutter's passing of that section, at a smaller force (open: docs/forces.md)."""
    (job, rigid, sim0), (_, soft, sim1) = pair
    force, moved = _at_section(job, soft, sim1)
    _, still = _at_section(job, rigid, sim0)
    delta = force / K * 1e6  # um
    alpha_n = math.radians(20.0)
    assert force > 100.0  # the thrust pushes the tool out of the space
    assert moved - still == pytest.approx(delta * math.sin(alpha_n), rel=0.05), (moved, still, delta)
    change = (soft["thickness"]["span"]["W_k_mm"] - rigid["thickness"]["span"]["W_k_mm"]) * 1e3
    assert 0.3 * 2 * delta * math.sin(alpha_n) < change < 1.05 * 2 * delta * math.sin(alpha_n)


@pytest.mark.slow
def test_the_report_gives_each_pass_its_components_and_vibration(pair) -> None:
    (_, rigid, _), (_, soft, _) = pair
    for doc in (rigid, soft):
        passes = doc["run"]["forces"]["passes"]
        assert [p["pass"] for p in passes] == [1, 2]
        for p in passes:
            assert p["cutting_mean_N"] > p["passive_mean_N"] > 0 and p["thrust_mean_N"] > 0
            assert p["peak_N"] >= max(p["cutting_mean_N"], p["thrust_mean_N"])
            assert set(p["flank_normal_deflection_um"]) == {"mean", "peak", "flanks_mean"}
            assert len(p["tool_force_machine_mean_N"]) == 3
        assert passes[0]["cutting_mean_N"] > passes[1]["cutting_mean_N"]  # the roughing pass takes more
        for v in doc["run"]["vibration"]:
            assert v["amplitude_um"] >= 0 and v["frequency_hz"] > 0 and "warning" not in v
    # the soft loop rings more under the tooth-passing force
    assert soft["run"]["vibration"][0]["amplitude_um"] > rigid["run"]["vibration"][0]["amplitude_um"]
