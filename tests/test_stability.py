"""`skive stability` (virtual_machine/processes/skiving/stability.py): a skiving job's lobes from its loop and its
passes' oriented coefficients, against the one-mode known answer, and the command's files."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from cutting.materials import material
from cutting.oblique import ObliqueForces, load_cutting_model
from machine_models.loop import LoopMode, frequency_response
from virtual_machine.cli import main
from virtual_machine.job import load_job
from virtual_machine.processes.skiving.stability import oriented_coefficients, pass_stability
from virtual_machine.setting.machine_layout import machine_params

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"


def test_the_passes_coefficients_are_the_chip_of_the_moments_linearisation() -> None:
    """D of the default job's first pass against the co-simulation's own load (cutting.skiving.chip_of_the_moment) on
    the ideal machine: the surface the previous revolution left moved by s (1 um along x, y or z of the machine)
    changes the engagements' mean force over a cutter pitch by D s: within 1 % of |D s| without the rounded edge's
    forces (measured 0.3, 0.4, 0.1 %), within 10 % with them (measured 6.4, 5.4, 0.1 %: the edge forces of the elements
    the shift brings into or out of the cut, a change of the chip's width the linearisation leaves out). The mean
    chip is the engagement's (area over width)."""
    from cutting.forces import EdgeFaces
    from cutting.skiving.chip_of_the_moment import COLUMNS, tick_load
    from cutting.skiving.edge import make_edge
    from cutting.skiving.kinematics import rot_z
    from cutting.skiving.sweep import outline_points, simplify_outline, split_sides
    from cutting.skiving.trajectory import ideal_passes
    from cutting.skiving.working_angles import rake_normal
    from virtual_machine.reach.skiving_load import engagement_half_angle_at

    job = load_job(JOBS / "default.toml")
    st = job.skiving
    model = ObliqueForces(material("16MnCr5"), load_cutting_model(), 0.010)
    a = st.pass_centre_distances[0]
    d, h = oriented_coefficients(st, model, a, None)
    assert 0.05 < h < 0.12  # measured 0.078 mm
    pts = outline_points(split_sides(simplify_outline(make_edge(st, "involute").outline, 0.005)[0], 0.2))
    faces = EdgeFaces.of_outline(pts, rake_normal(st))
    omega0 = st.tool_speed * 2 * math.pi / 60
    zeta = ideal_passes(st)[0].v_s / omega0
    ratio, diff = st.speed_ratio, st.differential_rotation_per_mm
    rev, pitch = 2 * math.pi / abs(ratio), 2 * math.pi / st.cutter.teeth
    c = model.model
    chip = np.array([model.material.kc11, model.material.mc, max(model.min_chip, 1e-4), model.reference_factor,
                     model.min_chip, *model.edge_coefficients, c.friction_angle, c.rake_floor])  # fmt: skip
    sharp = chip.copy()
    sharp[5:7] = 0.0  # no edge forces

    def ideal(b1: float) -> np.ndarray:
        return np.array([b1, ratio * b1 + diff * zeta * b1, zeta * b1, a])

    half = engagement_half_angle_at(st, pts, a)
    phi = np.linspace(-half, half, 121)

    def mean_force(shift: np.ndarray, chip: np.ndarray) -> np.ndarray:
        force = np.zeros((len(phi), 3))
        out = np.empty((1, COLUMNS))
        for i, b1 in enumerate(phi):
            turn = rot_z(ratio * b1 + diff * zeta * b1 + st.work_phase)  # blank -> machine frame
            before = np.concatenate([np.zeros(3), turn.T @ shift])
            if tick_load(
                ideal(b1), np.array([omega0, ratio * omega0 + diff * zeta * omega0, zeta * omega0, 0.0]), np.zeros(6),
                np.array([st.tilt, st.cutter_phase, st.work_phase]), st.passage_frames(np.array([0])),
                np.ascontiguousarray(st.blank_frame), pts, faces.rake, faces.body,
                np.array([st.gear.tip_radius, 0.0, st.gear.face_width / 2]),
                st.passage_frames(np.array([-round(rev / pitch)])), ideal(b1 - rev), before, True, np.zeros(4),
                np.zeros(6), False, chip, out,
            ):  # fmt: skip
                force[i] = turn @ out[0, :3]
        return np.trapezoid(force, phi / omega0, axis=0) / (pitch / omega0)

    for forces, tolerance in ((sharp, 0.01), (chip, 0.10)):
        base = mean_force(np.zeros(3), forces)
        for axis in range(3):
            s = np.zeros(3)
            s[axis] = 1e-3  # mm
            change = mean_force(s, forces) - base  # N
            predicted = d @ (s * 1e-3)  # N/m x m
            assert np.linalg.norm(change - predicted) < tolerance * np.linalg.norm(predicted), (axis, change, predicted)


def test_one_soft_mode_gives_tlustys_floor() -> None:
    """The default job on a machine whose only compliance is one tool mode along y (the axes made stiff far above
    it): G = g(omega) u u^T, so G D has one eigenvalue mu = g u^T D u and the lobes' floor of the margin is Tlusty's
    -1 / (2 (u^T D u) Re[g]_min) = 2 k zeta (1 + zeta) / (-u^T D u)."""
    job = load_job(JOBS / "default.toml")
    mode = LoopMode("tool", (0.0, 1.0, 0.0), 180.0, 0.03, 1.5e7)
    params = dataclasses.replace(
        machine_params(job), loop=(mode,), radial_stiffness=1e13, nut_stiffness=None, nut_backlash=0.0
    )
    st = job.skiving
    speeds = np.linspace(600.0, 3000.0, 800)
    (first, *_) = pass_stability(st, params, "16MnCr5", 0.010, speeds=speeds, depths=1)
    model = ObliqueForces(material("16MnCr5"), load_cutting_model(), 0.010)
    d, _ = oriented_coefficients(st, model, st.pass_centre_distances[0], None)
    u = np.array([0.0, 1.0, 0.0])
    floor = 2 * mode.stiffness * mode.damping * (1 + mode.damping) / -(u @ d @ u)
    assert float(np.min(first.margins)) == pytest.approx(floor, rel=0.02)
    # at the job's speed the margin lies on or above that floor (measured 0.65: it chatters) and the chatter frequency
    # just above the mode's (measured 195.9 Hz), within the band where Re[g] < 0
    assert floor * 0.999 <= first.margin < 1.0 and 180.0 < first.chatter_frequency < 200.0
    g = frequency_response((mode,), "tool", np.array([2 * math.pi * 180.0 * math.sqrt(1.06)]), np.zeros(3))
    assert g[0, 1, 1].real == pytest.approx(-1 / (4 * 1.5e7 * 0.03 * 1.03), rel=1e-3)


def test_skive_stability_writes_the_lobes_and_names_each_pass(tmp_path) -> None:
    res = CliRunner().invoke(main, ["stability", str(JOBS / "default.toml"), "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    doc = json.loads((tmp_path / "stability.json").read_text())
    job = load_job(JOBS / "default.toml")
    assert [p["pass"] for p in doc["passes"]] == [1, 2]
    for p, infeed in zip(doc["passes"], job.skiving.passes, strict=True):
        assert p["infeed_mm"] == infeed and p["tool_speed_rpm"] == job.skiving.tool_speed
        assert len(p["lobes"]["tool_speed_rpm"]) == len(p["lobes"]["margin"]) == 300
        assert p["stable"] == (p["margin"] is None or p["margin"] > 1)
        assert f"pass {p['pass']}: infeed" in res.output
    assert (tmp_path / "stability.png").stat().st_size > 10_000
    bad = CliRunner().invoke(main, ["stability", str(JOBS / "thread_m12.toml"), "--out", str(tmp_path)])
    assert bad.exit_code == 2 and "skiving job" in bad.output
