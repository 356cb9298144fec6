"""The cutting load a skiving job puts on its machine, estimated from the setting sheet before a run, and the check
that the job's machine holds it (its motors' peak torques against the estimate x a margin).

A job whose motors cannot hold its cut is refused as an input error before the run, naming the motor and what would
hold it. The estimate is the co-simulation's force law at the ideal machine: the chip of the moment of every edge
element (cutting.skiving.ideal_moment) and the oblique model's cutting, thrust and passive components at its chip,
working rake and inclination: :func:`pass_loads` per pass (its steps there), :func:`motor_loads` at the motors of
the job's structure, :func:`check_machine_holds` the check. How the estimate compares with the co-simulated peaks,
and the margin that covers it: docs/machines.md ("The cut against the motors").
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from cutting.errors import MachineLimitError, Problem
from cutting.gear import Gear
from cutting.materials import material
from cutting.oblique import ObliqueForces, load_cutting_model
from cutting.skiving.chip_of_the_moment import CHIP, COLUMNS, POWER, VOLUME_RATE, WIDTH
from cutting.skiving.ideal_moment import IdealMoment, chip_constants
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.sweep import place
from machine_models.parameters import SkivingMachineParams, override
from machine_models.sizes import SIZE_NAMES, size_params
from machine_models.structure_drives import MOTOR_TORQUE_KEYS
from virtual_machine.job import Job, flatten_model
from virtual_machine.setting.machine_layout import machine_size

#: the check refuses a job whose estimated peak motor torque x this exceeds the motor's peak torque: the estimate is
#: of the quasi-static load; the co-simulated tool motor's peaks run up to 1.11x above it (chip-to-chip changes,
#: servo ripple)
MARGIN = 1.25

#: the induction motor's breakdown torque over its rated torque (virtual_machine/controllers/motors.py)
BREAKDOWN = 2.5

G = 9.81


@dataclass(frozen=True)
class PassLoad:
    """The estimated load of one pass. Torques are what the spindle's drive must supply [N m] (positive: against
    the cut), at the spindle; forces on the workpiece [N]."""

    index: int
    depth: float  # radial increment of the pass [mm]
    area: float  # removed transverse cross-section of one space, A [mm^2]
    steady_volume: float  # one engagement's chip by the geometry in the steady state, A s [mm^3]
    chip_volume: float  # one engagement's chip by the chip of the moment at mid face, V [mm^3]
    chip_thickness: float  # its mean uncut chip thickness h (the chips' area over the engaged width) [mm]
    kc: float  # the chip's specific energy: one engagement's work over its volume [N/mm^2]
    teeth_in_cut: float  # engagement window over the cutter pitch
    tool_torque_mean: float
    tool_torque_peak: float
    work_torque_mean: float  # signed: negative when the cut drives the work
    work_torque_peak: float  # largest magnitude
    force_peak: float  # largest resultant on the workpiece
    axial_force_peak: float  # largest force along the work axis (on the carriage, through the screw)
    power: float  # mean cutting power [W]


@dataclass(frozen=True)
class MotorLoad:
    """What one motor must hold: the estimate at the motor [N m] (with the spindle's friction) in its worst pass,
    against its peak torque."""

    motor: str  # "M1", "GShD1", ...
    drives: str  # "tool spindle", "work spindle", ...
    key: str  # the [machine.model] parameter of its torque
    torque: float  # estimated peak at the motor [N m]
    limit: float  # the motor's peak torque [N m]
    pass_index: int

    @property
    def holds(self) -> bool:
        return self.torque * MARGIN <= self.limit


def space_area(gear: Gear, delta: float, samples: int = 400) -> float:
    """Transverse area [mm^2] of one tooth space inside the blank's tip circle, cut with the cutter ``delta`` [mm]
    short of its finishing position (the space of the gear with profile shift x + delta / mn)."""
    shifted = dataclasses.replace(
        gear, profile_shift=gear.x + delta / gear.mn, tip_diameter=gear.tip_diameter_value, root_diameter=None
    )
    root = gear.root_radius - delta if gear.internal else gear.root_radius + delta
    lo, hi = sorted((root, gear.tip_radius))
    if hi - lo <= 1e-9:
        return 0.0
    r = np.linspace(lo, hi, samples)
    psi = np.asarray(shifted.half_thickness_angle(np.maximum(r, gear.base_radius * (1 + 1e-9))))
    width = np.clip(r * (2 * math.pi / gear.z - 2 * psi), 0.0, None)
    return float(np.trapezoid(width, r))


def pass_loads(
    setup: SkivingSetup, material_key: str, samples: int = 121, edge_radius: float = 0.010
) -> list[PassLoad]:
    """The estimated load of every pass of ``setup`` cutting ``material_key`` (a row of assets/materials.toml).

    Per pass k:

    1. Removed cross-section (the steady chip's geometry, for the report beside the model's). A tooth space cut with
       the cutter standing delta short of its finishing position is the space of the gear with profile shift
       x2 + delta/mn; its transverse area inside the blank is S(delta) = integral of r (2 pi/z2 - 2 psi(r)) dr from
       its root (r_f + delta; ring gear: r_f - delta) to the tip circle (psi: half the tooth's angular thickness,
       involute, held at its base-circle value below r_b; :func:`space_area`). Pass k removes
       A_k = S(full - d_k) - S(full - d_(k-1)) per space (d_k: cumulative depth, full: the full depth); each space
       is passed once per work revolution while the carriage moves the axial feed s, so in the steady state an
       engagement takes A_k s.
    2. The engagement, by the chip of the moment (:class:`cutting.skiving.ideal_moment.IdealMoment`): one cutter
       tooth turns through the engagement window (the cutter angles at which its edge is within the tip cylinder)
       at the pass's centre distance, the carriage at mid face, by the ideal kinematics, in ``samples`` steps; at
       each, every element of the edge (the involute outline in elements of <= 0.2 mm, as the co-simulation's) takes
       the chip between it and the surface the previous tooth in its space left one work revolution earlier, the
       previous pass's surface or the blank's, and the oblique model's three components at that chip, its working
       rake and inclination (cutting, thrust normal to the cut surface, passive along the edge; ``edge_radius``
       [mm] the cutter's): the co-simulation's force law at the ideal machine. The chip is not spread evenly over
       the engaged edge: the elements near the tip and on the leading flank take most of it, and that decides the
       spindles' torques (docs/machines.md, "The cut against the motors").
    3. Loads. Each element pushes the workpiece (the cutter takes the opposite): a torque about the work axis
       T2(phi) and one about the cutter axis T1(phi). Successive cutter teeth engage a cutter pitch apart and
       overlap (2-6 teeth in the cut on the shipped jobs): the torques of all teeth are summed over one pitch and
       the peak is taken. The chip's volume V_k is the model's over the engagement, its mean thickness the chips'
       area over the engaged width, kc its cutting work over V_k, the mean power kc V_k z0 n0.
    """
    model = ObliqueForces(material(material_key), load_cutting_model(), edge_radius)
    chip = chip_constants(model)
    g = setup.gear
    pitch = 2 * math.pi / setup.cutter.teeth
    depths = (0.0, *setup.pass_depths)
    out, previous = [], None
    for k, a in enumerate(setup.pass_centre_distances):
        area = space_area(g, setup.full_depth - depths[k + 1]) - space_area(g, setup.full_depth - depths[k])
        e = _moment_engagement(IdealMoment(setup, a, previous), chip, samples)
        previous = a
        if e is None or area <= 0 or e.volume <= 0:
            continue
        kc = e.energy * 1e3 / e.volume
        work = np.cross(e.point, e.force)[:, 2] * 1e-3 + e.moment[:, 2]  # the load's torque about +z [N m]
        axis = e.rot[:, :, 2]  # the cutter axis
        tool = -(np.sum(np.cross(e.point - e.centre, e.force) * axis, axis=1) * 1e-3 + np.sum(e.moment * axis, axis=1))
        total = _overlapped(e.phi, pitch, e.half)
        t1, t2 = -total(tool), -total(work) * math.copysign(1.0, setup.speed_ratio)  # what the drives supply
        f = np.stack([total(e.force[:, i]) for i in range(3)], axis=-1)
        out.append(
            PassLoad(
                k,
                setup.passes[k],
                area,
                area * setup.axial_feed,
                e.volume,
                e.thickness,
                kc,
                2 * e.half / pitch,
                float(t1.mean()),
                float(np.abs(t1).max()),
                float(t2.mean()),
                float(np.abs(t2).max()),
                float(np.linalg.norm(f, axis=1).max()),
                float(np.abs(f[:, 2]).max()),
                float(kc * e.volume * setup.cutter.teeth * setup.tool_speed / 60 * 1e-3),
            )
        )
    return out


@dataclass(frozen=True)
class MomentEngagement:
    """One tooth's engagement by the chip of the moment on the ideal machine: the cutter angles ``phi`` (n,) over the
    window +-``half`` [rad], the cutter's pose in the work frame (``rot`` (n, 3, 3), ``centre`` (n, 3) [mm]), the
    load on the workpiece per angle (``force`` [N], its ``point`` [mm], the ``moment`` about it [N m], (n, 3) each,
    in the blank frame), and over the engagement the chip's ``volume`` [mm^3], its mean ``thickness`` [mm] and the
    cutting components' ``energy`` [J]."""

    phi: np.ndarray
    half: float
    rot: np.ndarray
    centre: np.ndarray
    force: np.ndarray
    point: np.ndarray
    moment: np.ndarray
    volume: float
    thickness: float
    energy: float


def _moment_engagement(moment: IdealMoment, chip: np.ndarray, samples: int) -> MomentEngagement | None:
    """The engagement of ``moment`` in ``samples`` steps over its window (None when the edge stays clear of the
    blank)."""
    setup, a = moment.setup, moment.centre_distance
    half = engagement_half_angle_at(setup, moment.points, a)
    if half <= 0:
        return None
    phi = np.linspace(-half, half, samples)
    rows = np.zeros((samples, COLUMNS))
    out = np.zeros((1, COLUMNS))
    for i, b1 in enumerate(phi):
        if moment.load(b1, chip, out):
            rows[i] = out[0]
    t = phi / moment.omega0
    width = rows[:, WIDTH]
    rot, centre = setup.cutter_pose(phi, 0.0, a)
    return MomentEngagement(
        phi,
        half,
        rot,
        centre,
        rows[:, 0:3],
        rows[:, 3:6],
        rows[:, 6:9],
        float(np.trapezoid(rows[:, VOLUME_RATE], t)),
        float((width * rows[:, CHIP]).sum() / width.sum()) if width.sum() > 0 else 0.0,
        float(np.trapezoid(rows[:, POWER], t)),
    )


def engagement_half_angle_at(setup: SkivingSetup, pts: np.ndarray, centre_distance: float) -> float:
    """Cutter rotation from the mesh [rad] beyond which no point of the edge is within the blank's radius."""
    g = setup.gear
    phi = np.linspace(-math.pi, math.pi, 3601)
    w = place(pts, *setup.cutter_pose(phi, 0.0, centre_distance))
    r = np.hypot(w[..., 0], w[..., 1])
    inside = (r > g.tip_radius).any(axis=1) if g.internal else (r < g.tip_radius).any(axis=1)
    return float(np.abs(phi[inside]).max()) + 2 * math.pi / 3600 if inside.any() else 0.0


def _overlapped(phi: np.ndarray, pitch: float, half: float):
    """f(y): the sum over the cutter teeth, a pitch apart, of one engagement's curve y(phi), over one pitch."""
    grid = np.linspace(0.0, pitch, 240, endpoint=False)
    shifts = range(-math.ceil(half / pitch) - 1, math.ceil(half / pitch) + 2)

    def total(y: np.ndarray) -> np.ndarray:
        return sum(np.interp(grid + j * pitch, phi, y, left=0.0, right=0.0) for j in shifts)

    return total


def motor_loads(job: Job, params: SkivingMachineParams, loads: list[PassLoad] | None = None) -> list[MotorLoad]:
    """Every motor of the job's structure with the largest torque the estimate asks of it over the passes.

    Which motor holds which spindle, per structure (power through each chain; the motor's torque = the spindle's
    torque x the spindle's turn per motor turn):

    - mechatronic (S4): M1 tool spindle through tool_drive; M2 work spindle through work_drive; M3 the carriage's
      axial cutting force and its unbalanced weight through the screw;
    - mechanical (S1): the main motor M1 drives the tool through the speed chain and the work through the chains
      behind it: (P_tool + P_work) / omega_M1 against its breakdown torque (2.5 x main_motor_torque);
    - hydraulic-differential (S2): M1 the tool (speed chain); GShD1 and GShD2 the work through the differential;
    - hydraulic-shaft (S3): M1 the work (speed chain); GShD the tool through the generating chain.
    """
    setup = job.skiving
    if loads is None:
        loads = pass_loads(setup, job.process.material, edge_radius=job.cutter_options.edge_radius)
    structure = job.machine.structure
    keys = MOTOR_TORQUE_KEYS[structure]
    p = params
    ratio = abs(setup.speed_ratio)  # work turn per tool turn
    rows: dict[str, list[tuple[str, float, float]]] = {}  # motor -> [(drives, torque at the motor, limit)] per pass

    def add(motor: str, drives: str, per_pass: list[float], limit: float) -> None:
        rows[motor] = [(drives, t, limit) for t in per_pass]

    tool = [ld.tool_torque_peak + p.tool_friction for ld in loads]
    work = [ld.work_torque_peak + p.work_friction for ld in loads]
    if structure == "mechatronic":
        add("M1", "tool spindle", [t * abs(p.tool_drive.ratio) for t in tool], p.tool_motor_torque)
        add("M2", "work spindle", [t * abs(p.work_drive.ratio) for t in work], p.work_motor_torque)
        lead = job.machine.lead_screw_pitch * 1e-3 * (1 + p.lead_screw_pitch_error) / (2 * math.pi)  # m/rad
        weight = (1 - p.counterbalance) * (p.carriage_mass + p.radial_mass) * G + p.ways_friction
        add(
            "M3",
            "carriage",
            [(ld.axial_force_peak + weight) * lead * abs(p.feed_drive.ratio) for ld in loads],
            p.feed_motor_torque,
        )
    else:
        from virtual_machine.setting.chains import chain_ratios

        chains = chain_ratios(job)
        main = BREAKDOWN * p.main_motor_torque
        if structure == "mechanical":  # M1 supplies both spindles' power through the chains
            both = [(t1 + t2 * ratio) * abs(chains.speed) for t1, t2 in zip(tool, work, strict=True)]
            add("M1", "tool and work spindles", both, main)
        elif structure == "hydraulic-differential":
            add("M1", "tool spindle", [t * abs(chains.speed) for t in tool], main)
            add("GShD1", "work spindle", [t * abs(chains.generating) for t in work], p.hydraulic_torque_limit)
            add("GShD2", "work spindle", [t * abs(chains.helix) for t in work], p.hydraulic_torque_limit)
        else:  # hydraulic-shaft: M1 turns the work, the stepping motor the tool
            add("M1", "work spindle", [t * abs(chains.speed) for t in work], main)
            add("GShD", "tool spindle", [t * abs(chains.generating) for t in tool], p.hydraulic_torque_limit)
    out = []
    for motor, per_pass in rows.items():
        k = int(np.argmax([t for _, t, _ in per_pass])) if per_pass else 0
        drives, torque, limit = per_pass[k] if per_pass else ("", 0.0, 0.0)
        out.append(
            MotorLoad(motor, drives, keys.get(motor, ""), float(torque), float(limit), loads[k].index if loads else 0)
        )
    return out


def check_machine_holds(job: Job, params: SkivingMachineParams, margin: float = MARGIN) -> list[MotorLoad]:
    """Refuse (MachineLimitError) a job whose estimated peak torque at a motor, x ``margin``, exceeds that motor's peak
    torque, naming the motor, both torques, and what would hold it: a larger machine size and the motor torque
    that would do. Returns the motors' loads when they all hold."""
    loads = pass_loads(job.skiving, job.process.material, edge_radius=job.cutter_options.edge_radius)
    motors = motor_loads(job, params, loads)
    bad = [m for m in motors if m.torque * margin > m.limit]
    if not bad:
        return motors
    size = machine_size(job)
    chosen = "machine.size" if job.machine.size else "the default size for this gear"
    larger = _larger_size_that_holds(job, size, loads, margin)
    problems = []
    for m in bad:
        ld = next(ld for ld in loads if ld.index == m.pass_index)
        need = math.ceil(m.torque * margin)
        key = f"machine.model.{m.key}"
        also = (
            f'machine.size = "{larger}" ({_torque_of(larger, m.key, job)})'
            if larger
            else "no larger machine size holds it"
        )
        problems.append(
            Problem(
                "machine.size",
                size,
                f"the {m.drives} motor {m.motor} of the {size} machine ({chosen}) cannot hold the cut: pass "
                f"{m.pass_index + 1} ({ld.depth:g} mm) needs an estimated {m.torque:.1f} N m at {m.motor} (peak "
                f"cutting torque {_spindle_torque(m, ld):.1f} N m at the spindle, chip {ld.chip_volume:.2f} mm^3, "
                f"h {ld.chip_thickness * 1e3:.0f} um), x {margin:g} margin = {m.torque * margin:.1f} N m, against its "
                f"{m.limit:.0f} N m ({key})",
                f"use {also}, or {key} >= {need}, or take less per pass (process.passes) or a smaller "
                "process.axial_feed",
            )
        )
    raise MachineLimitError(problems, job.source)


def _spindle_torque(m: MotorLoad, ld: PassLoad) -> float:
    return ld.work_torque_peak if m.drives == "work spindle" else ld.tool_torque_peak


def _torque_of(size: str, key: str, job: Job) -> str:
    params = override(size_params(size), flatten_model(job.machine.model))
    return f"{key} {getattr(params, key):.0f} N m" if key else size


def _larger_size_that_holds(job: Job, size: str, loads: list[PassLoad], margin: float) -> str | None:
    """The next size above ``size`` whose motors (with the job's [machine.model] overrides) hold every pass."""
    model = flatten_model(job.machine.model)
    for name in SIZE_NAMES[SIZE_NAMES.index(size) + 1 :]:
        params = override(size_params(name), model)
        if all(m.torque * margin <= m.limit for m in motor_loads(job, params, loads)):
            return name
    return None
