"""The generated MJCF machine: compiles, steps without warnings, and its drives show the set backlash and
compliance (lost motion = backlash within 5 %, static twist = T/k within 2 %)."""

from __future__ import annotations

import math
from dataclasses import replace

import mujoco
import numpy as np
import pytest
from checks import JOBS

from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.trajectory import ideal_passes
from machine_models.parameters import ARCSEC, DriveStage, SkivingMachineParams
from machine_models.skiving_machine import MachineLayout, build_spec
from virtual_machine.job import load_job
from virtual_machine.setting.machine_layout import skiving_layout

JOB_NAMES = ["spur_external", "helical_internal", "default"]


def _layout(setup: SkivingSetup, lead_screw_pitch_mm: float) -> MachineLayout:
    """The machine's layout for ``setup``, homed at the start of its first ideal pass."""
    return skiving_layout(setup, lead_screw_pitch_mm, ideal_passes(setup)[0])


def _model(job: str = "spur_external", params: SkivingMachineParams | None = None) -> mujoco.MjModel:
    j = load_job(str(JOBS / f"{job}.toml"))
    return build_spec(_layout(j.skiving, j.machine.lead_screw_pitch), params or SkivingMachineParams()).compile()


def _badqacc(d: mujoco.MjData) -> int:
    return int(d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number)


@pytest.mark.parametrize("job", JOB_NAMES)
def test_every_model_compiles_and_steps_without_warnings(job: str) -> None:
    m = _model(job)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("home").id)
    d.ctrl[m.actuator("X").id] = d.qpos[m.joint("X").qposadr[0]]
    mujoco.mj_step(m, d, nstep=2000)
    assert all(int(w.number) == 0 for w in d.warning), [w.number for w in d.warning]
    assert np.isfinite(d.qpos).all()
    # the home keyframe puts the cutter on the first pass's centre distance with every stage relaxed
    j = load_job(str(JOBS / f"{job}.toml"))
    a = j.skiving.pass_centre_distances[0] * 1e-3
    assert d.qpos[m.joint("X").qposadr[0]] == pytest.approx(a, abs=1e-6)


def test_scene_xml_round_trip_has_cutter_and_blank() -> None:
    j = load_job(str(JOBS / "spur_external.toml"))
    xml = build_spec(_layout(j.skiving, j.machine.lead_screw_pitch), SkivingMachineParams()).to_xml()
    m = mujoco.MjModel.from_xml_string(xml)
    bodies = {m.body(i).name for i in range(m.nbody)}
    assert {"work_spindle", "tool_spindle", "carriage", "radial_slide", "lead_screw"} <= bodies
    assert {"blank_frame", "cutter_frame"} <= {m.site(i).name for i in range(m.nsite)}
    # visible geoms on the spindles (cutter and blank)
    assert (m.geom_bodyid == m.body("tool_spindle").id).sum() >= 2
    assert (m.geom_bodyid == m.body("work_spindle").id).sum() >= 2


def _drive_motor(m, d, motor: str, target: float, kp: float, kd: float) -> None:
    """Test-local stiff PD on the motor angle (a position-controlled motor)."""
    q = d.qpos[m.joint(motor).qposadr[0]]
    w = d.qvel[m.joint(motor).dofadr[0]]
    d.ctrl[m.actuator(motor).id] = kp * (target - q) - kd * w


def test_work_drive_lost_motion_equals_backlash() -> None:
    b = 40 * ARCSEC
    stage = DriveStage(0.5, 1.0e6, b, 5.0)
    params = replace(SkivingMachineParams(), work_drive=stage, work_friction=0.05, work_motor_torque=500.0)
    m = _model(params=params)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    d.ctrl[m.actuator("X").id] = d.qpos[m.joint("X").qposadr[0]]
    qm, qb = m.joint("M2").qposadr[0], m.joint("B2").qposadr[0]
    # motor angle: a slow triangle (peak 8 b at the output), up then down
    n = 16000
    h = m.opt.timestep
    peak = 8 * b / stage.ratio
    speed = peak / (n * h)
    inputs, outputs = [], []
    for k in range(2 * n):
        target = speed * k * h if k < n else 2 * peak - speed * k * h
        _drive_motor(m, d, "M2", target, 2000.0, 20.0)
        mujoco.mj_step(m, d)
        inputs.append(d.qpos[qm] * stage.ratio)
        outputs.append(d.qpos[qb])
    assert _badqacc(d) == 0
    inp, out = np.array(inputs), np.array(outputs)
    # lost motion: the width of the hysteresis of output against input, between the steady parts of the
    # forward and the return branch (the output lags by b/2 each way once the gap has been crossed)
    forward = np.median((out - inp)[n // 2 : n])
    back = np.median((out - inp)[3 * n // 2 :])
    lost = back - forward
    assert lost == pytest.approx(b, rel=0.05), (lost / ARCSEC, b / ARCSEC)


def test_work_drive_static_twist_is_torque_over_stiffness() -> None:
    k = 5.0e5
    stage = DriveStage(0.5, k, 10 * ARCSEC, 20.0)
    params = replace(SkivingMachineParams(), work_drive=stage, work_friction=0.0, work_motor_torque=500.0)
    m = _model(params=params)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    d.ctrl[m.actuator("X").id] = d.qpos[m.joint("X").qposadr[0]]
    torque = 30.0  # N m on the work spindle (a cutting torque)
    d.qfrc_applied[m.joint("B2").dofadr[0]] = torque
    for _ in range(12000):
        _drive_motor(m, d, "M2", 0.0, 5000.0, 50.0)
        mujoco.mj_step(m, d)
    assert _badqacc(d) == 0
    twist = d.qpos[m.joint("B2").qposadr[0]] - stage.ratio * d.qpos[m.joint("M2").qposadr[0]]
    assert twist - stage.backlash / 2 == pytest.approx(torque / k, rel=0.02)


def test_nut_axial_compliance() -> None:
    params = replace(SkivingMachineParams(), ways_friction=0.0, nut_backlash=0.0, counterbalance=1.0)
    m = _model(params=params)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    d.ctrl[m.actuator("X").id] = d.qpos[m.joint("X").qposadr[0]]
    force = 2000.0  # N along +z on the carriage
    d.qfrc_applied[m.joint("P3").dofadr[0]] = force
    tv0 = d.qpos[m.joint("TV").qposadr[0]]
    for _ in range(12000):
        q = d.qpos[m.joint("TV").qposadr[0]]
        w = d.qvel[m.joint("TV").dofadr[0]]
        d.ctrl[m.actuator("M3").id] = 200.0 * (tv0 - q) - 2.0 * w  # motor holding the screw
        mujoco.mj_step(m, d)
    pitch = load_job(str(JOBS / "spur_external.toml")).machine.lead_screw_pitch * 1e-3
    stretch = d.qpos[m.joint("P3").qposadr[0]] - pitch / (2 * math.pi) * d.qpos[m.joint("TV").qposadr[0]]
    assert stretch == pytest.approx(force / params.nut_stiffness, rel=0.02)


def test_invalid_parameters_are_named() -> None:
    bad = replace(SkivingMachineParams(), work_drive=DriveStage(0.5, None, 1e-4), carriage_mass=0.0)
    j = load_job(str(JOBS / "spur_external.toml"))
    with pytest.raises(ValueError, match=r"work_drive.backlash.*contact stiffness") as info:
        build_spec(_layout(j.skiving, 10.0), bad)
    assert "carriage_mass" in str(info.value)


@pytest.mark.parametrize("structure", ["mechanical", "hydraulic-differential", "hydraulic-shaft", "mechatronic"])
@pytest.mark.parametrize("job", ["spur_external", "helical_internal"])
def test_every_structure_compiles_and_steps_without_warnings(job: str, structure: str) -> None:
    """Every structure's machine (with its realised chain ratios) has every engaged chain relaxed at home, and loads
    from its own XML (what the viewer opens; printed to ~7 digits, so home is relaxed only to ~1e-5 rad there) and
    steps 0.1 s with its motors idle without a MuJoCo warning (a diverged run only warns)."""
    import dataclasses

    from virtual_machine.setting.chains import chain_ratios

    j = load_job(str(JOBS / f"{job}.toml"))
    j = dataclasses.replace(j, machine=dataclasses.replace(j.machine, structure=structure))
    chains = chain_ratios(j) if structure != "mechatronic" else None
    spec = build_spec(_layout(j.skiving, j.machine.lead_screw_pitch), SkivingMachineParams(), structure, chains)
    compiled = spec.compile()
    d = mujoco.MjData(compiled)
    mujoco.mj_resetDataKeyframe(compiled, d, compiled.key("home").id)
    mujoco.mj_forward(compiled, d)
    clutched = {"feed_chain", "feed_reverse", "screw_brake", "traverse"}
    lengths = {compiled.tendon(t).name: d.ten_length[t] for t in range(compiled.ntendon)}
    assert all(abs(v) < 1e-9 for k, v in lengths.items() if k not in clutched), lengths
    m = mujoco.MjModel.from_xml_string(spec.to_xml())
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("home").id)
    d.ctrl[m.actuator("X").id] = d.qpos[m.joint("X").qposadr[0]]
    mujoco.mj_step(m, d, nstep=800)
    assert all(int(w.number) == 0 for w in d.warning), [w.number for w in d.warning]


def test_cutting_load_does_the_work_of_the_force_on_the_relative_motion() -> None:
    """The generalized forces of a cutting force F at a point (on the blank, -F on the cutter) do, for any joint
    velocity, the work F . (v_blank - v_cutter) of that point: checked against finite-difference point velocities."""
    from virtual_machine.runtime.integrator import Integrator
    from virtual_machine.runtime.loop import MachineLoop
    from virtual_machine.runtime.physics import BlankFrameLoad, MachinePhysics

    m = _model()
    phys = MachinePhysics(m, SkivingMachineParams())
    d = phys.data
    mujoco.mj_forward(m, d)
    force, point = np.array([120.0, -800.0, 250.0]), np.array([78.0, 6.0, -3.0])  # N, mm in the blank frame
    hook = BlankFrameLoad(phys, lambda t, dt: [(force, point, np.zeros(3))])  # the skiving machine's load hook
    loop = MachineLoop(Integrator(m, d, 1, 0, str), None, hook, phys.cutter_body, phys.blank_body)
    loop.apply_loads(0.0, 1e-3)  # as the machine loop applies it before a tick
    qfrc = d.qfrc_applied.copy()
    rb = d.site_xmat[phys.site_blank].reshape(3, 3).copy()
    p_world = d.site_xpos[phys.site_blank] + rb @ point * 1e-3
    local = {}
    for body in (phys.blank_body, phys.cutter_body):
        rot = d.xmat[body].reshape(3, 3).copy()
        local[body] = rot.T @ (p_world - d.xpos[body])
    rng = np.random.default_rng(3)
    qvel = rng.normal(size=m.nv)
    eps = 1e-7
    q0 = d.qpos.copy()
    mujoco.mj_integratePos(m, d.qpos, qvel, eps)
    mujoco.mj_kinematics(m, d)
    moved = {b: d.xpos[b] + d.xmat[b].reshape(3, 3) @ local[b] for b in local}
    v_rel = (moved[phys.blank_body] - moved[phys.cutter_body]) / eps  # the blank point minus the cutter point
    assert qfrc @ qvel == pytest.approx((rb @ force) @ v_rel, rel=1e-5)
    d.qpos[:] = q0
    # on the work spindle alone: the moment of the force about the work axis (blank frame z on the axis)
    assert qfrc[m.joint("B2").dofadr[0]] == pytest.approx(np.cross(point * 1e-3, force)[2], rel=1e-9)


def test_lead_screw_pitch_error_is_the_screws_real_lead() -> None:
    """A screw 0.4 % long: the nut couples P3 to TV with the real lead, and the home pose puts no preload on it."""
    from machine_models.parts import tendon_coefs

    job = load_job(str(JOBS / "spur_external.toml"))
    nominal = job.machine.lead_screw_pitch * 1e-3  # m
    params = replace(SkivingMachineParams(), lead_screw_pitch_error=4e-3)
    m = build_spec(_layout(job.skiving, job.machine.lead_screw_pitch), params).compile()
    assert tendon_coefs(m, "nut")["TV"] == pytest.approx(-nominal * 1.004 / (2 * math.pi), rel=1e-12)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_forward(m, d)
    assert abs(d.ten_length[m.tendon("nut").id]) < 1e-9  # within the nut's play: no force at home
    assert "lead_screw_pitch_error" in " ".join(replace(params, lead_screw_pitch_error=0.2).problems())
    assert not replace(params, lead_screw_pitch_error=-8e-5).problems()  # a short screw is fine


def test_a_job_can_make_a_stage_rigid() -> None:
    from machine_models.parameters import override

    p = override(
        SkivingMachineParams(),
        {"work_drive.stiffness": "rigid", "work_drive.backlash": 0.0, "nut_stiffness": "rigid", "nut_backlash": 0.0},
    )
    assert p.work_drive.stiffness is None and p.nut_stiffness is None and not p.problems()
