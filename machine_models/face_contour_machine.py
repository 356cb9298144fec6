"""The face-contour machine of seed 004 (radial slots of a face coupling cut by continuous indexing) as an MJCF model,
generated with MjSpec.

The work spindle A on a worm (on the cross slide Y when the work's setting changes during the cut), the infeed slide
Z on its ball screw with the swivel at the setting angle, and the tool head H, on the eccentric E (seed 004 eq. 14)
when the control has one: each axis driven by its motor through drive stages with their stiffness and backlash, so
the machine's errors show between the elements' tips and the workpiece. :func:`build_face_machine_spec` (its frame,
bodies, joints and drives there) builds it from a :class:`FaceMachineLayout` and :class:`FaceMachineParams`;
:func:`relaxed_qpos` is a pose with every stage relaxed. Lengths are metres here; the geometry and the records use
mm. What the machine does to the slots: docs/face-contours-and-turning.md, "The face-contour machine".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from machine_models.drives import couple, couple_linear, stage_frequency
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
    quat_z,
    tendon_coefs,
    visual,
)

MOTOR_MASS = 8.0  # kg: what machine_models.parts.motor gives a motor body
_BOX, _CYL = mujoco.mjtGeom.mjGEOM_BOX, mujoco.mjtGeom.mjGEOM_CYLINDER
_HINGE, _SLIDE = mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE


@dataclass(frozen=True)
class FaceMachineParams:
    """Masses, inertias, drives and friction of a face-contour machine for couplings of 80-200 mm (SI units).

    Plausible orders of magnitude for a machine with a 320 mm worm-driven work table, a 250 mm cutter head on a
    geared spindle that rides in an eccentric sleeve, and a vertical infeed slide on a 5 mm ball screw; not one
    maker's data.
    """

    # ---- work spindle A: table, fixture and blank on a worm stage from servo motor MA ----------------------
    table_inertia: float = 0.6  # kg m^2: 320 mm face plate (0.4) + worm wheel and fixture (0.2); blank added
    table_mass: float = 80.0  # kg: rotating parts (only the inertia about z matters on the table bearing)
    work_friction: float = 2.0  # N m: preloaded axial-radial table bearing and seal
    a_motor_inertia: float = 1.0e-3  # kg m^2: 6 N m class AC servo motor rotor
    a_motor_torque: float = 20.0  # N m: MA peak (1800 N m at the table)
    #: MA -> table: 1:90 precision worm, 5e5 N m/rad at the table (mesh, wheel, bearing), 4 arcsec backlash (duplex
    #: worm set to minimum play), 100 N m s/rad (oil film)
    work_drive: DriveStage = field(default_factory=lambda: DriveStage(1 / 90, 5.0e5, 4 * ARCSEC, 100.0))

    # ---- tool head H: cutter head with its cutting elements on a spindle, gear stage from servo motor MH -------
    head_inertia: float = 0.15  # kg m^2: 250 mm steel cutter head 40 mm thick (0.12) + spindle and gear (0.03)
    head_mass: float = 45.0  # kg: spindle, head and the spindle's bearing housing (what the eccentric carries)
    element_mass: float = 0.15  # kg: one cutting element with its cartridge, at radius R (added per element)
    head_friction: float = 1.0  # N m: spindle bearings (in the eccentric sleeve, on the relative rotation)
    h_motor_inertia: float = 2.0e-3  # kg m^2: 15 N m class AC servo motor rotor
    h_motor_torque: float = 30.0  # N m: MH peak
    #: MH -> head: 1:6 spur stage and Oldham coupling, 3e4 N m/rad at the head (gear mesh, shafts, coupling),
    #: 10 arcsec backlash (precision ground gears), 8 N m s/rad (oil film; zeta ~ 0.1)
    head_drive: DriveStage = field(default_factory=lambda: DriveStage(1 / 6, 3.0e4, 10 * ARCSEC, 8.0))
    #: rad/s: the head's top speed, 500 rpm: the 15 N m class servo MH's 3000 rpm through the 1:6 stage
    head_speed_limit: float = 52.4
    #: m: the largest coupling the 320 mm table takes (couplings of 80-200 mm)
    workpiece_diameter_limit: float = 0.2

    # ---- eccentric E (control "eccentric"): the sleeve carrying the head spindle, gear stage from ME ----------
    eccentric_inertia: float = 0.08  # kg m^2: 160 mm steel sleeve with its counterweight, about its centre of mass
    eccentric_mass: float = 25.0  # kg: sleeve and counterweight
    #: share of the head's mass e balanced by the counterweight (1: the combined centre of mass on the eccentric's
    #: axis, so no gravity torque on E and no shaking force on the slide as the head circles)
    eccentric_balance: float = 1.0
    eccentric_friction: float = 0.8  # N m: the sleeve's bearings
    e_motor_inertia: float = 1.0e-3  # kg m^2: 6 N m class AC servo motor rotor
    e_motor_torque: float = 12.0  # N m: ME peak
    #: ME -> eccentric: 1:5 spur stage, 4e4 N m/rad at the eccentric, 10 arcsec backlash, 10 N m s/rad
    eccentric_drive: DriveStage = field(default_factory=lambda: DriveStage(1 / 5, 4.0e4, 10 * ARCSEC, 10.0))

    # ---- infeed slide Z: vertical slide with swivel, eccentric and head; ball screw TZ from servo motor MZ ------
    slide_mass: float = 180.0  # kg: the slide on the column's guides
    swivel_mass: float = 60.0  # kg: the swivel housing with the spindle's (or the sleeve's) bearing seat
    ways_friction: float = 150.0  # N: preloaded roller guides
    #: share of the slide's whole weight carried by the hydraulic counterbalance; the rest keeps the nut on one flank
    counterbalance: float = 0.85
    screw_pitch: float = 0.005  # m: 32 mm ball screw, 5 mm pitch (a fine infeed)
    screw_inertia: float = 1.2e-3  # kg m^2: the screw, 1 m long
    z_motor_inertia: float = 1.0e-3  # kg m^2
    z_motor_torque: float = 15.0  # N m: MZ peak
    #: MZ -> screw: bellows coupling 1:1, 3e3 N m/rad at the screw (coupling and screw shaft twist), 0.5 N m s/rad
    z_drive: DriveStage = field(default_factory=lambda: DriveStage(1.0, 3.0e3, 0.0, 0.5))
    #: screw -> slide: 3e8 N/m axial (screw, nut, thrust bearings), 2 um play (a single nut, light preload)
    nut_stiffness: float | None = 3.0e8  # N/m; None = rigid
    nut_backlash: float = 2.0e-6  # m
    nut_damping: float = 2.0e4  # N s/m

    # ---- cross slide Y (control "work_setting"): the work spindle on a slide along the tool axis, ball screw ---
    cross_slide_mass: float = 140.0  # kg: the slide itself on its guides (the table, blank and motor MA ride on it)
    cross_ways_friction: float = 100.0  # N: preloaded roller guides
    y_motor_inertia: float = 1.6e-3  # kg m^2: 12 N m class AC servo rotor (1.0e-3) + 32 mm screw 0.6 m (0.6e-3)
    y_motor_torque: float = 12.0  # N m: MY peak
    #: MY -> slide: 10 mm pitch ball screw with a preloaded double nut (no play: the slide reverses every cycle),
    #: 2e8 N/m axial (screw, nut, fixed bearing), 2e4 N s/m
    y_drive: DriveStage = field(default_factory=lambda: DriveStage(0.010 / (2 * math.pi), 2.0e8, 0.0, 2.0e4))

    # ---- simulation ----------------------------------------------------------------------------------------
    timestep: float = 2.5e-4  # s: 4 kHz physics, two sub-steps of the 2 kHz servo; the stages keep omega h < 0.5
    #: RK4: the cyclic ratio varies the work's speed, and first-order integrators shift positions by (h/2) dw (library
    #: notes A6: 12 arcsec at the work here, 4 um at the slot); RK4 leaves 0.2 arcsec at 1.7x the cost. Stable for
    #: the stages' omega h < 2.8 (explicit springs and damping)
    integrator: str = "RK4"

    def problems(self) -> list[str]:
        out = common_problems(
            self,
            (
                "table_inertia",
                "table_mass",
                "a_motor_inertia",
                "a_motor_torque",
                "head_inertia",
                "head_mass",
                "h_motor_inertia",
                "h_motor_torque",
                "head_speed_limit",
                "workpiece_diameter_limit",
                "eccentric_inertia",
                "eccentric_mass",
                "e_motor_inertia",
                "e_motor_torque",
                "slide_mass",
                "swivel_mass",
                "screw_pitch",
                "screw_inertia",
                "z_motor_inertia",
                "z_motor_torque",
                "cross_slide_mass",
                "y_motor_inertia",
                "y_motor_torque",
            ),
        )
        if not 0 <= self.eccentric_balance <= 1.5:
            out.append(f"eccentric_balance = {self.eccentric_balance}: must be between 0 and 1.5 (1 = balanced)")
        return out

    def stiff(self) -> FaceMachineParams:
        """The ideal machine: every stage rigid and free of backlash, no friction (for the proofs)."""
        return rigid(
            self,
            work_friction=0.0,
            head_friction=0.0,
            eccentric_friction=0.0,
            ways_friction=0.0,
            cross_ways_friction=0.0,
        )

    def with_overrides(self, values: dict[str, Any]) -> FaceMachineParams:
        return override(self, values)


@dataclass(frozen=True)
class FaceMachineLayout:
    """What the coupling and its setting sheet fix in the machine (metres, radians): the slotted face
    (``inner_radius``..``outer_radius``), the m slots, M's radius L, the tool radius R to the tips, the setting angle
    lambda, the eccentricity e and the eccentric's ratio N (``eccentric``: the machine has the eccentric), the
    elements' phases beta_j, height and tip edge width, the blank's thickness (for its mass), the slide's home
    ``home_z`` (Z at the home keyframe: the tip this far above the face) and ``work_setting``: the work on the cross
    slide Y (its setting changed during the cut). Numbers only:
    ``virtual_machine.setting.machine_layout.face_layout`` builds it from a coupling."""

    m: int
    L: float
    R: float
    setting_angle: float
    inner_radius: float
    outer_radius: float
    eccentric: bool = False
    e: float = 0.0
    eccentric_ratio: int = 4
    element_phases: tuple[float, ...] = (0.0,)
    element_height: float = 5 * MM
    edge_width: float = 2 * MM
    blank_thickness: float = 20 * MM
    home_z: float = 5 * MM
    work_setting: bool = False

    def problems(self) -> list[str]:
        out = []
        if not (isinstance(self.m, int | np.integer) and self.m >= 2):
            out.append(f"m = {self.m}: must be an integer >= 2")
        for name in ("L", "R", "inner_radius", "outer_radius", "element_height", "edge_width", "blank_thickness"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                out.append(f"{name} = {v}: must be > 0 [m]")
        if not self.outer_radius > self.inner_radius:
            out.append(f"outer_radius = {self.outer_radius}: must exceed inner_radius = {self.inner_radius}")
        if not 0 <= self.setting_angle < math.pi / 2:
            out.append(f"setting_angle = {self.setting_angle}: must be in [0, pi/2) rad")
        if not (math.isfinite(self.e) and self.e >= 0):
            out.append(f"e = {self.e}: must be >= 0 [m]")
        if self.e > 0 and not self.eccentric:
            out.append(f"e = {self.e}: an eccentricity needs the eccentric (eccentric = True)")
        if not (isinstance(self.eccentric_ratio, int | np.integer) and self.eccentric_ratio >= 2):
            out.append(f"eccentric_ratio = {self.eccentric_ratio}: N must be an integer >= 2")
        if not self.element_phases or not all(math.isfinite(b) for b in self.element_phases):
            out.append(f"element_phases = {self.element_phases}: at least one finite phase [rad]")
        if not self.element_height < self.R:
            out.append(f"element_height = {self.element_height}: must be below R = {self.R}")
        if not math.isfinite(self.home_z):
            out.append(f"home_z = {self.home_z}: must be finite")
        return out


def head_angle_joints(model: mujoco.MjModel) -> tuple[str, ...]:
    """The joints whose sum is the head's absolute angle phi: (H, E) with the eccentric, (H,) without."""
    return ("H", "E") if has_joint(model, "E") else ("H",)


def has_joint(model: mujoco.MjModel, joint: str) -> bool:
    """Whether the model has the joint (the optional axes E and Y)."""
    try:
        model.joint(joint)
    except KeyError:
        return False
    return True


def build_face_machine_spec(layout: FaceMachineLayout, params: FaceMachineParams | None = None) -> mujoco.MjSpec:
    """The MJCF model of the face-contour machine for ``layout``. Raises ValueError naming bad parameters.

    Machine frame: z up along the work axis, the slotted face at z = 0, the point M (radius L, where the cutting speed
    V is radial) on machine +x. The tool head turns in a vertical plane above M; its plane is turned by the setting
    angle lambda from the radial line OM (cutting/face_contour/slots.py: the tool plane's horizontal direction
    u = (cos -lambda, sin -lambda), the tool axis n = (sin lambda, cos lambda)). Bodies and joints:

    - ``cross_slide``   (control "work_setting" only) slide ``Y`` along the tool axis n: the work's setting changed
      during the cut (seed 004), Y = T (1 - cos q_s phi) moves the work's axis across the tool plane; it carries the
      work spindle and its motor;
    - ``work_spindle``  hinge ``A`` about -z: table, fixture and blank; A is the seed's workpiece angle a (the
      workpiece frame turns by -a in the machine, so the head advances by +a in it, as in eq. 5). Site
      ``blank_frame`` = the workpiece frame of cutting/face_contour/slots.py (axis z, slotted face at z = 0, slot k's
      centre line at 2 pi k / m);
    - ``infeed_slide``  slide ``Z`` (vertical, on the column): Z = - the seed's feed term (S per tool revolution down
      to the depth); Z = 0 puts the tip of an element at psi = 0 on the face (with the eccentric at its start);
    - ``swivel``        welded to the slide, turned by -lambda about z (the fixed swivel of the setting angle);
    - ``eccentric``     (control "eccentric" only) hinge ``E`` about -n through the eccentric's axis O, R - e above
      the tip's lowest point: a sleeve that carries the head spindle's bearing at the eccentricity e (seed 004
      eq. 14); at E = 0 the head centre is e above O (eq. 14's start, the eccentric at 180 deg). A counterweight on
      the sleeve balances ``eccentric_balance`` of the head's mass (why a hinge: :func:`_add_tool_head`);
    - ``tool_head``     hinge ``H`` about -n (on the eccentric, else on the swivel): the cutter head with its cutting
      elements. Its absolute angle phi = H + E (= H without the eccentric) is the seed's head angle; element j's tip
      is at R (sin(phi + beta_j) u - cos(phi + beta_j) z) from the head centre. Site ``element_frame`` at element
      0's tip (``element_frame_<j>`` at element j's): its x axis the tool axis n (along the tip edge), its z axis
      from the head centre to the tip.

    Drives (each a :func:`machine_models.drives.couple` tendon; motors are torque actuators of the same names, ctrl
    in N m, ctrlrange = peak torque): ``MA`` -> worm ``work_drive`` -> A; ``MH`` -> gear stage ``head_drive`` -> the
    head's absolute angle H + E (an Oldham coupling passes the absolute angle across the offset e); ``ME`` -> gear
    stage ``eccentric_drive`` -> E; ``MZ`` -> ``z_drive`` -> screw ``TZ`` -> nut ``z_nut`` (ratio pitch / 2 pi) -> Z;
    ``MY`` -> ``y_drive`` (ball screw and preloaded double nut, ratio pitch / 2 pi) -> Y. A hydraulic counterbalance
    (``counterbalance`` of the slide's whole weight) acts on the slide only.
    """
    params = params or FaceMachineParams()
    problems = layout.problems() + params.problems()
    if problems:
        raise ValueError("invalid face-contour machine parameters: " + "; ".join(problems))
    spec = machine_spec("face_contour_machine", params.timestep, params.integrator, (0.0, 0.0, -9.81))
    world = spec.worldbody
    world.add_light(pos=[0.2, -1.0, 1.5], dir=[0, 0.6, -1], diffuse=[0.8, 0.8, 0.8])
    thick = layout.blank_thickness
    visual(world, _BOX, (0.4, 0.3, 0.04), DARK, pos=(0.1, 0, -thick - 0.2))  # bed
    visual(world, _BOX, (0.12, 0.25, 0.5), GREY, pos=(layout.L + 0.45, 0, 0.3))  # column
    _add_work_spindle(spec, layout, params)
    zs, swivel = _add_infeed_slide(world, layout, params)
    _add_tool_head(swivel, layout, params)
    _add_head_drives(spec, swivel, layout, params)
    _add_infeed_drive(spec, zs, layout, params)
    if layout.work_setting:
        y_motor = world.add_body(name="y_motor", pos=[-0.35, 0.3, -thick - 0.1])
        motor(spec, y_motor, "MY", params.y_motor_inertia, params.y_motor_torque)
        couple(spec, "y_drive", "Y", "MY", params.y_drive)

    home = {"A": 0.0, "H": 0.0, "Z": layout.home_z} | ({"E": 0.0} if layout.eccentric else {})
    home |= {"Y": 0.0} if layout.work_setting else {}
    spec.add_key(name="home", qpos=relaxed_qpos(spec.compile(), home).tolist())
    return spec


def _head_mass(layout: FaceMachineLayout, params: FaceMachineParams) -> float:
    """Mass of the tool head with its cutting elements [kg] (what the eccentric carries)."""
    return params.head_mass + len(layout.element_phases) * params.element_mass


def _add_work_spindle(spec: mujoco.MjSpec, layout: FaceMachineLayout, params: FaceMachineParams) -> None:
    """The work spindle A with table, fixture and blank (site ``blank_frame``), on the cross slide Y with the work
    setting, and its motor MA with the worm."""
    r_in, r_out, thick = layout.inner_radius, layout.outer_radius, layout.blank_thickness
    base = spec.worldbody
    if layout.work_setting:
        n_tool = [math.sin(layout.setting_angle), math.cos(layout.setting_angle), 0.0]  # the tool axis n
        base = base.add_body(name="cross_slide")
        inertial(base, params.cross_slide_mass, 8.0, 8.0)
        base.add_joint(name="Y", type=_SLIDE, axis=n_tool, frictionloss=params.cross_ways_friction)
        visual(base, _BOX, (0.2, 0.2, 0.02), BLUE, pos=(0, 0, -thick - 0.1))
    table = base.add_body(name="work_spindle")
    blank_mass = STEEL * math.pi * (r_out**2 - r_in**2) * thick
    blank_inertia = blank_mass * (r_out**2 + r_in**2) / 2
    inertial(table, params.table_mass + blank_mass, params.table_inertia + blank_inertia)
    table.add_joint(name="A", type=_HINGE, axis=[0, 0, -1], frictionloss=params.work_friction)
    visual(table, _CYL, (0.16, 0.03), GREY, pos=(0, 0, -thick - 0.05))  # table
    visual(table, _CYL, (r_out, thick / 2), STEELC, pos=(0, 0, -thick / 2))  # blank
    visual(table, _BOX, ((r_out - r_in) / 2, 0.001, 0.001), ORANGE, pos=((r_out + r_in) / 2, 0, 0))  # slot 0 mark
    table.add_site(name="blank_frame", size=[0.002, 0.002, 0.002])
    a_motor = base.add_body(name="a_motor", pos=[-0.25, -0.2, -thick - 0.05])
    motor(spec, a_motor, "MA", params.a_motor_inertia, params.a_motor_torque)
    couple(spec, "work_drive", "A", "MA", params.work_drive)


def _add_infeed_slide(
    world: mujoco.MjsBody, layout: FaceMachineLayout, params: FaceMachineParams
) -> tuple[mujoco.MjsBody, mujoco.MjsBody]:
    """The infeed slide Z on the column and on it the swivel, turned by the setting angle: (slide, swivel)."""
    zs = world.add_body(name="infeed_slide", pos=[layout.L, 0.0, 0.0])
    inertial(zs, params.slide_mass, 15.0, 15.0)
    zs.add_joint(name="Z", type=_SLIDE, axis=[0, 0, 1], frictionloss=params.ways_friction)
    visual(zs, _BOX, (0.06, 0.2, 0.15), BLUE, pos=(0.3, 0, layout.R))
    swivel = zs.add_body(name="swivel", pos=[0.0, 0.0, layout.R - layout.e], quat=quat_z(-layout.setting_angle))
    inertial(swivel, params.swivel_mass, 1.0, 1.0)
    visual(swivel, _BOX, (0.05, 0.06, 0.05), BLUE, pos=(0, -0.09, 0))  # the bearing seat behind the head
    return zs, swivel


def _add_tool_head(swivel: mujoco.MjsBody, layout: FaceMachineLayout, params: FaceMachineParams) -> None:
    """The tool head H with its cutting elements: on the eccentric E (with its counterweight) if the machine has
    one, else on the swivel.

    Why a hinge for the eccentric rather than two slides: the seed's eccentric is a rotating crank geared N times to the
    head (the head centre moves on a circle of radius e at constant speed), so its physics is a rotor's: a constant
    speed with no reversal (its stage stays on one flank; two slides would each reverse twice per eccentric turn and
    cross their backlash each time), an unbalance that a counterweight can cancel (two slides shake the machine with
    their masses' accelerations instead), and a phase error that moves the head centre along the circle.
    """
    R, e = layout.R, layout.e
    # local frame of the rotating parts: z = -n (their axis), x = u, y = up
    rotor_quat = quat_x(math.pi / 2)
    elements = len(layout.element_phases)
    if layout.eccentric:
        ecc = swivel.add_body(name="eccentric", quat=rotor_quat)
        inertial(ecc, params.eccentric_mass, params.eccentric_inertia)
        carried = _head_mass(layout, params)
        ecc.ipos = [0.0, -params.eccentric_balance * carried * e / params.eccentric_mass, 0.0]  # the counterweight
        ecc.add_joint(name="E", type=_HINGE, axis=[0, 0, 1], frictionloss=params.eccentric_friction)
        visual(ecc, _CYL, (0.08, 0.02), GREY, pos=(0, 0, 0.05))
        visual(ecc, _BOX, (0.004, 0.04, 0.021), ORANGE, pos=(0, 0.04, 0.05))  # the eccentric's angle mark
        head = ecc.add_body(name="tool_head", pos=[0.0, e, 0.0])
    else:
        head = swivel.add_body(name="tool_head", quat=rotor_quat)
    inertial(head, _head_mass(layout, params), params.head_inertia + elements * params.element_mass * R**2)
    head.add_joint(name="H", type=_HINGE, axis=[0, 0, 1], frictionloss=params.head_friction)
    visual(head, _CYL, (R - layout.element_height, 0.02), ORANGE)  # head body
    visual(head, _CYL, (0.03, 0.06), STEELC, pos=(0, 0, 0.07))  # spindle nose
    _add_cutting_elements(head, layout)


def _add_cutting_elements(head: mujoco.MjsBody, layout: FaceMachineLayout) -> None:
    """Each cutting element on the head: its plate, and its tip's site ``element_frame`` (``element_frame_<j>``)."""
    R = layout.R
    for j, beta in enumerate(layout.element_phases):
        rho = np.array([math.sin(beta), -math.cos(beta), 0.0])  # from the centre to the tip at phi = 0
        mid = (R - layout.element_height / 2) * rho
        plate = (layout.element_height / 2, 0.004, layout.edge_width / 2)  # along rho, across, along the edge
        visual(head, _BOX, plate, DARK, pos=mid, quat=quat_z(beta - math.pi / 2))
        # site frame: x = tool axis n (= -local z), z = rho, y = z x x
        x, z = np.array([0.0, 0.0, -1.0]), rho
        mat = np.column_stack((x, np.cross(z, x), z))
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, mat.ravel())
        name = "element_frame" if j == 0 else f"element_frame_{j}"
        head.add_site(name=name, pos=(R * rho).tolist(), quat=quat.tolist(), size=[0.002, 0.002, 0.002])


def _add_head_drives(
    spec: mujoco.MjSpec, swivel: mujoco.MjsBody, layout: FaceMachineLayout, params: FaceMachineParams
) -> None:
    """Motor MH and its stage to the head; with the eccentric, motor ME and its stage, MH then driving H + E."""
    rotor_quat = quat_x(math.pi / 2)
    h_motor = swivel.add_body(name="h_motor", pos=[0.0, -0.25, 0.0], quat=rotor_quat)
    motor(spec, h_motor, "MH", params.h_motor_inertia, params.h_motor_torque)
    if layout.eccentric:
        e_motor = swivel.add_body(name="e_motor", pos=[0.12, -0.2, 0.0], quat=rotor_quat)
        motor(spec, e_motor, "ME", params.e_motor_inertia, params.e_motor_torque)
        couple(spec, "eccentric_drive", "E", "ME", params.eccentric_drive)
        stage = params.head_drive
        couple_linear(spec, "head_drive", [("H", 1.0), ("E", 1.0), ("MH", -stage.ratio)], stage)
    else:
        couple(spec, "head_drive", "H", "MH", params.head_drive)


def _add_infeed_drive(
    spec: mujoco.MjSpec, zs: mujoco.MjsBody, layout: FaceMachineLayout, params: FaceMachineParams
) -> None:
    """The ball screw TZ and motor MZ on the column, the nut driving the slide ``zs``, and the counterbalance that
    carries the slide's whole weight (a force on the slide, not on the rotors)."""
    world, R = spec.worldbody, layout.R
    screw = world.add_body(name="z_screw", pos=[layout.L + 0.3, 0.15, R])
    inertial(screw, 6.0, params.screw_inertia, 0.5)
    screw.add_joint(name="TZ", type=_HINGE, axis=[0, 0, 1])
    visual(screw, _CYL, (0.016, 0.3), STEELC)
    z_motor = world.add_body(name="z_motor", pos=[layout.L + 0.3, 0.15, R + 0.38])
    motor(spec, z_motor, "MZ", params.z_motor_inertia, params.z_motor_torque)
    couple(spec, "z_drive", "TZ", "MZ", params.z_drive)
    nut = DriveStage(params.screw_pitch / (2 * math.pi), params.nut_stiffness, params.nut_backlash, params.nut_damping)
    couple(spec, "z_nut", "Z", "TZ", nut)
    riding = params.slide_mass + params.swivel_mass + _head_mass(layout, params) + MOTOR_MASS
    if layout.eccentric:
        riding += params.eccentric_mass + MOTOR_MASS
    zs.gravcomp = params.counterbalance * riding / params.slide_mass


#: each drive's tendon and the joint it solves for when relaxed (in this order: the screw before its motor)
DRIVES = (
    ("work_drive", "MA"),
    ("eccentric_drive", "ME"),
    ("head_drive", "MH"),
    ("z_nut", "TZ"),
    ("z_drive", "MZ"),
    ("y_drive", "MY"),
)


def relaxed_qpos(model: mujoco.MjModel, axes: dict[str, float]) -> np.ndarray:
    """qpos with the machine's axes (``A``, ``H``, ``E``, ``Z``, ``Y`` as given; the others 0) and every stage relaxed
    (tendon lengths zero): each motor, and the screw, from what it drives."""
    q = np.zeros(model.nq)
    adr = {model.joint(j).name: int(model.joint(j).qposadr[0]) for j in range(model.njnt)}
    for name, value in axes.items():
        q[adr[name]] = value
    for tendon, driver in DRIVES:
        if driver not in adr:
            continue
        coef = tendon_coefs(model, tendon)
        rest = sum(c * q[adr[j]] for j, c in coef.items() if j != driver)
        q[adr[driver]] = -rest / coef[driver]
    return q


def build_face_machine(layout: FaceMachineLayout, params: FaceMachineParams | None = None) -> mujoco.MjModel:
    return build_face_machine_spec(layout, params).compile()


def stage_omega_h(layout: FaceMachineLayout, params: FaceMachineParams) -> dict[str, float]:
    """omega * h of every compliant stage's local mode (explicit springs: unstable beyond 2, inaccurate beyond
    ~0.5), keyed by the parameter to change (``nut_stiffness`` for the nut, the stage's name otherwise)."""
    p, h = params, params.timestep
    out: dict[str, float] = {}
    blank = STEEL * math.pi * (layout.outer_radius**4 - layout.inner_radius**4) * layout.blank_thickness / 2
    n = len(layout.element_phases)
    head = p.head_inertia + n * p.element_mass * layout.R**2
    carried = (p.head_mass + n * p.element_mass) * layout.e  # the head's mass moment on the eccentric
    ecc = p.eccentric_inertia + carried * layout.e + (p.eccentric_balance * carried) ** 2 / p.eccentric_mass

    def put(name: str, stage: DriveStage, driven: float, motor_inertia: float) -> None:
        if stage.stiffness is not None:
            w = 2 * math.pi * stage_frequency(stage.stiffness, driven, motor_inertia, stage.ratio)
            out[name] = max(out.get(name, 0.0), w * h)

    put("work_drive", p.work_drive, p.table_inertia + blank, p.a_motor_inertia)
    put("head_drive", p.head_drive, head, p.h_motor_inertia)
    if layout.eccentric:
        put("eccentric_drive", p.eccentric_drive, ecc, p.e_motor_inertia)
    lead = p.screw_pitch / (2 * math.pi)
    k_nut = (p.nut_stiffness or 0.0) * lead**2
    if p.z_drive.stiffness is not None:
        out["z_drive"] = math.sqrt((p.z_drive.stiffness + k_nut) / p.screw_inertia) * h
    riding = p.slide_mass + p.swivel_mass + p.head_mass + n * p.element_mass + MOTOR_MASS
    if layout.eccentric:
        riding += p.eccentric_mass + MOTOR_MASS
    put("nut_stiffness", DriveStage(lead, p.nut_stiffness), riding, p.screw_inertia)
    if layout.work_setting:
        carried = (
            p.cross_slide_mass
            + p.table_mass
            + STEEL * math.pi * (layout.outer_radius**2 - layout.inner_radius**2) * layout.blank_thickness
            + MOTOR_MASS
        )
        put("y_drive", p.y_drive, carried, p.y_motor_inertia)
    return out
