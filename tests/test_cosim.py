"""Machine and cut together: the chips' forces act on the machine and the motors pay for them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from small_jobs import small_job

from cutting.materials import H_MIN
from virtual_machine.job import load_job
from virtual_machine.processes.skiving.cosim import cosimulate
from virtual_machine.setting.machine_layout import machine_params

SMALL_JOB = small_job(sweep_error=0.02)


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    path = tmp_path_factory.mktemp("cosim") / "small.toml"
    path.write_text(SMALL_JOB)
    job = load_job(path)
    return cosimulate(job, forces=True), cosimulate(job, forces=False)


@pytest.mark.slow
def test_the_motors_pay_for_the_chips(runs) -> None:
    loaded, free = runs
    chip_energy = sum(a.load.energy for a in loaded.loads)
    volume = sum(c.volume for c in loaded.cut.chips)
    assert len(loaded.loads) > 300 and volume > 100.0  # a full-depth pass of an 18-tooth m1 gear
    # the load of each servo tick is the chip of the moment (cutting.skiving.chip_of_the_moment): its cutting power,
    # summed, is the work MuJoCo's integration sees the applied wrenches do (measured to 1e-5)
    assert -loaded.load_work == pytest.approx(chip_energy, rel=1e-3)
    # and the actuators deliver exactly the extra work (the run without forces is otherwise the same)
    assert loaded.actuator_work - free.actuator_work == pytest.approx(-loaded.load_work, rel=0.01)
    # the oblique model (cutting.oblique): its level is Kienzle's kc(h) = 2100 h^-0.26 at the table's +6 deg tool,
    # moved by each element's working rake and inclination, plus the 10 um edge's ploughing. The chips sit where the
    # feed puts them: on the elements whose previous surface lies towards the tool's body, the flank and tip that
    # meet the material at a positive working rake (the exact working-angles map of this cut agrees: +18 deg
    # chip-weighted mean); so the specific energy over the chip is about half Kienzle's at 0 deg rake (measured
    # 0.56 of it at the median chip, the chip-weighted K_c / tau_s 1.89 against the table tool's 3.08)
    h = np.array([a.load.thickness for a in loaded.loads])
    kc = np.array([a.load.kc for a in loaded.loads])
    cut = kc > 0
    kienzle = 2100 * np.maximum(h[cut], H_MIN) ** -0.26 * 1.09
    assert 0.45 < float(np.median(kc[cut] / kienzle)) < 0.7
    loads_volume = sum(a.load.volume for a in loaded.loads)
    assert chip_energy == pytest.approx(1e-3 * sum(k * a.load.volume for k, a in zip(kc, loaded.loads, strict=True)))
    assert 1e-3 * kc.min() <= chip_energy / loads_volume <= 1e-3 * kc.max()
    # and every chip pushes the tool off the flank it cuts: a thrust on every engagement, a passive force too
    comp = np.array([np.abs(a.load.components).mean(axis=0) for a in loaded.loads])
    assert (comp[:, 1] > 0).all() and 0.2 < comp[:, 1].sum() / comp[:, 0].sum() < 2.0 and comp[:, 2].sum() > 0


def test_forces_change_the_chips_only_by_the_machines_deflection(runs) -> None:
    loaded, free = runs
    v1, v0 = (sum(c.volume for c in r.cut.chips) for r in runs)
    # a synchronisation error moves both flanks of a space alike (the volume is unchanged to first order); the depth
    # axis gives under the cut's force by at most F_max / k_r, over a space's floor narrower than the pitch p:
    # |V1 - V0| <= z2 b p F_max / k_r (0.9 % here)
    job, params = loaded_job(), machine_params(loaded_job())
    g = job.gear
    give = float(np.linalg.norm(loaded.load_rows[:, 1:4], axis=1).max()) / params.radial_stiffness * 1e3  # mm
    assert abs(v1 - v0) <= g.z * g.face_width * math.pi * g.mn * give
    assert loaded.cut.gear.genus() == 0 and free.cut.gear.genus() == 0
    # the tool motor carries the cutting torque while the cutter is in the blank
    rec = loaded.record
    feed = rec.segment == 3
    base, cutting = rec.torque[feed & ~rec.cutting, 0].mean(), rec.torque[rec.cutting, 0].mean()
    rec0 = free.record
    # without a load the tool motor holds the spindle's friction (at steady speed the inertia's share averages out),
    # in the cut or out of it: 0.5 N m through the 1:1 drive, within 1 %
    friction = params.tool_friction * abs(params.tool_drive.ratio)
    assert rec0.torque[rec0.cutting, 0].mean() == pytest.approx(friction, rel=0.01)
    assert base == pytest.approx(friction, rel=0.01) and cutting > base
    # what it gives beyond that while cutting is the tool spindle's share of the work on the chips, the work spindle
    # the rest. The cutting components alone would leave most of it to the tool (89 % here); the thrust, normal to
    # the flanks, and its net moment about the axes move work from the tool spindle to the work spindle, like a gear
    # pair's tooth force (31 % left to the tool here, docs/forces.md)
    omega = np.gradient(rec.q[:, 0], rec.t) / params.tool_drive.ratio
    extra = float(((rec.torque[:, 0] - friction) * omega * np.gradient(rec.t))[rec.cutting].sum())
    assert 0.05 * -loaded.load_work < extra < -loaded.load_work
    assert loaded.chip_change() < 0.1  # consecutive chips of the removal: the cut changes slowly along the face


def test_the_dexel_cosimulation_equals_a_cut_afterwards_from_its_recorded_motion(runs) -> None:
    """The removal that kept up with the machine (passage by passage, each on the samples around its window) and
    the dexel cut of the motion the machine recorded, made afterwards pass by pass: the same chips, the same gear;
    and its stock as a picture (cutting.skiving.dexel_solid.stock_mesh) the same solid."""
    from cutting.skiving.dexel_cut import cut_dexel
    from cutting.skiving.sampled_motion import sampled_passes
    from virtual_machine.job import dexel_spacing

    loaded, _ = runs
    job = loaded_job()
    st = job.skiving
    after = cut_dexel(st.gear, loaded.edge, sampled_passes(st, loaded.record.passes), dexel_spacing(job), 0.01)
    during = {(c.pass_index, c.cutter_tooth, round(c.time, 6)): c.volume for c in loaded.cut.chips}
    later = {(c.pass_index, c.cutter_tooth, round(c.time, 6)): c.volume for c in after.result.chips if c.volume > 0}
    assert {k for k, v in during.items() if v > 0} == set(later)
    assert [during[k] for k in later] == pytest.approx(list(later.values()), rel=1e-6, abs=1e-12)
    assert after.result.gear.volume() == pytest.approx(loaded.cut.gear.volume(), rel=1e-9)
    # the stock as the recording's snapshots show it (no boolean): closed, the solid's volume within 0.01 % at every
    # ray and slice, 0.1 % thinned by 2 (measured 0.001 % and 0.03 % on the default job)
    import trimesh

    from cutting.skiving.dexel_solid import stock_mesh

    for stride, tol in ((1, 1e-4), (2, 1e-3)):
        mesh = trimesh.Trimesh(*stock_mesh(after.workpiece, stride, stride), process=False)
        assert mesh.is_watertight and mesh.is_winding_consistent and mesh.volume > 0
        assert mesh.volume == pytest.approx(after.result.gear.volume(), rel=tol)


def loaded_job():
    import tomllib

    from virtual_machine.job import parse_job

    return parse_job(tomllib.loads(SMALL_JOB))


@pytest.mark.slow
def test_parallel_manifold_removal_cuts_the_same_gear(tmp_path) -> None:
    """The manifold reference: two worker processes, each owning half the tooth spaces, take the same chips as the
    inline removal (without forces the machine's motion does not depend on when the chips finish). The claim does not
    depend on the feed: the small job at 0.4 mm/rev (233 passages in 327 subtractions, not 470 in 658)."""
    path = tmp_path / "small.toml"
    path.write_text(small_job(sweep_error=0.02, axial_feed=0.4))
    job = load_job(path)
    inline = cosimulate(job, forces=False, removal="manifold")
    par = cosimulate(job, forces=False, workers=2, removal="manifold")
    assert [c.volume for c in par.cut.chips] == pytest.approx([c.volume for c in inline.cut.chips], rel=1e-9, abs=1e-12)
    assert par.cut.gear.volume() == pytest.approx(inline.cut.gear.volume(), rel=1e-12)
    assert par.cut.gear.genus() == 0 and par.cut.subtractions == inline.cut.subtractions
