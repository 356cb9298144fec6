"""The thread-cutting lathe of seed 001 (group Fv(B1 P2)) as an MJCF model, generated with MjSpec.

Seed 001's three forms of the thread-cutting group on one lathe: the spindle B1 and the carriage P2 on the lead screw
TV, linked by the mechanical chain (fig. 1) or by the screw's own motor M2 (master-slave, fig. 2; equal coordinates,
fig. 3), each link a drive stage with its stiffness and backlash, so the lead the form cuts shows between tool and
workpiece. :func:`build_thread_lathe_spec` (its frame, bodies, joints, forms and drives there) builds it from a
:class:`ThreadLayout` (the thread's hand there) and :class:`ThreadLatheParams`. Lengths are metres here; the job and
the records use mm. The lathe's runs and its reach: docs/machines.md, "The machine in MuJoCo".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import mujoco
import numpy as np

from machine_models.drives import couple
from machine_models.parameters import ARCSEC, DriveStage, common_problems, rigid
from machine_models.parts import (
    BLUE,
    DARK,
    GREY,
    ORANGE,
    STEEL,
    STEELC,
    inertial,
    machine_spec,
    motor,
    tendon_coefs,
    visual,
)

FORMS = ("mechanical", "master-slave", "equal-coordinates")


@dataclass(frozen=True)
class ThreadLatheParams:
    """Masses, inertias, drives and friction of a CNC lathe of 320 mm swing (SI units, as MuJoCo uses them).

    Plausible orders of magnitude for a 5.5 kW lathe with a 160 mm chuck and a 25 mm lead screw, not one
    maker's data. Stages whose ratio comes from the job (``gear_chain``, ``feed_drive``; ``spindle_drive`` in
    the mechanical form) hold a placeholder ratio of 1 that the model replaces.
    """

    # ---- spindle B1: spindle, chuck, workpiece (added from the job) -------------------------------------
    spindle_inertia: float = 0.04  # kg m^2: 160 mm three-jaw chuck (0.025) + spindle shaft and pulley (0.015)
    spindle_mass: float = 30.0  # kg: chuck + spindle (carried by the bearings; only the inertia matters)
    spindle_friction: float = 1.0  # N m: two preloaded taper-roller bearings at speed
    spindle_motor_inertia: float = 0.015  # kg m^2: rotor of a 5.5 kW 4-pole induction motor
    #: N m: M1 peak of a spindle motor rated for fast run-up (S6 rating, 2.5x the 36 N m of 5.5 kW at 1450 rpm):
    #: the 0.3 s run-up to 2400 rpm needs ~100 N m at the motor of the mechanical form
    spindle_motor_torque: float = 120.0
    #: M1 -> spindle: 1:1 poly-V belt, 2e4 N m/rad referred to the spindle (belt spans at the pulley radius);
    #: the mechanical form uses its stiffness for the gearbox 8 -> R2 -> iv -> 5 with the ratio c3 iv
    spindle_drive: DriveStage = field(default_factory=lambda: DriveStage(1.0, 2.0e4, 0.0, 8.0))
    #: rad/s: the spindle's top speed, 5000 rpm: its bearings at a speed factor n dm of 0.6e6 mm/min (grease-
    #: lubricated precision bearings) on a 120 mm pitch diameter, within what a 160 mm chuck is rated for
    spindle_speed_limit: float = 524.0
    #: m: the largest workpiece diameter over the bed (the lathe's swing)
    swing_diameter: float = 0.32

    # ---- mechanical form: internal link 5 -> ix -> R1 -> 6 -> TV (ratio hand ix i01 from the sheet) -------
    #: referred to the screw: 2e3 N m/rad (six gear meshes and the long shaft 6 twist), 60 arcsec of play
    #: (change gears on a swing bracket are never set to zero backlash)
    gear_chain: DriveStage = field(default_factory=lambda: DriveStage(1.0, 2.0e3, 60 * ARCSEC, 0.5))

    # ---- lead screw TV and its motor M2 (electronic forms) ----------------------------------------------
    screw_inertia: float = 3.0e-4  # kg m^2: 25 mm steel screw 1 m long (3.9 kg)
    #: m: the carriage's travel on that screw (less the nut and the end bearings)
    carriage_travel: float = 0.8
    screw_friction: float = 0.1  # N m: screw support bearings
    screw_motor_inertia: float = 1.2e-3  # kg m^2: 10 N m class AC servo motor rotor
    screw_motor_torque: float = 20.0  # N m: M2 peak (current limit of power amplifier 11 / 28)
    #: M2 -> screw: rigid coupling (ratio i0 or i01 from the job), 3e3 N m/rad of the screw shaft's twist
    feed_drive: DriveStage = field(default_factory=lambda: DriveStage(1.0, 3.0e3, 0.0, 0.5))

    # ---- carriage P2 on the bed ways, nut on the screw ---------------------------------------------------
    carriage_mass: float = 60.0  # kg: saddle, cross slide, tool post and tool
    ways_friction: float = 80.0  # N: slideways with turcite lining, lightly loaded
    nut_stiffness: float | None = 2.0e8  # N/m: axial, screw + nut + thrust bearing; None = rigid
    nut_backlash: float = 5.0e-6  # m: a half-nut / unpreloaded nut of a lathe
    nut_damping: float = 1.0e4  # N s/m: lubricant film in the nut

    # ---- the stroke -----------------------------------------------------------------------------------------
    runup_time: float = 0.3  # s: half-cosine run-up of the spindle with the feed engaged (the CNC's ramp)
    #: m: travel at speed before the tool reaches the thread: ~0.07 s for the servos to settle after the
    #: run-up at the 70 mm/s feed of M12 at 90 m/min. The carriage starts run-up travel + clearance ahead.
    clearance: float = 0.005

    # ---- simulation ---------------------------------------------------------------------------------------
    timestep: float = 1.25e-4  # s: 8 kHz physics, two sub-steps of a 4 kHz servo
    integrator: str = "implicitfast"  # damping implicit; the stages' springs stay below omega h ~ 0.4

    def problems(self) -> list[str]:
        return common_problems(
            self,
            (
                "spindle_inertia",
                "spindle_mass",
                "carriage_mass",
                "screw_inertia",
                "runup_time",
                "spindle_motor_inertia",
                "screw_motor_inertia",
                "spindle_motor_torque",
                "screw_motor_torque",
                "spindle_speed_limit",
                "swing_diameter",
                "carriage_travel",
            ),
        )

    def stiff(self) -> ThreadLatheParams:
        """The ideal lathe: every stage rigid and free of backlash, no friction (for the proofs)."""
        return rigid(self, spindle_friction=0.0, screw_friction=0.0, ways_friction=0.0)


@dataclass(frozen=True)
class ThreadLayout:
    """What the job and its setting sheet fix in the lathe: ratios, direction, speeds and the start.

    Hand: ``hand_sign`` = dP2/dB1 sign, -1 for a right-hand thread (the spindle turns positively about +z, which is
    M03 seen from the headstock, and the carriage feeds towards the chuck: in the workpiece frame the tool then
    climbs a right-hand helix), +1 for a left-hand one."""

    form: str  # one of FORMS
    hand_sign: int  # sign of dP2/dB1: -1 right hand, +1 left hand
    lead: float  # thread lead P [m]
    screw_lead: float  # carriage travel per screw radian, t_TV / (2 pi) [m/rad]
    spindle_ratio: float  # spindle rad per M1 rad
    chain_ratio: float | None  # mechanical: screw rad per spindle rad (hand ix i01, ix as realised)
    feed_ratio: float | None  # electronic: screw rad per M2 rad (i0 master-slave, i01 equal coordinates)
    spindle_speed: float  # spindle speed the settings realise [rad/s]
    motor_speed: float  # M1 speed [rad/s] at that spindle speed
    length: float  # threaded length [m]
    approach: float  # carriage travel from the start to the thread: run-up travel + clearance [m]
    carriage_start: float  # P2 at the home keyframe [m]; the thread spans [approach, approach + length]
    diameter: float  # thread major diameter [m]


def build_thread_lathe_spec(lay: ThreadLayout, params: ThreadLatheParams | None = None) -> mujoco.MjSpec:
    """The MJCF model of the thread lathe laid out by ``lay``
    (``virtual_machine.setting.thread_layout.thread_layout``: the
    job's form and its setting sheet's ratios).

    Machine frame: z along the spindle axis, pointing from the headstock to the tailstock (the chuck face at z = 0,
    the workpiece on +z); y up (gravity -y), so neither the spindle nor the carriage carries a weight. Bodies
    and joints (seed 001 notation):

    - ``spindle``     hinge ``B1`` about z: spindle, chuck and workpiece;
    - ``carriage``    slide ``P2`` along z: saddle, cross slide and threading tool (site ``tool_tip``);
    - ``lead_screw``  hinge ``TV`` about z, below the carriage;
    - ``spindle_motor`` hinge ``M1``, torque actuator ``M1`` (every form);
    - ``screw_motor`` hinge ``M2``, torque actuator ``M2`` (electronic forms only).

    Three forms (``virtual_machine.setting.thread_layout.thread_form``):

    - ``mechanical`` (fig. 1): M1 -> 8 -> R2 -> iv -> 5 -> spindle (stage ``spindle_drive``, ratio c3 iv), and the
      internal link 5 -> ix -> R1 -> 6 -> TV (stage ``gear_chain``, ratio hand * ix * i01 screw rad per spindle
      rad, with the realised ix of the setting sheet); no M2;
    - ``master-slave`` (fig. 2) and ``equal-coordinates`` (fig. 3): M1 -> belt -> spindle (``spindle_drive``) and
      M2 -> TV (``feed_drive``, ratio i0 resp. i01: screw turn per motor turn).

    The carriage rides on the screw through the nut stage ``nut`` (ratio t_TV / (2 pi) m/rad). Every stage is a
    :func:`machine_models.drives.couple` tendon.
    """
    params = params or ThreadLatheParams()
    problems = params.problems()
    if problems:
        raise ValueError("invalid lathe parameters: " + "; ".join(problems))
    spec = machine_spec(f"thread_lathe_{lay.form}", params.timestep, params.integrator, (0.0, -9.81, 0.0))
    world = spec.worldbody
    world.add_light(pos=[0.3, 1.2, 0.4], dir=[-0.2, -1, -0.2], diffuse=[0.8, 0.8, 0.8])
    box, cyl = mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_CYLINDER
    r_work = lay.diameter / 2
    work_len = lay.length + 2 * lay.approach
    visual(world, box, (0.18, 0.03, 0.6), DARK, pos=(0.0, -0.25, 0.35))  # bed
    visual(world, box, (0.14, 0.14, 0.12), GREY, pos=(0.0, -0.08, -0.2))  # headstock

    # ---- spindle B1: chuck and workpiece ------------------------------------------------------------------
    spindle = world.add_body(name="spindle")
    work_mass = STEEL * math.pi * r_work**2 * work_len
    inertial(spindle, params.spindle_mass + work_mass, params.spindle_inertia + work_mass * r_work**2 / 2)
    spindle.add_joint(name="B1", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1], frictionloss=params.spindle_friction)
    visual(spindle, cyl, (0.1, 0.04), GREY, pos=(0, 0, -0.045))  # chuck
    for k in range(3):  # jaws
        a = 2 * math.pi * k / 3
        c, s = math.cos(a), math.sin(a)
        visual(spindle, box, (0.012, 0.012, 0.015), DARK, pos=(c * (r_work + 0.012), s * (r_work + 0.012), -0.005))
    visual(spindle, cyl, (r_work, work_len / 2), STEELC, pos=(0, 0, work_len / 2))  # workpiece
    visual(spindle, box, (r_work * 0.9, 0.001, work_len / 2 + 0.001), ORANGE, pos=(0, 0, work_len / 2))  # mark
    motor1 = world.add_body(name="spindle_motor", pos=[0.0, -0.2, -0.3])
    motor(spec, motor1, "M1", params.spindle_motor_inertia, params.spindle_motor_torque)
    couple(spec, "spindle_drive", "B1", "M1", replace(params.spindle_drive, ratio=lay.spindle_ratio))

    # ---- carriage P2 with the threading tool -----------------------------------------------------------------
    carriage = world.add_body(name="carriage")
    inertial(carriage, params.carriage_mass, 2.0, 2.0)
    carriage.add_joint(name="P2", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1], frictionloss=params.ways_friction)
    visual(carriage, box, (0.16, 0.03, 0.08), BLUE, pos=(0.0, -0.19, 0.0))  # saddle
    visual(carriage, box, (0.04, 0.04, 0.04), BLUE, pos=(r_work + 0.07, -0.12, 0.0))  # tool post
    visual(carriage, box, (0.03, 0.006, 0.006), ORANGE, pos=(r_work + 0.03, 0.0, 0.0))  # tool
    carriage.add_site(name="tool_tip", pos=[r_work, 0.0, 0.0], size=[0.001, 0.001, 0.001])

    # ---- lead screw TV -----------------------------------------------------------------------------------
    screw = world.add_body(name="lead_screw", pos=[0.12, -0.22, 0.0])
    inertial(screw, 3.9, params.screw_inertia, 0.3)
    screw.add_joint(name="TV", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1], frictionloss=params.screw_friction)
    visual(screw, cyl, (0.0125, 0.5), STEELC, pos=(0, 0, 0.35))
    if lay.form == "mechanical":
        couple(spec, "gear_chain", "TV", "B1", replace(params.gear_chain, ratio=lay.chain_ratio))
    else:
        motor2 = world.add_body(name="screw_motor", pos=[0.12, -0.22, 0.92])
        motor(spec, motor2, "M2", params.screw_motor_inertia, params.screw_motor_torque)
        couple(spec, "feed_drive", "TV", "M2", replace(params.feed_drive, ratio=lay.feed_ratio))
    nut = DriveStage(lay.screw_lead, params.nut_stiffness, params.nut_backlash, params.nut_damping)
    couple(spec, "nut", "P2", "TV", nut)

    spec.add_key(name="home", qpos=_home_qpos(spec, lay))
    return spec


def _home_qpos(spec: mujoco.MjSpec, lay: ThreadLayout) -> list[float]:
    """The carriage at its start, every stage relaxed (tendon lengths zero): screw from the nut, then the
    spindle from the screw (mechanical chain) or the motors from their driven joints."""
    model = spec.compile()
    q = np.zeros(model.nq)
    adr = {model.joint(j).name: int(model.joint(j).qposadr[0]) for j in range(model.njnt)}
    q[adr["P2"]] = lay.carriage_start
    q[adr["TV"]] = lay.carriage_start / lay.screw_lead
    if lay.form == "mechanical":
        coef = tendon_coefs(model, "gear_chain")
        q[adr["B1"]] = -coef["TV"] * q[adr["TV"]] / coef["B1"]
    else:
        coef = tendon_coefs(model, "feed_drive")
        q[adr["M2"]] = -coef["TV"] * q[adr["TV"]] / coef["M2"]
    coef = tendon_coefs(model, "spindle_drive")
    q[adr["M1"]] = -coef["B1"] * q[adr["B1"]] / coef["M1"]
    return q.tolist()
