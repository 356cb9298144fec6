"""Cutting along sampled (simulated) trajectories: interpolation accuracy against the exact ideal motion, the
tooth passages found from the sampled cutter angle, bad trajectories refused, and skive cut --trajectory."""

from __future__ import annotations

import json

import numpy as np
import pytest
from checks import JOBS
from click.testing import CliRunner
from small_jobs import small_job

from cutting.skiving.edge import make_edge
from cutting.skiving.passages import passage_range
from cutting.skiving.sampled_motion import SampledMotion, ideal_samples
from cutting.skiving.trajectory import ideal_passes
from virtual_machine.cli import main
from virtual_machine.job import load_job
from virtual_machine.output import motion_io


def test_interpolation_between_4khz_samples_is_within_0_1_um() -> None:
    """The finishing pass of spur_external sampled at 4 kHz (3.75 deg of cutter per sample): poses between the
    samples, applied to points 50 mm from the cutter axis, lie within 0.1 um of the exact motion (measured
    0.06 um; the sweep error allowed is 1 um)."""
    motion = ideal_passes(load_job(str(JOBS / "spur_external.toml")).skiving)[3]
    sampled = ideal_samples(motion, 4000.0)
    t = np.random.default_rng(1).uniform(0.0, motion.duration, 3000)
    r1, p1 = motion.pose(t)
    r2, p2 = sampled.pose(t)
    pts = np.array([[50.0, 0.0, 0.0], [0.0, 50.0, 0.0], [0.0, 0.0, 50.0]])
    err = np.linalg.norm(np.einsum("nij,kj->nki", r1 - r2, pts) + (p1 - p2)[:, None, :], axis=2)
    assert err.max() < 1e-4, err.max()
    # at the samples themselves the poses are exact
    r3, p3 = sampled.pose(sampled.t[5:9])
    assert np.allclose(r3, sampled.rot[5:9], atol=1e-14) and np.allclose(p3, sampled.trans[5:9], atol=1e-12)


def test_tooth_passages_come_from_the_sampled_cutter_angle() -> None:
    setup = load_job(str(JOBS / "spur_external.toml")).skiving
    motion = ideal_passes(setup)[3]
    sampled = ideal_samples(motion, 4000.0)
    edge = make_edge(setup, "conjugate")
    assert passage_range(sampled, edge)[1:] == passage_range(motion, edge)[1:]
    # a cutter that lags by a constant angle has its passages later by that angle / speed
    lag = SampledMotion(setup, 3, sampled.t, sampled.rot, sampled.trans, sampled.phi - 0.1, sampled.s, sampled.a)
    assert lag.time_at_angle(1.0) == pytest.approx(1.1 / motion.omega0, rel=1e-9)


def test_bad_trajectories_are_refused() -> None:
    setup = load_job(str(JOBS / "spur_external.toml")).skiving
    s = ideal_samples(ideal_passes(setup)[3], 1000.0)
    rot = s.rot.copy()
    rot[10] *= 1.01
    with pytest.raises(Exception, match="not a rigid rotation"):
        SampledMotion(setup, 3, s.t, rot, s.trans, s.phi, s.s, s.a)
    phi = s.phi.copy()
    phi[20] = phi[19]
    with pytest.raises(ValueError, match="cutter angle does not increase"):
        SampledMotion(setup, 3, s.t, s.rot, s.trans, phi, s.s, s.a)


SMALL_JOB = small_job(edge=None)


@pytest.mark.slow
def test_cut_along_the_simulated_trajectory(tmp_path) -> None:
    """skive simulate, then skive cut --trajectory: the gear the simulated machine cuts, measured; the default
    machine without load follows the ratio to a fraction of a micrometre (test_simulate), so its gear's span is
    within 2 um of the ideal cut's."""
    job = tmp_path / "small.toml"
    job.write_text(SMALL_JOB)
    runner = CliRunner()
    sim = runner.invoke(main, ["simulate", str(job), "--out", str(tmp_path / "sim"), "--json"])
    assert sim.exit_code == 0, sim.output
    docs = {}
    for name, extra in (("ideal", []), ("machine", ["--trajectory", str(tmp_path / "sim" / "trajectory.npz")])):
        res = runner.invoke(main, ["cut", str(job), "--out", str(tmp_path / name), *extra])
        assert res.exit_code == 0, res.output
        docs[name] = json.loads((tmp_path / name / "measurement.json").read_text())
    assert docs["machine"]["cut"]["motion"].endswith("trajectory.npz")
    w = {k: d["thickness"]["span"]["W_k_mm"] for k, d in docs.items()}
    assert abs(w["machine"] - w["ideal"]) < 2e-3, w
    # a file that is not a trajectory: the loader refuses it by name, and skive cut reports that as a bad input
    np.savez(tmp_path / "x.npz", a=np.zeros(2))
    with pytest.raises(ValueError, match="not a skive pose trajectory"):
        motion_io.load_trajectory(tmp_path / "x.npz")
    res = runner.invoke(main, ["cut", str(job), "--trajectory", str(tmp_path / "x.npz")])
    assert res.exit_code == 2 and "not a skive pose trajectory" in res.output, res.output
