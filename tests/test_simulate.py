"""The simulated machine: S4 equal coordinates holds the setup ratios, the correction rejects a
load, the recorded pose trajectory is MuJoCo's own kinematics, a diverging run names its stage."""

from __future__ import annotations

import dataclasses
import math

import mujoco
import numpy as np
import pytest
from checks import JOBS

from cutting.errors import SimulationDivergedError
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.trajectory import ideal_passes
from machine_models.parameters import DriveStage, SkivingMachineParams
from machine_models.skiving_machine import MachineLayout, build_spec
from virtual_machine.job import Job, load_job
from virtual_machine.runtime.machine_run import relative_pose, simulate
from virtual_machine.runtime.physics import MachinePhysics
from virtual_machine.setting.machine_layout import skiving_layout


def _layout(setup: SkivingSetup, lead_screw_pitch_mm: float) -> MachineLayout:
    """The machine's layout for ``setup``, homed at the start of its first ideal pass."""
    return skiving_layout(setup, lead_screw_pitch_mm, ideal_passes(setup)[0])


def _job(name: str, **machine) -> Job:
    job = load_job(str(JOBS / f"{name}.toml"))
    return dataclasses.replace(job, machine=dataclasses.replace(job.machine, **machine))


@pytest.mark.parametrize("name", ["spur_external", "helical_internal"])
def test_stiff_machine_follows_the_setup_ratios(name: str) -> None:
    """Rigid, backlash-free drives, fine pulses (1e6 per turn) and encoders: while the cutter can be in the blank
    the work angle follows ratio * B1 + B4(P3) with a variation below 0.1 um on the reference circle (helical:
    the B4 chain through dividers 21/22 has the right sign and size, else the error would grow by mm). The
    feed's start transient (~2 um for 0.05 s: carriage and work axis answer the step with different
    dynamics) ends in the approach, before the cutter reaches the blank."""
    job = _job(name, command_pulses_per_rev=1_000_000, encoder_lines=2_500_000)
    setup = job.skiving
    approach = setup.clearance + setup.engagement_half_length(setup.pass_centre_distances[0])
    rec = simulate(
        job, SkivingMachineParams().stiff(), duration=1.2 + approach / (setup.axial_feed * setup.work_speed / 60)
    )
    stats = rec.sync_stats("cut")
    assert rec.cutting.sum() > 1000
    assert stats["peak_to_peak_um"] < 0.1, stats
    # a constant offset is a phase, not a ratio error: within one command pulse (the discriminators' dead band)
    pulse_um = job.skiving.gear.reference_radius * 2 * math.pi / 1_000_000 * 1e3
    assert abs(stats["mean_um"]) <= 1.05 * pulse_um, (stats, pulse_um)


def test_adaptive_correction_rejects_a_load_step_at_least_5x() -> None:
    """A 20 N m load step on the work spindle (the cutter entering the cut): without correction the speed loop
    recovers the speed but never the lost angle; the correction (discriminators 30/31, keys 33/34) recovers it."""

    def load(t: float) -> float:
        return 0.0 if t < 0.6 else 20.0

    rms = {}
    for adaptive in (True, False):
        job = _job("spur_external", adaptive_correction=adaptive)  # on the small machine (the default size)
        rec = simulate(job, SkivingMachineParams(), duration=1.6, disturbance=load)
        before = (rec.t > 0.5) & (rec.t < 0.6)
        err = rec.sync_um[rec.t > 0.6] - rec.sync_um[before].mean()
        rms[adaptive] = float(np.sqrt(np.mean(err**2)))
    assert rms[False] > 5 * rms[True], rms
    assert rms[False] > 20.0  # the uncorrected loss is real: T / (speed-loop stiffness) integrated


def test_pass_trajectories_cover_every_pass() -> None:
    job = load_job(str(JOBS / "spur_external.toml"))
    rec = simulate(job)
    setup = job.skiving
    assert [p.index for p in rec.passes] == list(range(len(setup.passes)))
    for p, a, travel in zip(rec.passes, setup.pass_centre_distances, setup.pass_travel, strict=True):
        assert np.allclose(p.centre_distance, a, atol=1e-3)  # the radial slide holds the pass depth (um)
        assert p.carriage[0] - p.carriage[-1] == pytest.approx(travel, abs=0.01)  # down feed over the travel
        assert p.t[-1] == pytest.approx(travel / (setup.axial_feed * setup.work_speed / 60), rel=0.01)
    stats = rec.sync_stats("cut")
    assert stats["rms_about_mean_um"] < 2.0, stats  # the default machine, no load


def test_relative_pose_is_mujocos_kinematics() -> None:
    job = load_job(str(JOBS / "helical_internal.toml"))
    params = SkivingMachineParams()
    phys = MachinePhysics(build_spec(_layout(job.skiving, 10.0), params).compile(), params)
    rng = np.random.default_rng(3)
    for _ in range(5):
        for axis, span in (("B1", 10.0), ("B2", 10.0), ("P3", 0.02), ("X", 0.001)):
            phys.data.qpos[phys.qadr[axis]] += rng.uniform(-span, span)
        rot, trans = phys.cutter_pose()
        q = np.array([[phys.q("B1"), phys.q("B2"), phys.q("P3") * 1e3, phys.q("X") * 1e3]])
        r2, t2 = relative_pose(job.skiving, q)
        assert np.allclose(rot, r2[0], atol=1e-12)
        assert np.allclose(trans, t2[0], atol=1e-9)  # mm


def test_relative_pose_with_the_loops_deflection_is_mujocos_kinematics() -> None:
    """With the loop's modes (machine_models/loop.py) the axes' kinematics plus the recorded deflection
    (loop_deflection) is the cutter frame MuJoCo holds, the modes displaced by tens of micrometres."""
    from machine_models.loop import LoopMode
    from virtual_machine.runtime.machine_run import loop_deflection

    job = load_job(str(JOBS / "helical_internal.toml"))
    loop = (
        LoopMode("tool", (1, 0, 0), 150, 0.03, 3e7),
        LoopMode("tool", (0, 1, 0), 260, 0.03, 6e6, "tilt", 0.25),
        LoopMode("work", (0, 1, 0), 200, 0.03, 5e7),
        LoopMode("work", (1, 0, 0), 300, 0.03, 5e6, "tilt", 0.1),
    )
    params = dataclasses.replace(SkivingMachineParams(), loop=loop)
    phys = MachinePhysics(build_spec(_layout(job.skiving, 10.0), params).compile(), params)
    rng = np.random.default_rng(4)
    axes = ("B1", "B2", "P3", "X", "TV")
    for _ in range(5):
        for axis, span in (("B1", 10.0), ("B2", 10.0), ("P3", 0.02), ("X", 0.001)):
            phys.data.qpos[phys.qadr[axis]] += rng.uniform(-span, span)
        for k in range(2):
            for side in ("tool", "work"):
                phys.data.qpos[phys.qadr[f"{side}_loop_{k}"]] = rng.uniform(-5e-5, 5e-5)
        rot, trans = phys.cutter_pose()
        deflection = np.array([loop_deflection(job.skiving, np.array([phys.q(a) for a in axes]), rot, trans)])
        q = np.array([[phys.q("B1"), phys.q("B2"), phys.q("P3") * 1e3, phys.q("X") * 1e3]])
        rigid = relative_pose(job.skiving, q)
        assert np.abs(trans - rigid[1][0]).max() > 0.01  # the modes moved the cutter by more than 10 um
        r2, t2 = relative_pose(job.skiving, q, deflection)
        assert np.allclose(rot, r2[0], atol=1e-12)
        assert np.allclose(trans, t2[0], atol=1e-9)  # mm


def test_a_diverging_simulation_names_its_stage() -> None:
    params = dataclasses.replace(SkivingMachineParams(), work_drive=DriveStage(0.5, 1e10, 0.0, 0.0))
    with pytest.raises(SimulationDivergedError, match=r"work_drive.*stiffness"):
        simulate(load_job(str(JOBS / "spur_external.toml")), params, duration=0.5)
    m = build_spec(_layout(load_job(str(JOBS / "spur_external.toml")).skiving, 10.0), params).compile()
    assert m.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST


def test_simulate_cli_writes_the_trajectory_and_the_record(tmp_path) -> None:
    import json

    from click.testing import CliRunner

    from virtual_machine.cli import main
    from virtual_machine.output import motion_io

    out = tmp_path / "sim"
    args = ["simulate", str(JOBS / "spur_external.toml"), "--duration", "1.2", "--out", str(out), "--json"]
    res = CliRunner().invoke(main, [*args, "--rrd", str(tmp_path / "run.rrd")])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.output)
    assert doc["machine_seconds"] == pytest.approx(1.2, abs=1e-3)
    assert (tmp_path / "run.rrd").stat().st_size > 100_000 and doc["recording"].endswith("run.rrd")
    assert doc["passes"][0]["sync_error_in_cut"]["rms_um"] < 2.0  # 0.7 s of feed: the cut began after 1 mm
    # each file holds what the run reported: simulation.json is the printed summary (less the recording's path),
    # motion.npz the record it was computed from (its sync error while cutting gives the summary's figures),
    # sync_error.png a PNG image, machine.xml the model MuJoCo compiles
    assert json.loads((out / "simulation.json").read_text()) == {k: v for k, v in doc.items() if k != "recording"}
    with np.load(out / "motion.npz") as motion:
        assert motion["t"][-1] == pytest.approx(doc["machine_seconds"], abs=1e-9)
        cut = motion["sync_um"][motion["cutting"]]
        assert cut.size > 0
        assert float(np.sqrt(np.mean(cut**2))) == pytest.approx(doc["sync_error_in_cut"]["rms_um"], rel=1e-12)
        assert float(np.ptp(cut)) == pytest.approx(doc["sync_error_in_cut"]["peak_to_peak_um"], rel=1e-12)
    assert (out / "sync_error.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    machine = mujoco.MjModel.from_xml_path(str(out / "machine.xml"))
    assert "tool_spindle" in {machine.body(i).name for i in range(machine.nbody)}
    scene = mujoco.MjModel.from_xml_path(str(out / "scene.xml"))  # what the plain viewer opens
    assert "tool_spindle" in {scene.body(i).name for i in range(scene.nbody)}
    assert "cutter_frame" in {scene.site(i).name for i in range(scene.nsite)}
    (p,) = motion_io.load_trajectory(out / "trajectory.npz")
    assert p.index == 0 and p.rot.shape == (len(p.t), 3, 3)
    # the poses are rigid and follow the recorded axes
    assert np.allclose(np.einsum("nji,njk->nik", p.rot, p.rot), np.eye(3), atol=1e-12)
    with pytest.raises(ValueError, match="not a skive pose trajectory"):
        np.savez(tmp_path / "x.npz", a=np.zeros(3))
        motion_io.load_trajectory(tmp_path / "x.npz")


def test_master_slave_passes_the_masters_disturbance_to_the_slave() -> None:
    """A 10 N m load step on the tool spindle (the master of Fv): in master-slave form the work spindle follows
    the disturbed tool (it copies the master's deviation: small sync error); in equal coordinates the work
    follows the generator only and the tool's lost angle becomes sync error."""

    def load(t: float) -> float:
        return 0.0 if t < 0.6 else 10.0

    rms = {}
    for sync in ("master-slave", "equal-coordinates"):
        job = _job("spur_external", synchronization=sync)  # on the small machine (the default size)
        rec = simulate(job, SkivingMachineParams(), duration=1.2, disturbance=load, disturbance_axis="B1")
        before = (rec.t > 0.5) & (rec.t < 0.6)
        err = rec.sync_um[rec.t > 0.6] - rec.sync_um[before].mean()
        rms[sync] = float(np.sqrt(np.mean(err**2)))
    assert rms["equal-coordinates"] > 2.5 * rms["master-slave"], rms


def _drift_per_work_rev(rec) -> float:
    """Slope of the sync error [um] against work revolutions (in the direction of rotation) while cutting."""
    sel = rec.cutting
    revs = np.abs(rec.q[sel, 1] - rec.q[sel, 1][0]) / (2 * math.pi)
    return float(np.polyfit(revs, rec.sync_um[sel], 1)[0])


@pytest.mark.parametrize(
    ("structure", "machine", "setting"),
    [
        ("mechanical", {"change_gears": [20, 25, 30, 35, 40, 45, 50, 55, 60, 65, 70, 75, 80]}, "ix"),
        ("hydraulic-differential", {"hydraulic_steps_per_rev": 997}, "kx"),
        ("hydraulic-shaft", {}, "kx"),
    ],
)
def test_chain_structures_hold_the_ratio_their_sheet_realises(structure: str, machine: dict, setting: str) -> None:
    """S1 with a coarse change-gear set (ix realised 1.14872 for 1.15), S2 with a 997-step hydraulic motor
    (kx = 1147/997 for 1.15), S3 with its 3600-step motor (kx = 6261/3600 for 40/23): the simulated work spindle
    drifts against the tool by the sheet's own figure, pitch_um_per_work_rev = eps pi d (stiff chains: the rest
    of the machine adds no drift). S3's kx is cutter turns per work turn, so its error acts with the other sign."""
    from virtual_machine.setting.sheet import setup_sheet

    job = _job("spur_external", structure=structure, **machine)
    sheet = setup_sheet(job, structure)
    eps = sheet.settings[setting].relative_error
    expected = sheet.settings[setting].effect["pitch_um_per_work_rev"]  # eps pi d2
    rec = simulate(job, SkivingMachineParams().stiff(), duration=1.5)
    assert rec.cutting.sum() > 1000
    slope = _drift_per_work_rev(rec)
    dir_work = 1.0 if job.skiving.speed_ratio > 0 else -1.0
    sign = -1.0 if structure == "hydraulic-shaft" else 1.0
    assert slope == pytest.approx(sign * dir_work * expected, rel=0.05), (slope, expected, eps)


@pytest.mark.parametrize(
    ("structure", "setting"), [("mechanical", "ix"), ("hydraulic-differential", "kx"), ("hydraulic-shaft", "kx")]
)
def test_chain_structures_run_a_helical_job(structure: str, setting: str) -> None:
    """The helix chains (iy with the differential; GGI2 -> GShD2; S3's kx with (1 + s/T)) add B4 with the right
    sign and size: on the default compliant machine, once the drift the sheet predicts from its realised ratio is
    taken out, the sync error varies by a few micrometres while cutting (a wrong B4 would drift by mm)."""
    from virtual_machine.setting.sheet import setup_sheet

    job = _job("helical_internal", structure=structure)
    rec = simulate(job, duration=2.5)
    effect = setup_sheet(job, structure).settings[setting].effect["pitch_um_per_work_rev"]
    sel = rec.cutting
    revs = np.abs(rec.q[sel, 1] - rec.q[sel, 1][0]) / (2 * math.pi)
    dir_work = 1.0 if job.skiving.speed_ratio > 0 else -1.0
    sign = -1.0 if structure == "hydraulic-shaft" else 1.0
    residual = rec.sync_um[sel] - sign * dir_work * effect * revs
    assert np.ptp(residual) < 10.0, (np.ptp(residual), effect)


def test_simulate_cli_runs_a_thread_job(tmp_path) -> None:
    import json

    from click.testing import CliRunner

    from virtual_machine.cli import main

    res = CliRunner().invoke(main, ["simulate", str(JOBS / "thread_m12.toml"), "--out", str(tmp_path), "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.output)
    assert doc["form"] == "master-slave" and doc["lead_mm"] == 1.75
    assert doc["lead_error_on_thread"]["peak_to_peak_um"] < 1.0  # the shipped lathe, no load
    assert abs(doc["travel_mm"]) == pytest.approx(30.0, abs=0.5)
    assert mujoco.MjModel.from_xml_path(str(tmp_path / "scene.xml")).nbody >= 4


def test_job_overrides_machine_parameters(tmp_path) -> None:
    """[machine.model] changes the MuJoCo machine (here the work drive's backlash, 1e-4 rad); unknown or invalid
    parameters are reported with their key and the valid names."""
    from cutting.errors import InputError
    from virtual_machine.setting.machine_layout import machine_params

    text = tmp_path / "j.toml"
    base = (JOBS / "spur_external.toml").read_text()
    text.write_text(base + "\n[machine.model.work_drive]\nbacklash = 1e-4\n")
    params = machine_params(load_job(text))
    size = machine_params(load_job(str(JOBS / "spur_external.toml")))  # the job's machine size, unchanged
    assert params.work_drive.backlash == 1e-4 and params.work_drive.stiffness == size.work_drive.stiffness
    m = build_spec(_layout(load_job(text).skiving, 10.0), params).compile()
    assert np.diff(m.tendon_lengthspring[m.tendon("work_drive").id])[0] == pytest.approx(1e-4)
    text.write_text(base + "\n[machine.model]\ncarriage_mas = 300.0\n[machine.model.work_drive]\nbacklash = -1.0\n")
    with pytest.raises(InputError) as info:
        load_job(text)
    msg = str(info.value)
    assert "machine.model.carriage_mas" in msg and "carriage_mass" in msg and "must be >= 0" in msg


def test_hydraulic_steps_show_as_a_sawtooth_of_one_step() -> None:
    """S2 at 10 rpm with a 100-step motor: GShD1 steps at windows * n1 = 115 * 10/60 = 19 Hz, far below the
    oil column's natural frequency (3e4 N m/rad on ~0.04 kg m^2: 138 Hz, damped past critical here), so the work
    spindle follows each step: the sync error is a sawtooth of one step, c1 iS 2 pi / q * r2 = 1257 um peak-to-peak
    (within 10 %), periodic with the disc's window (the synchronous average over one window explains > 90 %
    of its variance). At the shipped 3600 steps and working speed the steps come at 170 kHz and vanish."""
    job = _job("spur_external", structure="hydraulic-differential", c3=0.02, hydraulic_steps_per_rev=100)
    job = dataclasses.replace(job, process=dataclasses.replace(job.process, tool_speed=10.0))
    params = dataclasses.replace(SkivingMachineParams(), hydraulic_stiffness=3e4, hydraulic_damping=80.0)
    rec = simulate(job, params, duration=2.0)
    sel = rec.t > 1.0  # steady running
    e, b1 = rec.sync_um[sel], rec.q[sel, 0]
    step_um = 1.0 * 0.5 * 2 * math.pi / 100 * job.skiving.gear.reference_radius * 1e3  # c1 iS 2pi/q r2
    assert np.ptp(e) == pytest.approx(step_um, rel=0.10)
    phase = np.mod(b1 * 115 / (2 * math.pi), 1.0)  # position within one window of GGI1 (115 windows)
    k = (phase * 32).astype(int)
    avg = np.bincount(k, weights=e, minlength=32) / np.maximum(np.bincount(k, minlength=32), 1)
    assert np.var(avg[k]) > 0.9 * np.var(e)


def test_divider_quantisation_bounds_the_error_by_one_command_pulse() -> None:
    """S4 with coarse command pulses (500 and 2000 per turn: 503 and 126 um on the reference circle of
    spur_external) and fine encoders: the discriminators compare whole pulses, so the work sits within one pulse
    of its reference, and the sign discriminator with its keys acts as a relay: a limit cycle inside that quantum.
    Its size does not scale with the pulse as a relay on a linear plant would (4x the pulse, 4x the cycle): the
    pulse train beats with the 4 kHz servo tick, so the cycle's frequency and share of the pulse change with it
    (measured at 500 / 1000 / 2000 / 4000 pulses: 44.7 / 32.4 / 7.3 / 3.3 um p-p, 9 / 13 / 6 / 5 % of the pulse,
    dominant at 10 / 8 / 31 / 61 Hz). What the quantisation does bound is asserted: the mean within one pulse, the
    cycle within a fifth of it, the finer pulse the smaller error."""
    pp = {}
    for p in (500, 2000):
        job = _job("spur_external", command_pulses_per_rev=p, encoder_lines=2_500_000)
        rec = simulate(job, SkivingMachineParams().stiff(), duration=1.2)
        pulse_um = 2 * math.pi / p * job.skiving.gear.reference_radius * 1e3
        stats = rec.sync_stats("cut")
        assert abs(stats["mean_um"]) <= 1.02 * pulse_um
        assert stats["peak_to_peak_um"] < 0.2 * pulse_um, stats
        pp[p] = stats["peak_to_peak_um"]
    assert pp[2000] < pp[500], pp


def test_simulate_cli_overrides_the_structure(tmp_path) -> None:
    import json

    from click.testing import CliRunner

    from virtual_machine.cli import main

    # 1.0 s: the run-up of spur_external's medium machine (0.64 s) and the first pass's start
    args = ["simulate", str(JOBS / "spur_external.toml"), "--duration", "1.0", "--out", str(tmp_path), "--json"]
    res = CliRunner().invoke(main, [*args, "--structure", "mechanical"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.output)
    assert doc["structure"] == "mechanical" and list(doc["passes"][0]["peak_torque_Nm"]) == ["M1", "M2"]
    res = CliRunner().invoke(main, ["simulate", str(JOBS / "thread_m12.toml"), "--structure", "hydraulic-shaft"])
    assert res.exit_code == 2 and "hydraulic" in res.output
