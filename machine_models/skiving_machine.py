"""The skiving machine as an MJCF model, generated with MjSpec from the job's :class:`MachineLayout` (numbers only:
``virtual_machine.setting.machine_layout.skiving_layout`` builds it from the job's setup) and
:class:`SkivingMachineParams`.

Machine frame = the work frame at rest (cutting/skiving/kinematics.py): z up along the work axis, the common
perpendicular of the axes on +x. Bodies and joints (seed 000 notation):

- ``work_spindle``  hinge ``B2`` about z: table, fixture and blank (B2 + B4 of the seed are one joint);
- ``carriage``      slide ``P3`` along z on vertical ways (gravity loads the lead screw);
- ``radial_slide``  slide ``X`` along x on the carriage: the centre distance of the pass;
- ``swivel_head``   fixed at the shaft angle (the axis turned by -Sigma about x);
- ``tool_spindle``  hinge ``B1`` about the head's z: arbor and cutter;
- ``lead_screw``    hinge ``TV`` about z, beside the carriage;
- motors ``M1`` (tool), ``M2`` (work), ``M3`` (feed): hinges with their rotor inertia, torque actuators
  of the same names.

Every drive stage is a fixed tendon ``L = driven - ratio * motor`` (see :mod:`machine_models.drives`).
Frames for the cutting engine: site ``blank_frame`` (the gear's frame: space 0 centred on +x at B2 = 0)
and site ``cutter_frame`` (the cutter's frame: rake face at z = 0, tooth 0 on the mesh at B1 = 0). The cutter's
visual geoms are named in CUTTER_GEOMS.
Lengths are metres here; the cutting engine works in mm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from machine_models.drives import couple
from machine_models.loop import MIN_MASS, add_modes
from machine_models.parameters import DriveStage, SkivingMachineParams
from machine_models.parts import (
    BLUE,
    DARK,
    GREY,
    MM,
    ORANGE,
    STEEL,
    STEELC,
    inertial,
    machine_spec,
    quat_x,
    quat_z,
    tendon_coefs,
    visual,
)
from machine_models.structure_drives import ChainRatios

#: the visual geoms that draw the cutter as a plain disc (tool_spindle body)
CUTTER_GEOMS = ("cutter", "cutter_mark")


@dataclass(frozen=True)
class MachineLayout:
    """Where the job puts the machine and what it carries, in metres and radians (built from the job's setup by
    ``virtual_machine.setting.machine_layout.skiving_layout``): the first pass's centre distance and carriage start,
    the tool axis's tilt, the work and cutter phases of the cutting engine's frames, the blank (radius, face width),
    the cutter (tip radius, face width), the holder's radius, and the job's nominal lead-screw pitch."""

    centre_distance: float  # first pass [m]
    carriage_start: float  # carriage position at the start of the first pass [m]
    tilt: float  # rotation of the tool axis about x [rad] (-Sigma)
    work_phase: float  # blank_frame about z: the centre of space 0 on +x at B2 = 0 [rad]
    cutter_phase: float  # cutter_frame about z: tooth 0 on the mesh at B1 = 0 [rad]
    lead_screw_pitch_mm: float  # the job's nominal pitch [mm]; the model's screw has it x (1 + pitch error)
    blank_radius: float  # the blank as a disc: tip radius; ring gear: root radius + 3 mn [m]
    blank_width: float  # the gear's face width [m]
    cutter_radius: float  # the cutter's tip radius [m]
    cutter_width: float  # the cutter's face width [m]
    holder_radius: float  # [m]


def build_spec(
    lay: MachineLayout,
    params: SkivingMachineParams,
    structure: str = "mechatronic",
    chains: ChainRatios | None = None,
) -> mujoco.MjSpec:
    """The MJCF model of the machine for the job's layout ``lay`` with the drives of ``structure`` (see
    :mod:`machine_models.structure_drives`); ``chains`` are the realised ratios of the structure's setting organs
    (ideal if None)."""
    problems = params.problems()
    if problems:
        raise ValueError("invalid machine parameters: " + "; ".join(problems))
    # the model's screw has its real lead; the CNC counts pulses for the job's nominal one
    lead_screw_pitch = lay.lead_screw_pitch_mm * (1 + params.lead_screw_pitch_error) * MM
    spec = machine_spec("skiving_machine", params.timestep, params.integrator, (0.0, 0.0, -9.81))
    world = spec.worldbody
    world.add_light(pos=[0, -1.0, 1.5], dir=[0, 0.6, -1], diffuse=[0.8, 0.8, 0.8])
    b = lay.blank_width
    visual(world, mujoco.mjtGeom.mjGEOM_BOX, (0.45, 0.35, 0.04), DARK, pos=(0.1, 0, -b / 2 - 0.16))  # bed

    _work_spindle(world, lay, params)
    loop = params.loop

    # ---- carriage P3, radial slide X, swivel head, tool spindle B1 --------------------------------------
    carriage = world.add_body(name="carriage")
    inertial(carriage, params.carriage_mass, 10.0, 10.0)
    carriage.gravcomp = params.counterbalance
    carriage.add_joint(name="P3", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1], frictionloss=params.ways_friction)
    visual(carriage, mujoco.mjtGeom.mjGEOM_BOX, (0.06, 0.2, 0.18), GREY, pos=(lay.centre_distance + 0.2, 0, 0))
    radial = carriage.add_body(name="radial_slide")
    # the tool's translational modes move part of the slide's and the head's mass: the slide keeps the rest
    tool_modal = sum(m.mass for m in loop if m.at == "tool" and m.kind == "translation")
    inertial(radial, params.radial_mass - tool_modal, 5.0, 5.0)
    radial.gravcomp = params.counterbalance
    radial.add_joint(name="X", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[1, 0, 0], damping=params.radial_damping)
    visual(radial, mujoco.mjtGeom.mjGEOM_BOX, (0.04, 0.12, 0.12), BLUE, pos=(0.13, 0, 0))
    head = radial.add_body(name="swivel_head", quat=quat_x(lay.tilt))
    visual(head, mujoco.mjtGeom.mjGEOM_CYLINDER, (0.05, 0.08), BLUE, pos=(0, 0, 0.1))  # spindle housing
    r_cut, width = lay.cutter_radius, lay.cutter_width
    cutter_mass = STEEL * math.pi * r_cut**2 * width  # the cutter as a disc at its tip diameter (HSS/carbide ~ steel)
    tool_axial = params.tool_inertia + cutter_mass * r_cut**2 / 2
    turn = np.empty(9)
    mujoco.mju_quat2Mat(turn, np.array(quat_x(lay.tilt)))  # head frame -> machine frame
    turn = turn.reshape(3, 3)  # the tilts' pivots lie up the spindle (-z local)
    mount = add_modes(head, loop, "tool", turn.T, turn @ np.array([0.0, 0.0, 1.0]), tool_axial / 2)
    tool = mount.add_body(name="tool_spindle")
    inertial(tool, MIN_MASS if _has(loop, "tool") else 12.0 + cutter_mass, tool_axial)
    tool.add_joint(name="B1", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1], frictionloss=params.tool_friction)
    # the cutter as a disc and its angle mark (a recording that knows the cutter draws its teeth instead: CUTTER_GEOMS)
    visual(tool, mujoco.mjtGeom.mjGEOM_CYLINDER, (r_cut, width / 2), ORANGE, pos=(0, 0, -width / 2), name="cutter")
    mark = (r_cut * 0.9, 0.002, width / 2 + 0.001)
    visual(tool, mujoco.mjtGeom.mjGEOM_BOX, mark, DARK, pos=(0, 0, -width / 2), name="cutter_mark")
    visual(
        tool,
        mujoco.mjtGeom.mjGEOM_CYLINDER,
        (lay.holder_radius, 0.02),
        DARK,
        pos=(0, 0, -width - 0.02),
    )  # holder
    tool.add_site(name="cutter_frame", quat=quat_z(lay.cutter_phase))
    tool.gravcomp = params.counterbalance  # the counterbalance carries everything that rides on the carriage
    spec.add_actuator(name="X", target="X", trntype=mujoco.mjtTrn.mjTRN_JOINT).set_to_position(
        kp=params.radial_stiffness
    )

    # ---- lead screw TV and feed motor M3 ---------------------------------------------------------------
    screw = world.add_body(name="lead_screw", pos=[lay.centre_distance + 0.2, 0.25, 0.0])
    inertial(screw, 10.0, params.screw_inertia, 1.0)
    screw.add_joint(name="TV", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    visual(screw, mujoco.mjtGeom.mjGEOM_CYLINDER, (0.02, 0.3), STEELC)
    nut = DriveStage(lead_screw_pitch / (2 * math.pi), params.nut_stiffness, params.nut_backlash, params.nut_damping)
    couple(spec, "nut", "P3", "TV", nut)

    # ---- the structure's motors and chains, then the start of the first pass --------------------------------
    from machine_models.structure_drives import DRIVES

    if structure not in DRIVES:
        raise ValueError(f"unknown structure {structure!r}: use one of {', '.join(DRIVES)}")
    if chains is None and structure != "mechatronic":
        raise ValueError(
            f"structure {structure!r} needs the realised ratios of its chains "
            f"(virtual_machine.setting.chains.chain_ratios)"
        )
    drives = DRIVES[structure](spec, {"world": world, "head": head}, params, chains or ChainRatios())
    spec.add_key(name="home", qpos=_home_qpos(spec, lay, lead_screw_pitch, drives))
    return spec


def _work_spindle(world, lay: MachineLayout, params: SkivingMachineParams) -> None:
    """The work spindle B2 with table, fixture and blank, on the loop's work-side modes (machine_models/loop.py)."""
    r_blank, b = lay.blank_radius, lay.blank_width
    loop = params.loop
    blank_mass = STEEL * math.pi * r_blank**2 * b
    work_axial = params.work_inertia + blank_mass * r_blank**2 / 2
    base = add_modes(world, loop, "work", np.eye(3), np.array([0.0, 0.0, 1.0]), work_axial / 2)
    work = base.add_body(name="work_spindle")
    # with modes the structure's modal masses hold the table's and the blank's translational mass
    inertial(work, MIN_MASS if _has(loop, "work") else 60.0 + blank_mass, work_axial)
    work.add_joint(name="B2", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1], frictionloss=params.work_friction)
    visual(work, mujoco.mjtGeom.mjGEOM_CYLINDER, (0.15, 0.03), GREY, pos=(0, 0, -b / 2 - 0.09))  # table
    visual(work, mujoco.mjtGeom.mjGEOM_CYLINDER, (r_blank, b / 2), STEELC)  # blank
    # the angle mark: a thin bar on the blank's top face from the axis to within the root circle (through the blank
    # it stood across the cut teeth in the recording)
    mark = (0.3 * r_blank, 0.0015, 0.0002)
    visual(work, mujoco.mjtGeom.mjGEOM_BOX, mark, ORANGE, pos=(0.3 * r_blank, 0, b / 2 + 0.0002))
    work.add_site(name="blank_frame", quat=quat_z(lay.work_phase))


def _has(loop, at: str) -> bool:
    return any(m.at == at for m in loop)


def _home_qpos(spec: mujoco.MjSpec, lay: MachineLayout, lead_screw_pitch: float, drives) -> list[float]:
    """Joint positions at the start of the first pass: B1 = 0, the carriage at the pass start (the screw turned by
    its real ``lead_screw_pitch`` [m]), the cutter at the centre distance, B2 = 0 unless a chain sets it, and the
    other joints (motors, stepping motors) such that every engaged chain is relaxed (least squares over the tendons;
    clutched chains are re-centred when they engage)."""
    model = spec.compile()
    q = np.zeros(model.nq)
    known = {
        "X": lay.centre_distance,
        "P3": lay.carriage_start,
        "TV": lay.carriage_start / (lead_screw_pitch / (2 * math.pi)),
        "B1": 0.0,
    }
    if "B2" not in drives.chain_driven:
        known["B2"] = 0.0
    for name, value in known.items():
        q[model.joint(name).qposadr[0]] = value
    unknown = [j for j in range(model.njnt) if model.joint(j).name not in known]
    rows, rhs = [], []
    for t in range(model.ntendon):
        name = model.tendon(t).name
        if name == "nut" or name in drives.clutched:
            continue
        coefs = tendon_coefs(model, name)
        row = np.zeros(len(unknown))
        b = 0.0
        for joint, c in coefs.items():
            jid = model.joint(joint).id
            if jid in unknown:
                row[unknown.index(jid)] = c
            else:
                b -= c * q[model.jnt_qposadr[jid]]
        rows.append(row)
        rhs.append(b)
    if rows:
        sol = np.linalg.lstsq(np.array(rows), np.array(rhs), rcond=None)[0]
        for k, jid in enumerate(unknown):
            q[model.jnt_qposadr[jid]] = sol[k]
    return q.tolist()
