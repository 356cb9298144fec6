"""The CNC form-milling machine of seed 003 (the copying method: a profiled disc mill on a spatial path) as an
MJCF model, generated with MjSpec.

The indexing work table A on a worm, the slides X, Y, Z on ball screws, the swivel head B on a worm and the mill
spindle S on a belt (a right-angle head for the finger mill): each axis driven by its motor through drive stages
with their stiffness and backlash, so the machine's errors show between the mill and the gear.
:func:`build_form_mill_spec` (its frame, bodies, joints and drives there) builds it from a :class:`FormMillLayout`
and :class:`FormMillParams`. Lengths are metres here; the CNC and the records use mm. What the machine makes:
docs/form-milling.md, "The machine".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from machine_models.drives import couple, stage_frequency
from machine_models.parameters import ARCSEC, DriveStage, common_problems, override, rigid
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
    motor,
    quat_x,
    tendon_coefs,
    visual,
)

SLIDES = ("X", "Y", "Z")
HEADS = ("disc", "finger_external", "finger_internal")
_BOX, _CYL = mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_CYLINDER
_HINGE, _SLIDE = mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE


@dataclass(frozen=True)
class FormMillParams:
    """Masses, inertias, drives and friction of a mid-size 5-axis CNC gear form-milling machine for gears of
    50-300 mm (SI units, as MuJoCo uses them).

    Plausible orders of magnitude for a machine with a 400 mm worm-driven rotary table, 40 mm ball screws of
    10 mm pitch (the pitch is the layout's) and a 15 kW belt-driven milling spindle, not one maker's data.
    The three nuts are alike (same screw size), so they share ``nut_*``.
    """

    # ---- what the machine takes ------------------------------------------------------------------------------
    #: m: the largest workpiece (external: its tip circle; ring gear: the outside of its rim): gears of 50-300 mm
    workpiece_diameter_limit: float = 0.3
    #: m: the Z slide's travel on its 1 m screw (less the nut and the end bearings): a pass's stroke must fit in it
    z_travel: float = 0.8
    #: m: the largest mill the spindle carries (its arbor and guard)
    mill_diameter_limit: float = 0.25

    # ---- indexing work axis A: rotary table on a worm gear stage from servo motor MA ---------------------
    table_inertia: float = 1.5  # kg m^2: 400 mm face plate + worm wheel (1.2) + fixture (0.3); blank added
    table_mass: float = 120.0  # kg: rotating parts (on the table bearing: only the inertia about z matters)
    table_friction: float = 3.0  # N m: preloaded axial-radial table bearing + worm wheel seal
    a_motor_inertia: float = 1.0e-3  # kg m^2: 6 N m class AC servo motor rotor
    a_motor_torque: float = 20.0  # N m: MA peak (1800 N m at the table through the worm)
    #: MA -> table: 1:90 precision worm gear, 5e5 N m/rad referred to the table (worm mesh, wheel and bearing),
    #: 4 arcsec backlash (a duplex worm set to minimum play), 100 N m s/rad (oil film; zeta ~ 0.06)
    work_drive: DriveStage = field(default_factory=lambda: DriveStage(1 / 90, 5.0e5, 4 * ARCSEC, 100.0))

    # ---- slides on linear roller guides ------------------------------------------------------------------
    z_mass: float = 450.0  # kg: vertical saddle on the column (it carries X, Y and the spindle head)
    x_mass: float = 250.0  # kg: radial ram
    y_mass: float = 120.0  # kg: tangential slide with the spindle housing
    x_ways_friction: float = 150.0  # N: preloaded roller guides of the ram
    y_ways_friction: float = 120.0  # N: guides of the tangential slide
    z_ways_friction: float = 200.0  # N: column guides (wider, higher preload)
    #: share of the weight on Z carried by the counterbalance (hydraulic cylinder); the rest keeps the Z nut on
    #: one flank (as the skiving machine's carriage)
    counterbalance: float = 0.85

    # ---- ball screws: motor -> coupling -> screw -> nut -> slide ------------------------------------------
    screw_inertia: float = 2.0e-3  # kg m^2: 40 mm steel ball screw, 1 m long (9.9 kg)
    x_motor_inertia: float = 1.5e-3  # kg m^2: 12 N m class AC servo motor rotor
    y_motor_inertia: float = 1.5e-3  # kg m^2
    z_motor_inertia: float = 2.5e-3  # kg m^2: 20 N m class motor with holding brake
    x_motor_torque: float = 20.0  # N m: peak
    y_motor_torque: float = 20.0  # N m
    z_motor_torque: float = 30.0  # N m
    #: motor -> screw: bellows coupling 1:1, 5e3 N m/rad referred to the screw (coupling and screw shaft twist)
    x_drive: DriveStage = field(default_factory=lambda: DriveStage(1.0, 5.0e3, 0.0, 0.5))
    y_drive: DriveStage = field(default_factory=lambda: DriveStage(1.0, 5.0e3, 0.0, 0.5))
    z_drive: DriveStage = field(default_factory=lambda: DriveStage(1.0, 5.0e3, 0.0, 0.5))
    #: screw -> slide (ratio pitch / 2 pi from the layout): 2.5e8 N/m axial (screw shaft at mid travel, nut,
    #: thrust bearings in series), 2 um play (a single nut with light preload), 2e4 N s/m (lubricant film)
    nut_stiffness: float | None = 2.5e8  # N/m; None = rigid
    nut_backlash: float = 2.0e-6  # m
    nut_damping: float = 2.0e4  # N s/m

    # ---- swivel head B: spindle housing turning about the radial axis through the mill centre -------------
    head_mass: float = 80.0  # kg: spindle housing, spindle motor bracket (rides on the Y slide)
    head_inertia: float = 1.0  # kg m^2: about the swivel axis (housing, spindle, motor at ~0.1 m)
    head_friction: float = 5.0  # N m: swivel bearing and its clamping seal
    b_motor_inertia: float = 6.0e-4  # kg m^2: 4 N m class AC servo motor rotor
    b_motor_torque: float = 12.0  # N m: MB peak (1440 N m at the head through the worm)
    #: MB -> head: 1:120 worm gear, 3e5 N m/rad referred to the head, 6 arcsec backlash, 60 N m s/rad
    head_drive: DriveStage = field(default_factory=lambda: DriveStage(1 / 120, 3.0e5, 6 * ARCSEC, 60.0))

    # ---- milling spindle S: arbor and disc mill, belt from servo motor MS --------------------------------
    spindle_inertia: float = 0.03  # kg m^2: spindle shaft, pulley and arbor; the mill is added from the layout
    spindle_mass: float = 40.0  # kg: rotating parts riding on the Y slide
    spindle_friction: float = 0.5  # N m: spindle bearings
    s_motor_inertia: float = 3.0e-3  # kg m^2: 15 kW spindle motor rotor
    s_motor_torque: float = 40.0  # N m: MS peak
    #: MS -> spindle: 1:2 toothed belt (spindle rad per motor rad 0.5), 1.5e4 N m/rad referred to the spindle
    spindle_drive: DriveStage = field(default_factory=lambda: DriveStage(0.5, 1.5e4, 0.0, 5.0))

    # ---- simulation -------------------------------------------------------------------------------------------
    timestep: float = 2.5e-4  # s: 4 kHz physics, two sub-steps of the 2 kHz servo; stages keep omega h < 0.5
    integrator: str = "implicitfast"  # damping implicit; the stages' springs explicit (stable for omega h < 2)

    def problems(self) -> list[str]:
        out = common_problems(
            self,
            (
                "table_inertia",
                "table_mass",
                "a_motor_inertia",
                "a_motor_torque",
                "z_mass",
                "x_mass",
                "y_mass",
                "screw_inertia",
                "x_motor_inertia",
                "y_motor_inertia",
                "z_motor_inertia",
                "x_motor_torque",
                "y_motor_torque",
                "z_motor_torque",
                "head_mass",
                "head_inertia",
                "b_motor_inertia",
                "b_motor_torque",
                "spindle_inertia",
                "spindle_mass",
                "s_motor_inertia",
                "s_motor_torque",
                "workpiece_diameter_limit",
                "z_travel",
                "mill_diameter_limit",
            ),
        )
        return out

    def stiff(self) -> FormMillParams:
        """The ideal machine: every stage rigid and free of backlash, no friction (for the proofs)."""
        return rigid(
            self,
            table_friction=0.0,
            x_ways_friction=0.0,
            y_ways_friction=0.0,
            z_ways_friction=0.0,
            spindle_friction=0.0,
            head_friction=0.0,
        )

    def with_overrides(self, values: dict[str, Any]) -> FormMillParams:
        return override(self, values)


@dataclass(frozen=True)
class FormMillLayout:
    """What the gear and the tools fix in the machine (metres, radians).

    The gear frame is the machine frame at A = 0: gear axis z, mid face at z = 0. The home positions are the
    mill centre (X, Y, Z) and the table angle A at the ``home`` keyframe.
    """

    tip_radius: float  # m: gear tip radius
    face_width: float  # m: gear face width b
    blank_radius: float  # m: radius of the blank's mass (a disc of the face width)
    teeth: int  # z: number of teeth (tooth spaces)
    mill_radius: float  # m: disc mill tip radius
    mill_width: float  # m: disc mill width
    screw_pitch: float = 0.010  # m: ball screw pitch of the three slides (10 mm)
    home_x: float = 0.0  # m
    home_y: float = 0.0  # m
    home_z: float = 0.0  # m
    home_a: float = 0.0  # rad
    #: the mill head: "disc" (the disc mill's spindle along machine y at B = 0) or a finger (end) mill's
    #: right-angle head whose spindle lies along the radial symmetry line: "finger_external" (its tip towards the
    #: gear axis, the axis from the tip into the mill along machine +x) or "finger_internal" (inside the ring, its
    #: tip outwards, axis along -x); for a finger ``mill_radius`` is its largest radius, ``mill_width`` its length
    head: str = "disc"

    @classmethod
    def for_gear(
        cls,
        tip_radius: float,
        face_width: float,
        teeth: int,
        mill_radius: float,
        mill_width: float,
        screw_pitch: float = 0.010,
    ) -> FormMillLayout:
        """A layout whose home is the safe position in front of space 0: X at the safe radius, Y = Z = A = 0; the
        blank's mass a disc of the tip radius."""
        safe = tip_radius + mill_radius + 2 * MM
        return cls(tip_radius, face_width, tip_radius, teeth, mill_radius, mill_width, screw_pitch, home_x=safe)

    @classmethod
    def for_finger(
        cls,
        tip_radius: float,
        face_width: float,
        teeth: int,
        mill_radius: float,
        mill_length: float,
        internal: bool,
        screw_pitch: float = 0.010,
    ) -> FormMillLayout:
        """A finger-mill layout (the reference point is the finger's tip centre), home at the safe radius in front
        of space 0 (inside the ring's bore for an internal gear)."""
        head = "finger_internal" if internal else "finger_external"
        safe = tip_radius + (-2 * MM if internal else 2 * MM)
        return cls(
            tip_radius, face_width, tip_radius, teeth, mill_radius, mill_length, screw_pitch, home_x=safe, head=head
        )

    @property
    def finger(self) -> bool:
        return self.head != "disc"

    @property
    def axis_sign(self) -> float:
        """A finger's axis (tip into the mill) along machine x at A = 0: +1 external, -1 internal."""
        return -1.0 if self.head == "finger_internal" else 1.0

    @property
    def safe_radius(self) -> float:
        """Mill centre radius [m] at which the mill clears the tip circle by 2 mm (retract position of X); a finger's
        tip centre 2 mm outside an external gear's tip circle or inside an internal gear's."""
        if self.finger:
            return self.tip_radius + 2 * MM * self.axis_sign
        return self.tip_radius + self.mill_radius + 2 * MM

    def problems(self) -> list[str]:
        out = []
        for name in ("tip_radius", "face_width", "blank_radius", "mill_radius", "mill_width", "screw_pitch"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                out.append(f"{name} = {v}: must be > 0 [m]")
        if self.head not in HEADS:
            out.append(f"head = {self.head!r}: must be one of {', '.join(HEADS)}")
        if not (isinstance(self.teeth, int | np.integer) and self.teeth >= 1):
            out.append(f"teeth = {self.teeth}: must be an integer >= 1")
        for name in ("home_x", "home_y", "home_z", "home_a"):
            if not math.isfinite(getattr(self, name)):
                out.append(f"{name} = {getattr(self, name)}: must be finite")
        return out


def build_form_mill_spec(layout: FormMillLayout, params: FormMillParams | None = None) -> mujoco.MjSpec:
    """The MJCF model of the form-milling machine for ``layout``. Raises ValueError naming bad parameters.

    Machine frame: z up along the work axis, the gear's mid face at z = 0; the mill works on the +x side. Bodies
    and joints:

    - ``work_table``   hinge ``A`` about z: the indexing work axis (rotary table, fixture and blank); site
      ``blank_frame`` = the gear frame (gear axis z, mid face at z = 0, tooth space k centred at the polar angle
      2 pi k / z; with A = 0 space 0 lies on +x);
    - ``z_slide``      slide ``Z`` (vertical, on the column; carries gravity, mostly taken by a counterbalance);
    - ``x_slide``      slide ``X`` on it (radial, along machine x);
    - ``y_slide``      slide ``Y`` on that (tangential, machine y);
    - ``mill_head``    hinge ``B`` about machine x through the mill centre on the Y slide: the swivel head that
      turns the mill's axis out of the transverse plane (seed 003's psi_y: the mill turned with the path);
    - ``mill_spindle`` hinge ``S`` about the head's y axis (machine y at B = 0): arbor and disc mill; site
      ``mill_frame`` at the mill centre, its local z the mill axis (machine +y at B = 0). With a finger mill
      (``FormMillLayout.head``) the head is a right-angle head: ``S`` about machine +x (external
      gear: the finger's tip towards the gear axis) or -x (internal gear: the head reaches into the ring's bore, the
      tip outwards), ``mill_frame`` at the finger's tip centre, its local z the axis from the tip into the mill; B then
      turns the finger about its own axis and is held at 0 (the finger's axis stays along the symmetry line).

    The slides sit at the origin, so the slide coordinates (X, Y, Z) are the mill centre in the machine frame
    and, at A = 0, in the gear frame. Each slide is driven by a ball screw: motor ``MX``/``MY``/``MZ`` -> screw
    hinge ``TX``/``TY``/``TZ`` (stage ``x_drive`` ...) -> nut (stage ``x_nut`` ..., ratio pitch / 2 pi) -> slide;
    the table by ``MA`` through the worm stage ``work_drive``; the head by ``MB`` through the worm stage
    ``head_drive``; the spindle by ``MS`` through the belt ``spindle_drive``. Head B and table A together give the
    mill's axis any direction: B its tilt towards the gear axis, A (turned by a small angle during the feed) its
    component along the radius. Every stage is a :func:`machine_models.drives.couple` tendon; the motors are torque
    actuators of the same names (ctrl in N m, ctrlrange = peak torque).
    """
    params = params or FormMillParams()
    problems = layout.problems() + params.problems()
    if problems:
        raise ValueError("invalid form-milling machine parameters: " + "; ".join(problems))
    spec = machine_spec("form_mill", params.timestep, params.integrator, (0.0, 0.0, -9.81))
    world = spec.worldbody
    world.add_light(pos=[0.2, -1.0, 1.5], dir=[0, 0.6, -1], diffuse=[0.8, 0.8, 0.8])
    b = layout.face_width
    col_x = layout.safe_radius + 0.35  # the column's face
    visual(world, _BOX, (0.45, 0.35, 0.04), DARK, pos=(0.15, 0, -b / 2 - 0.2))  # bed
    visual(world, _BOX, (0.12, 0.25, 0.45), GREY, pos=(col_x + 0.2, 0, 0.2))  # column
    _add_work_table(spec, layout, params)
    zs, xs, ys = _add_slides(world, layout, params, col_x)
    head = _add_mill_head(spec, ys, layout, params)
    _add_mill_spindle(spec, head, layout, params)
    _add_ball_screws(spec, {"X": zs, "Y": xs, "Z": world}, layout, params, col_x)
    spec.add_key(name="home", qpos=_home_qpos(spec, layout))
    return spec


def _add_work_table(spec: mujoco.MjSpec, layout: FormMillLayout, params: FormMillParams) -> None:
    """The indexing work axis A (table, fixture and blank, site ``blank_frame``) and its motor MA with the worm."""
    world = spec.worldbody
    b, r_tip = layout.face_width, layout.tip_radius
    table = world.add_body(name="work_table")
    blank_mass = STEEL * math.pi * layout.blank_radius**2 * b
    inertial(table, params.table_mass + blank_mass, params.table_inertia + blank_mass * layout.blank_radius**2 / 2)
    table.add_joint(name="A", type=_HINGE, axis=[0, 0, 1], frictionloss=params.table_friction)
    visual(table, _CYL, (0.2, 0.03), GREY, pos=(0, 0, -b / 2 - 0.11))  # table
    visual(table, _CYL, (0.04, 0.04), DARK, pos=(0, 0, -b / 2 - 0.04))  # fixture
    visual(table, _CYL, (r_tip, b / 2), STEELC)  # blank
    visual(table, _BOX, (r_tip * 0.5, 0.001, b / 2 + 0.001), ORANGE, pos=(r_tip * 0.5, 0, 0))  # space 0 mark
    table.add_site(name="blank_frame", size=[0.002, 0.002, 0.002])
    a_motor = world.add_body(name="a_motor", pos=[-0.3, -0.25, -b / 2 - 0.11])
    motor(spec, a_motor, "MA", params.a_motor_inertia, params.a_motor_torque)
    couple(spec, "work_drive", "A", "MA", params.work_drive)


def _add_slides(
    world: mujoco.MjsBody, layout: FormMillLayout, params: FormMillParams, col_x: float
) -> tuple[mujoco.MjsBody, mujoco.MjsBody, mujoco.MjsBody]:
    """The slides Z (on the column), X on it and Y on that, all on the counterbalance: (Z, X, Y slide bodies)."""
    gc = params.counterbalance  # the counterbalance carries everything that rides on Z
    zs = world.add_body(name="z_slide")
    inertial(zs, params.z_mass, 20.0, 20.0)
    zs.gravcomp = gc
    zs.add_joint(name="Z", type=_SLIDE, axis=[0, 0, 1], frictionloss=params.z_ways_friction)
    visual(zs, _BOX, (0.06, 0.2, 0.15), BLUE, pos=(col_x + 0.02, 0, 0))
    xs = zs.add_body(name="x_slide")
    inertial(xs, params.x_mass, 10.0, 10.0)
    xs.gravcomp = gc
    xs.add_joint(name="X", type=_SLIDE, axis=[1, 0, 0], frictionloss=params.x_ways_friction)
    visual(xs, _BOX, (0.16, 0.08, 0.08), BLUE, pos=(layout.mill_radius + 0.2, 0, 0.1))  # ram
    ys = xs.add_body(name="y_slide")
    inertial(ys, params.y_mass, 5.0, 5.0)
    ys.gravcomp = gc
    ys.add_joint(name="Y", type=_SLIDE, axis=[0, 1, 0], frictionloss=params.y_ways_friction)
    return zs, xs, ys


def _add_mill_head(
    spec: mujoco.MjSpec, ys: mujoco.MjsBody, layout: FormMillLayout, params: FormMillParams
) -> mujoco.MjsBody:
    """The swivel head B on the Y slide (about machine x through the mill centre) and its motor MB with the worm."""
    gc, r_mill = params.counterbalance, layout.mill_radius
    head = ys.add_body(name="mill_head")
    inertial(head, params.head_mass, params.head_inertia, params.head_inertia)
    head.gravcomp = gc
    head.add_joint(name="B", type=_HINGE, axis=[1, 0, 0], frictionloss=params.head_friction)
    visual(head, _BOX, (0.04, 0.1, 0.06), BLUE, pos=(r_mill + 0.05, 0, 0.06))  # spindle housing
    b_motor = ys.add_body(name="b_motor", pos=[r_mill + 0.12, -0.12, 0.0], quat=[0.5, 0.5, 0.5, 0.5])
    motor(spec, b_motor, "MB", params.b_motor_inertia, params.b_motor_torque)
    b_motor.gravcomp = gc
    couple(spec, "head_drive", "B", "MB", params.head_drive)
    return head


def _add_mill_spindle(
    spec: mujoco.MjSpec, head: mujoco.MjsBody, layout: FormMillLayout, params: FormMillParams
) -> None:
    """The milling spindle S with its mill (site ``mill_frame``) on the head, and its motor MS with the belt."""
    gc, r_mill = params.counterbalance, layout.mill_radius
    if layout.finger:  # right-angle head: local z = the finger's axis along machine +-x (B turns it about itself)
        turn = layout.axis_sign * math.pi / 4
        spindle = head.add_body(name="mill_spindle", quat=[math.cos(turn), 0.0, math.sin(turn), 0.0])
    else:
        spindle = head.add_body(name="mill_spindle", quat=quat_x(-math.pi / 2))  # local z = machine +y at B = 0
    mill_mass = STEEL * math.pi * r_mill**2 * layout.mill_width
    inertial(spindle, params.spindle_mass + mill_mass, params.spindle_inertia + mill_mass * r_mill**2 / 2)
    spindle.gravcomp = gc
    spindle.add_joint(name="S", type=_HINGE, axis=[0, 0, 1], frictionloss=params.spindle_friction)
    _add_mill_visuals(spindle, layout)
    spindle.add_site(name="mill_frame", size=[0.002, 0.002, 0.002])
    s_motor = head.add_body(name="s_motor", pos=[r_mill + 0.05, 0.0, 0.18])
    motor(spec, s_motor, "MS", params.s_motor_inertia, params.s_motor_torque)
    s_motor.gravcomp = gc
    couple(spec, "spindle_drive", "S", "MS", params.spindle_drive)


def _add_mill_visuals(spindle: mujoco.MjsBody, layout: FormMillLayout) -> None:
    """The mill's geoms on the spindle: a finger from its tip with the shank behind, or a disc with mark and arbor."""
    r_mill, w = layout.mill_radius, layout.mill_width
    if layout.finger:  # the finger from its tip (the site) along its axis, the shank behind it
        visual(spindle, _CYL, (r_mill, w / 2), ORANGE, pos=(0, 0, w / 2))
        visual(spindle, _CYL, (max(r_mill, 0.003), 0.03), STEELC, pos=(0, 0, w + 0.03))
    else:
        visual(spindle, _CYL, (r_mill, w / 2), ORANGE)  # disc mill
        visual(spindle, _BOX, (r_mill * 0.9, 0.002, w / 2 + 0.001), DARK)  # angle mark
        visual(spindle, _CYL, (0.012, 0.06), STEELC, pos=(0, 0, -w / 2 - 0.06))  # arbor


def _add_ball_screws(
    spec: mujoco.MjSpec,
    carrier: dict[str, mujoco.MjsBody],
    layout: FormMillLayout,
    params: FormMillParams,
    col_x: float,
) -> None:
    """The ball screws TX/TY/TZ and feed motors MX/MY/MZ on their ``carrier`` bodies, with their drives and nuts."""
    gc, r_mill = params.counterbalance, layout.mill_radius
    lead = layout.screw_pitch / (2 * math.pi)
    nut = DriveStage(lead, params.nut_stiffness, params.nut_backlash, params.nut_damping)
    rot = {"X": [math.cos(math.pi / 4), 0, math.sin(math.pi / 4), 0], "Y": quat_x(-math.pi / 2), "Z": [1, 0, 0, 0]}
    where = {"X": (col_x - 0.2, 0.15, 0.12), "Y": (r_mill + 0.12, 0.0, 0.16), "Z": (col_x + 0.1, 0.2, 0.2)}
    motor_offset = {"X": (0.33, 0, 0), "Y": (0, 0.33, 0), "Z": (0, 0, 0.33)}  # behind the screw, on its axis
    for axis in SLIDES:
        a = axis.lower()
        screw = carrier[axis].add_body(name=f"{a}_screw", pos=list(where[axis]), quat=rot[axis])
        inertial(screw, 9.9, params.screw_inertia, 0.8)
        screw.add_joint(name=f"T{axis}", type=_HINGE, axis=[0, 0, 1])
        visual(screw, _CYL, (0.02, 0.25), STEELC)
        pos = np.add(where[axis], motor_offset[axis]).tolist()
        m = carrier[axis].add_body(name=f"{a}_motor", pos=pos, quat=rot[axis])  # beside the screw, not on it
        motor(spec, m, f"M{axis}", getattr(params, f"{a}_motor_inertia"), getattr(params, f"{a}_motor_torque"))
        if axis != "Z":  # riding on Z: the counterbalance carries them too
            screw.gravcomp = m.gravcomp = gc
        couple(spec, f"{a}_drive", f"T{axis}", f"M{axis}", getattr(params, f"{a}_drive"))
        couple(spec, f"{a}_nut", axis, f"T{axis}", nut)


def _home_qpos(spec: mujoco.MjSpec, layout: FormMillLayout) -> list[float]:
    """Slides and table at the layout's home, every stage relaxed (tendon lengths zero): each screw from its
    nut, each motor from its driven joint."""
    model = spec.compile()
    q = np.zeros(model.nq)
    adr = {model.joint(j).name: int(model.joint(j).qposadr[0]) for j in range(model.njnt)}
    for name, value in (("A", layout.home_a), ("X", layout.home_x), ("Y", layout.home_y), ("Z", layout.home_z)):
        q[adr[name]] = value

    def relax(tendon: str, driven: str, driver: str) -> None:
        coef = tendon_coefs(model, tendon)
        q[adr[driver]] = -coef[driven] * q[adr[driven]] / coef[driver]

    relax("work_drive", "A", "MA")
    relax("head_drive", "B", "MB")
    relax("spindle_drive", "S", "MS")
    for axis in SLIDES:
        relax(f"{axis.lower()}_nut", axis, f"T{axis}")
        relax(f"{axis.lower()}_drive", f"T{axis}", f"M{axis}")
    return q.tolist()


def build_form_mill(layout: FormMillLayout, params: FormMillParams | None = None) -> mujoco.MjModel:
    return build_form_mill_spec(layout, params).compile()


def stage_omega_h(layout: FormMillLayout, params: FormMillParams) -> dict[str, float]:
    """omega * h of every compliant stage's local mode (explicit springs: unstable beyond 2, inaccurate beyond
    ~0.5), keyed by the parameter to change (``nut_stiffness`` for the nuts, the stage's name otherwise)."""
    p, h = params, params.timestep
    lead = layout.screw_pitch / (2 * math.pi)
    blank = STEEL * math.pi * layout.blank_radius**4 * layout.face_width / 2
    out: dict[str, float] = {}

    def put(name: str, stage: DriveStage, driven: float, motor_inertia: float) -> None:
        if stage.stiffness is not None:
            w = 2 * math.pi * stage_frequency(stage.stiffness, driven, motor_inertia, stage.ratio)
            out[name] = max(out.get(name, 0.0), w * h)

    put("work_drive", p.work_drive, p.table_inertia + blank, p.a_motor_inertia)
    put("spindle_drive", p.spindle_drive, p.spindle_inertia, p.s_motor_inertia)
    put("head_drive", p.head_drive, p.head_inertia, p.b_motor_inertia)
    on_y = p.y_mass + p.head_mass + p.spindle_mass
    masses = {"X": p.x_mass + on_y, "Y": on_y, "Z": p.z_mass + p.x_mass + on_y}
    k_nut = (p.nut_stiffness or 0.0) * lead**2  # referred to the screw
    for axis in SLIDES:
        drive: DriveStage = getattr(p, f"{axis.lower()}_drive")
        if drive.stiffness is not None:  # the screw between its coupling and its nut
            out[f"{axis.lower()}_drive"] = math.sqrt((drive.stiffness + k_nut) / p.screw_inertia) * h
        nut = DriveStage(lead, p.nut_stiffness)  # the slide on its nut against the screw
        put("nut_stiffness", nut, masses[axis], p.screw_inertia)
    return out
