"""Form milling by the copying method (seed 003) as `skive setup`, `skive cut` and `skive run` do it.

- :func:`plan_job`: the seed's 15 steps for the job's design (:func:`cutting.form_milling.copying_path.plan_copying`).
- :func:`cut_form_job` (`skive cut`): the ideal machine follows the planned path exactly.
- :func:`run_form_job` (`skive run`): the simulated form-milling machine (MuJoCo, its CNC) follows it; the poses
  it really made are what cuts. The accuracy check is repeated on what the machine cut (space 0 and its
  neighbours) and the path corrected, up to ``process.machine_iterations`` runs; the last run is the gear.

Either way the gear is the blank minus the mill's swept volumes: gear.stl from manifold3d, space after space,
and the measurement on the exact swept surface of the same passes (:class:`cutting.form_milling.sweep.MilledGear`),
with gear.stl measured beside it.
"""

from __future__ import annotations

import hashlib
import html
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from cutting.errors import InputError, Problem, UnmeasurableError
from cutting.flank import SIDES, twist_rate
from cutting.form_milling.copying_path import (
    CHECK_TOLERANCE,
    CopyingPlan,
    FlankPath,
    accuracy_check,
    correction_from_residual,
    plan_copying,
)
from cutting.form_milling.finger import FingerPlan, finger_check, pass_length, path_point, plan_finger
from cutting.form_milling.forces import FingerLoad, MillLoad
from cutting.form_milling.helical import set_over
from cutting.form_milling.mill import to_space
from cutting.form_milling.removal import cut_gear
from cutting.form_milling.sweep import MilledGear, MillPassPoses
from cutting.gear import form_roll_length
from cutting.gear_file import write_gear_stl
from cutting.materials import material
from cutting.modification import roll
from metrology.charts import write_charts
from metrology.cut_measurement import compare, unmeasured_mesh
from metrology.datum import check_mesh
from metrology.measure import MeasureOptions, measure_gear
from virtual_machine.job import Job, flatten_model
from virtual_machine.output.json_file import write_json

Stage = Callable[[str], None]
CHECK_POINTS = 11


def is_finger(job: Job) -> bool:
    """Whether the job's mill is the finger mill (``mill.type = "finger"``)."""
    return (job.mill or {}).get("type", "disc") == "finger"


def plan_job(job: Job, checks: int = 3) -> CopyingPlan | FingerPlan:
    """The seed's 15 steps for the job (``checks`` rounds of the accuracy check on the ideal machine): the disc
    mill's (:func:`plan_copying`) or the finger mill's (:func:`cutting.form_milling.finger.plan_finger`)."""
    from virtual_machine.reach.form_mill import check_form_reach

    check_form_reach(job, machine_params(job))  # before a path of that size is planned
    m, p = job.mill, job.process
    common = {"checks": checks, "check_points": CHECK_POINTS, "path_form": p.path_form}
    try:
        if is_finger(job):
            return plan_finger(job.gear, job.modification, m["clearance"], p.path_points, m["teeth"], **common)
        return plan_copying(
            job.gear,
            job.modification,
            m["diameter"],
            m["clearance"],
            p.path_points,
            m["teeth"],
            turned=p.mill_axis == "turned",
            **common,
        )
    except ValueError as exc:  # the mill the design asks for cannot be made (no periphery, no tip, an undercut edge)
        raise InputError(
            Problem("mill", m, str(exc), "change mill.clearance or the [modification]"), job.source
        ) from exc


def format_finger_plan(plan: FingerPlan) -> str:
    """The setting sheet of the copying method with the finger mill: mill, path points, corrections, iterations."""
    s = plan.summary()
    mill = s["mill"]
    half = pass_length(plan.gear, plan.mill)
    lines = [
        "COPYING METHOD (seed 003): profiled finger mill, one pass per flank",
        f"  mill: diameter {mill['diameter_mm']:.3f} mm (tip {mill['tip_diameter_mm']:.3f} mm), {mill['teeth']} teeth, "
        f"length {mill['length_mm']:.3f} mm, radius of {len(mill['radius_bezier'])} cubic Bezier segments; clearance "
        f"{plan.clearance:.3f} mm; passes from z = -{half:.2f} to +{half:.2f} mm",
        "  axis along the space's symmetry line ("
        + ("towards the gear axis" if not plan.gear.internal else "out of the ring's bore")
        + "); path: "
        + ("the seed's single cubic Bezier over the face (eq. 17)" if s["path_form"] == "bezier" else "C2 cubic spline")
        + " of the tip centre",
        "  path point   z [mm]   left: x [um]  y [um]   right: x [um]  y [um]   (from the nominal path point)",
    ]
    z = plan.paths["left"].z
    for i in range(len(z)):
        row = f"  {i - len(z) // 2:+10d} {z[i]:8.3f}"
        for side in SIDES:
            x0, y0 = path_point(plan.gear, side, plan.clearance)
            xy = plan.paths[side].at(z[i : i + 1])[0]
            row += f"   {(xy[0] - x0) * 1e3:10.3f} {(xy[1] - y0) * 1e3:7.3f}"
        lines.append(row)
    lines += _iteration_lines(s["iterations"])
    return "\n".join(lines)


def _iteration_lines(iterations: list[dict[str, Any]]) -> list[str]:
    """Steps 11-14 (the path's moves) and step 15 (the accuracy checks) of a plan's summary, a line each."""
    return [
        f"  steps 11-14, iteration {it['iteration']}: path moved {it['path_change_um']:.4f} um"
        if it["step"] == "path"
        else f"  step 15, accuracy check {it['round']}: largest residual {it['max_residual_um']:.3f} um"
        for it in iterations
    ]


def format_plan(plan: CopyingPlan | FingerPlan) -> str:
    """The setting sheet of the copying method: mill, path points, corrections, iterations."""
    if isinstance(plan, FingerPlan):
        return format_finger_plan(plan)
    s = plan.summary()
    mill = s["mill"]
    lines = [
        "COPYING METHOD (seed 003): profiled disc mill, one pass per flank",
        f"  mill: diameter {mill['diameter_mm']:.1f} mm, {mill['teeth']} teeth, width {mill['width_mm']:.3f} mm, "
        f"edge {len(mill['edge_bezier']['left'])} + {len(mill['edge_bezier']['right'])} cubic Bezier segments; "
        f"clearance {plan.clearance:.3f} mm; run-in/out {plan.approach:.2f} mm beyond each face",
        "  sections' RMS thickness deviation from the mean section (eq. 8): "
        f"left {s['section_rms_um']['left']:.2f} um, right {s['section_rms_um']['right']:.2f} um",
    ]
    form = plan.paths["left"].form
    lines.append(
        "  path: "
        + ("the seed's single cubic Bezier over the face (eq. 17)" if form == "bezier" else "C2 cubic spline (eq. 17)")
        + "; mill axis "
        + (
            "turned by the path (eq. 6: head B, table A), psi_x / psi_y up to "
            + ", ".join(
                f"{side} {np.abs(v[:, 0]).max() * 1e3:.2f} / {np.abs(v[:, 1]).max() * 1e3:.2f}"
                for side, v in plan.psi.items()
            )
            + " mrad"
            if plan.turned
            else (
                f"set over at the helix angle ({math.degrees(plan.gear.helix_angle):.1f} deg: head B), its edge the "
                "envelope for the helical space, fixed along the path"
                if plan.gear.helix_angle
                else "fixed (tangential)"
            )
        )
    )
    lines.append("  path point   z [mm]   left: x [um]  y [um]   right: x [um]  y [um]   (from the nominal path point)")
    xn = {"left": -plan.clearance / 2, "right": plan.clearance / 2}
    z = plan.paths["left"].z
    at = {side: plan.paths[side].at(z) for side in SIDES}  # the curve (a fitted Bezier passes near its points)
    for i in range(len(z)):
        row = f"  {i - len(z) // 2:+10d} {z[i]:8.3f}"
        for side in SIDES:
            row += f"   {(at[side][i, 0] - xn[side]) * 1e3:10.3f} {(at[side][i, 1] - plan.gear.root_radius) * 1e3:7.3f}"
        lines.append(row)
    lines += _iteration_lines(s["iterations"])
    return "\n".join(lines)


def format_copying(doc: dict[str, Any]) -> str:
    """What the copying method did: the mill, the accuracy checks and the modification it made."""
    c = doc["copying"]
    mill = c["mill"]
    if mill.get("type") == "finger":
        lines = [
            "",
            "COPYING METHOD (seed 003)  profiled finger mill, one pass per flank",
            f"  mill {mill['diameter_mm']:.3f} mm (tip {mill['tip_diameter_mm']:.3f} mm), length "
            f"{mill['length_mm']:.3f} mm, radius of {len(mill['radius_bezier'])} cubic Bezier segments; "
            f"{len(c['path_points_z_mm'])} path points per pass",
        ]
        return "\n".join(lines + _copying_results(doc))
    lines = [
        "",
        "COPYING METHOD (seed 003)  profiled disc mill, one pass per flank",
        f"  mill {mill['diameter_mm']:.1f} mm, width {mill['width_mm']:.3f} mm, edge of "
        f"{len(mill['edge_bezier']['left'])} + {len(mill['edge_bezier']['right'])} cubic Bezier segments; "
        f"{len(c['path_points_z_mm'])} path points per pass",
    ]
    return "\n".join(lines + _copying_results(doc))


def _copying_results(doc: dict[str, Any]) -> list[str]:
    """The accuracy checks and the modification made (either mill)."""
    c = doc["copying"]
    lines = []
    for it in c["iterations"]:
        if it["step"] != "path":
            lines.append(
                f"  ideal machine, accuracy check {it['round']}: largest residual {it['max_residual_um']:.3f} um"
            )
    for r in c.get("machine_checks", []):
        lines.append(f"  simulated machine, run {r['run']}: largest residual {r['max_residual_um']:.3f} um")
    topo = doc.get("topography") or {}
    for side in SIDES:
        p, h = doc["profile"][side], doc["helix"][side]
        t = topo.get(side, {})
        twist = f", twist {t['twist_um']:.2f} um (design {t['twist_design_um']:.2f})" if "twist_um" in t else ""
        lines.append(
            f"  {side}: C_alpha {p['C_alpha']:.2f} um (design {p['C_alpha_design']:.2f}), C_beta {h['C_beta']:.2f} um "
            f"(design {h['C_beta_design']:.2f}){twist}"
        )
    worst = [float(np.nanmax(np.abs(np.asarray(topo[s]["against_design_um"], float)))) for s in SIDES if s in topo]
    if worst:
        lines.append(f"  topography against the design: largest {max(worst):.2f} um")
    return lines


def _measure(job: Job, exact: MilledGear, stl, stl_path: Path, sweep_error: float) -> dict[str, Any]:
    """The exact swept surface measured, gear.stl beside it (as `skive cut` of a skiving job)."""
    opts = MeasureOptions.from_job(job.measurement, job.modification)
    doc = measure_gear(exact, job.gear, opts, exact.name)
    try:
        mesh = check_mesh(stl.mesh, str(stl_path))
        mesh_doc = measure_gear(mesh, job.gear, opts, str(stl_path))
    except (InputError, UnmeasurableError) as exc:  # the file failed, not the gear: the exact measurement stands
        doc["mesh"] = unmeasured_mesh(str(stl_path), str(exc), len(stl.mesh.faces))
        return doc
    doc["mesh"] = compare(doc, mesh_doc, job.gear, sweep_error, str(stl_path), len(stl.mesh.faces), stl.simplification)
    return doc


def _cut_and_measure(
    job: Job, plan: CopyingPlan | FingerPlan, passes: list[MillPassPoses], out: Path, stage: Stage, name: str
) -> tuple[dict[str, Any], dict[str, Any]]:
    """gear.stl by manifold3d (space after space) and the measurement of the exact swept surface."""
    stage("removal: the mill's swept volumes, space after space (manifold3d)")
    t0 = time.perf_counter()
    tol = job.process.sweep_error
    removal = cut_gear(job.gear, plan.mill, passes, tol)
    seconds_cut = time.perf_counter() - t0
    out.mkdir(parents=True, exist_ok=True)
    stl = write_gear_stl(removal.gear_solid, out / "gear.stl", job.process.stl_tolerance)
    stage("measurement: the exact swept surface and gear.stl")
    t0 = time.perf_counter()
    exact = MilledGear(job.gear, plan.mill, passes, name)
    doc = _measure(job, exact, stl, out / "gear.stl", tol)
    cut = {
        "method": "copying (seed 003)",
        "passes": len(passes),
        "hulls": removal.hulls,
        "sweep_error_um": tol * 1e3,
        "chip_volume_mm3": float(sum(v for _, _, v in removal.chips)),
        "chips": [{"space": k, "flank": s, "volume_mm3": v} for k, s, v in removal.chips],
        "triangles": stl.solid_triangles,
        "gear_stl": stl.summary(),
    }
    return doc, {"cut": cut, "seconds": {"removal": seconds_cut, "measurement": time.perf_counter() - t0}}


def cut_form_job(job: Job, out: Path, stage: Stage | None = None) -> dict[str, Any]:
    """`skive cut` of a form-milling job: the ideal machine on the planned path; writes gear.stl,
    measurement.json and the charts into ``out`` and returns the measurement document."""
    stage = stage or (lambda name: None)
    stage("path of the profiled mill (seed 003: 15 steps, accuracy check on the ideal machine)")
    t0 = time.perf_counter()
    plan = plan_job(job)
    seconds_plan = time.perf_counter() - t0
    doc, facts = _cut_and_measure(job, plan, plan.all_passes(), out, stage, "form-milled gear (ideal machine)")
    doc["copying"] = plan.summary()
    doc["cut"] = {
        **facts["cut"],
        "motion": "ideal: the planned path",
        "seconds": {"plan": seconds_plan, **facts["seconds"]},
    }
    _write(doc, out)
    return doc


# ---- the simulated machine ----------------------------------------------------------------------------------
def machine_layout(job: Job, plan: CopyingPlan):
    """The machine for the job's gear and the planned mill (its radius and width: the mill's mass on the spindle)."""
    from machine_models.form_mill import FormMillLayout
    from machine_models.parts import MM

    g = job.gear
    if isinstance(plan, FingerPlan):
        return FormMillLayout.for_finger(
            g.tip_radius * MM, g.face_width * MM, g.teeth, plan.mill.radius * MM, plan.mill.width * MM, g.internal
        )
    return FormMillLayout.for_gear(
        g.tip_radius * MM, g.face_width * MM, g.teeth, plan.mill.radius * MM, plan.mill.width * MM
    )


def machine_params(job: Job):
    from machine_models.form_mill import FormMillParams

    return FormMillParams().with_overrides(flatten_model(job.machine.model))


def cnc_passes(plan: CopyingPlan) -> list:
    """The passes for the CNC: per space the left pass fed down, the right pass fed up; the path as the mill
    centre (radial, tangential) in the frame where space k faces +x (the machine indexes it there); a turned
    plan's mill also gives its centre's axial position and its axis (:func:`mill_pose_in_cnc_frame`)."""
    from virtual_machine.processes.form_milling.cnc import MillPass

    if isinstance(plan, FingerPlan):
        return finger_cnc_passes(plan)
    half = plan.gear.face_width / 2 + plan.approach
    out = []
    for k in range(plan.gear.teeth):
        for side, (z0, z1) in zip(SIDES, ((half, -half), (-half, half)), strict=True):
            path = plan.paths[side]
            if plan.turned or set_over(plan.gear) != 0.0:

                def centre(z: np.ndarray, side: str = side) -> np.ndarray:
                    return mill_pose_in_cnc_frame(plan, side, z)[0]

                def axis(z: np.ndarray, side: str = side) -> np.ndarray:
                    return mill_pose_in_cnc_frame(plan, side, z)[1]

                out.append(MillPass(k, z0, z1, centre, axis))
                continue

            def fixed(z: np.ndarray, path: FlankPath = path) -> np.ndarray:
                xy = path.at(np.asarray(z, dtype=float))
                return np.column_stack([xy[:, 1] + plan.mill.radius, xy[:, 0]])

            out.append(MillPass(k, z0, z1, fixed))
    return out


def finger_cnc_passes(plan: FingerPlan) -> list:
    """The finger's passes for the CNC (as :func:`cnc_passes`): the tip centre (radial, tangential) in the frame
    where space k faces +x, from the planned path; no axis (the head keeps it along the symmetry line). On a helical
    space the work turns with the helix as the finger feeds (the space's frame at each face position faces +x)."""
    from virtual_machine.processes.form_milling.cnc import MillPass

    half = pass_length(plan.gear, plan.mill)
    rate = twist_rate(plan.gear)
    turn = (lambda z: HELIX_TURN * rate * np.asarray(z, dtype=float)) if rate else None
    out = []
    for k in range(plan.gear.teeth):
        for side, (z0, z1) in zip(SIDES, ((half, -half), (-half, half)), strict=True):

            def tip(z: np.ndarray, path: FlankPath = plan.paths[side]) -> np.ndarray:
                xy = path.at(np.asarray(z, dtype=float))
                return np.column_stack([xy[:, 1], xy[:, 0]])

            out.append(MillPass(k, z0, z1, tip, turn=turn))
    return out


#: the work's turn per unit of the space frame's turn along the face (the CNC's A against cutting's space frame)
HELIX_TURN = -1.0


def mill_pose_in_cnc_frame(plan: CopyingPlan, side: str, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The mill's centre [mm] and unit axis, (N, 3) each, in the CNC's space frame (radial, tangential, axial) at
    path positions ``z`` [mm]: the plan's poses of space 0 (turned by the path, set over on a helical space) in the
    frame of its mid face, which the CNC indexes (a helical space's own frame turns along the face; the CNC keeps
    the axis in the head's plane by turning A, and so follows the helix); its tangential and radial are the CNC's
    y and x."""
    poses = plan.poses_at(0, side, z)
    swap = [1, 0, 2]
    return to_space(plan.gear, 0, poses.centre)[:, swap], to_space(plan.gear, 0, poses.axis)[:, swap]


def mill_load(job: Job, plan: CopyingPlan | FingerPlan) -> MillLoad | FingerLoad:
    """The steady cutting force of each pass (:mod:`cutting.form_milling.forces`) for the job's material and process."""
    p = job.process
    if isinstance(plan, FingerPlan):
        return FingerLoad(job.gear, plan.mill, material(p.material), p.feed, p.mill_speed, plan.clearance)
    return MillLoad(job.gear, plan.mill, material(p.material), p.feed, p.mill_speed, plan.clearance)


def load_of(ml: MillLoad | FingerLoad):
    """The CNC's load callback: pass i of :func:`cnc_passes` is the left pass (fed down) for even i."""

    def load(index: int, z: np.ndarray) -> np.ndarray:
        side = SIDES[index % 2]
        return ml.force(side, z, -1.0 if side == "left" else 1.0)

    return load


def recorded_poses(plan: CopyingPlan, record) -> list[MillPassPoses]:
    """The poses the machine made, per pass, in the gear frame of :mod:`cutting.form_milling.mill` (the CNC's frame has
    space k at 2 pi k / z, ours at 2 pi (k + 1/2) / z: turned by pi / z)."""
    turn = math.pi / plan.gear.teeth
    c, s = math.cos(turn), math.sin(turn)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    out = []
    for i, rec in enumerate(record.passes):
        side = SIDES[i % 2]
        out.append(MillPassPoses(int(record.spaces[i]), side, rec.t, rec.centre @ rot.T, rec.axis @ rot.T))
    return out


def machine_check(plan: CopyingPlan, poses: list[MillPassPoses]) -> tuple[float, dict[str, np.ndarray]]:
    """Step 15 on what the machine cut: space 0's flanks (its passes and its neighbours') against the design."""
    z = plan.gear.teeth
    near = [p for p in poses if p.space in (z - 1, 0, 1)]
    lc = np.linspace(form_roll_length(plan.gear), roll(plan.gear, plan.gear.tip_diameter_value), CHECK_POINTS)
    if isinstance(plan, FingerPlan):
        return finger_check(plan, lc, passes=near)
    return accuracy_check(plan, lc, passes=near)


def run_form_job(
    job: Job,
    path: Path,
    out: Path,
    rrd: Path | None = None,
    progress: Callable[[float], None] | None = None,
    stage: Stage | None = None,
) -> dict[str, Any]:
    """`skive run` of a form-milling job on the simulated machine (see the module docstring)."""
    from virtual_machine.processes.form_milling.cnc import simulate_form_milling

    stage = stage or (lambda name: None)
    durations: dict[str, float] = {}
    t0 = time.perf_counter()
    stage("path of the profiled mill (seed 003: 15 steps, accuracy check on the ideal machine)")
    plan = plan_job(job)
    durations["plan"] = time.perf_counter() - t0
    layout, params = machine_layout(job, plan), machine_params(job)
    p = job.process
    check_motors(job, layout, params, mill_load(job, plan))
    runs = []
    record = poses = None
    lc = np.linspace(form_roll_length(job.gear), roll(job.gear, job.gear.tip_diameter_value), CHECK_POINTS)
    for it in range(p.machine_iterations):
        stage(f"machine: the form-milling machine mills every space, run {it + 1}")
        t0 = time.perf_counter()
        ml = mill_load(job, plan)
        record = simulate_form_milling(
            layout, cnc_passes(plan), params, p.feed, p.mill_speed, progress, load=load_of(ml)
        )
        durations[f"machine run {it + 1}"] = time.perf_counter() - t0
        poses = recorded_poses(plan, record)
        worst, res = machine_check(plan, poses)
        runs.append({"run": it + 1, "max_residual_um": round(worst * 1e3, 4)})
        if worst < CHECK_TOLERANCE or it == p.machine_iterations - 1:
            break
        for side in SIDES:  # step 15 on the machine: correct the path by what it cut
            dx, dy = correction_from_residual(job.gear, side, lc, res[side])
            plan.paths[side] = plan.paths[side].moved(dx, dy)[0]
    doc, facts = _cut_and_measure(job, plan, poses, out, stage, "form-milled gear (simulated machine)")
    durations.update(facts["seconds"])
    doc["copying"] = {**plan.summary(), "machine_checks": runs}
    doc["cut"] = {**facts["cut"], "motion": "the simulated form-milling machine"}
    doc["run"] = _run_facts(job, path, record, durations)
    doc["run"]["forces"] = forces_doc(ml)
    doc["run"]["motor_torque_Nm"] = motor_loads(layout, params, ml)  # the cutting force's share of each motor
    stage("report")
    charts = _write(doc, out)
    _report(out / "report.html", path, doc, charts, plan)
    if rrd is not None:
        stage("recording")
        _record(rrd, job, record, out / "gear.stl", doc, charts)
    return doc


def forces_doc(ml: MillLoad | FingerLoad) -> dict[str, Any]:
    """The cutting force model's figures for measurement.json."""
    out = {
        "material": ml.material.key,
        "kc11": ml.material.kc11,
        "mc": ml.material.mc,
        "model": "steady force of each pass from the section it removes, the oblique model on its teeth "
        "(cutting/form_milling/forces.py, docs/forces.md)",
        "edge_radius_mm": ml.edge_radius,
        "removed_area_mm2": ml.areas,
        "main_force_N": {s: ml.main_force(s) for s in SIDES},
        "thrust_sum_N": {s: ml.load(s).thrust for s in SIDES},
    }
    if isinstance(ml, FingerLoad):
        out["mean_chip_thickness_mm"] = {s: ml.chip_thickness(s) for s in SIDES}
        out["against_feed_N"] = {s: ml.components(s)[0] for s in SIDES}
        out["normal_N"] = {s: ml.components(s)[1] for s in SIDES}
        out["axial_N"] = {s: ml.axial(s) for s in SIDES}
        out["spindle_torque_Nm"] = {s: ml.torque(s) for s in SIDES}
        return out
    return {
        **out,
        "mean_chip_thickness_mm": ml.chip_thickness,
        "thrust_N": {s: ml.components(s)[1] for s in SIDES},
        "axial_thrust_N": {s: ml.components(s)[0] for s in SIDES},
    }


def motor_loads(layout, params, ml: MillLoad | FingerLoad) -> dict[str, float]:
    """The largest steady torque [N m] each motor needs against the cutting force of a pass in full engagement
    (friction and weight aside): a slide's F t / 2 pi through its coupling, the spindle's cutting torque through
    its belt, the table's moment of the tangential force at the root radius through its worm. The disc's thrust
    along its axis and the finger's normal force are tangential (x_s), the disc's radial thrust and the finger's
    axial force radial (y_s)."""
    lead = layout.screw_pitch / (2 * math.pi)
    out = dict.fromkeys(("a", "x", "y", "z", "s"), 0.0)
    for side in SIDES:
        if isinstance(ml, FingerLoad):
            feed, tangential = (abs(f) for f in ml.components(side))  # down milling pulls along the feed
            radial, torque = abs(ml.axial(side)), ml.torque(side)
        else:
            along, radial, feed = ml.components(side)
            tangential, torque = abs(along), feed * ml.mill.radius * 1e-3
        r = ml.gear.root_radius * 1e-3
        need = {
            "x": radial * lead * params.x_drive.ratio,
            "y": tangential * lead * params.y_drive.ratio,
            "z": feed * lead * params.z_drive.ratio,
            "s": torque * params.spindle_drive.ratio,
            "a": tangential * r * params.work_drive.ratio,
        }
        out = {k: max(out[k], v) for k, v in need.items()}
    return out


def check_motors(job: Job, layout, params, ml: MillLoad | FingerLoad) -> None:
    """Refuse the job before the run when a motor's peak torque cannot take the cutting force (InputError naming
    the motor's key and the feed)."""
    need = motor_loads(layout, params, ml)
    problems = [
        Problem(
            f"machine.model.{k}_motor_torque",
            getattr(params, f"{k}_motor_torque"),
            f"the cutting force needs {v:.2f} N m of motor M{k.upper()} (peak "
            f"{getattr(params, f'{k}_motor_torque'):.2f} N m)",
            f"lower process.feed (now {job.process.feed:g} mm/min) or give M{k.upper()} a peak torque above "
            f"{v:.2f} N m",
        )
        for k, v in need.items()
        if v > getattr(params, f"{k}_motor_torque")
    ]
    if problems:
        raise InputError(problems, job.source)


def _run_facts(job: Job, path: Path, record, durations: dict[str, float]) -> dict[str, Any]:
    text = Path(path).read_text()
    steady = [r.deviation()[r.steady] for r in record.passes if r.steady.any()]
    dev = np.vstack(steady) if steady else np.zeros((1, 3))
    return {
        "job": {"path": str(path), "sha256": hashlib.sha256(text.encode()).hexdigest(), "kind": job.kind},
        "seed": None,  # nothing random: the same job gives the same gear
        # the machine and the job's [machine.model] overrides of its parameters
        "machine": {"model": "CNC form-milling machine (machine_models/form_mill.py)", "overrides": job.machine.model},
        "durations_s": {**{k: round(v, 3) for k, v in durations.items()}, "machine": float(record.sim_time)},
        "mill_deviation_um": {  # recorded - commanded mill centre at constant feed, in the space's frame
            axis: {"mean": float(dev[:, i].mean()), "peak_to_peak": float(np.ptp(dev[:, i]))}
            for i, axis in enumerate(("radial", "tangential", "axial"))
        },
        "feed_mm_min": job.process.feed,
        "mill_rpm": job.process.mill_speed,
    }


def _write(doc: dict[str, Any], out: Path) -> list[Path]:
    out.mkdir(parents=True, exist_ok=True)
    charts = write_charts(out / "charts", doc)
    write_json(out / "measurement.json", doc)
    return charts


def _report(page: Path, path: Path, doc: dict[str, Any], charts: list[Path], plan: CopyingPlan | FingerPlan) -> None:
    from virtual_machine.output.formatting import class_table
    from virtual_machine.output.report import html_table, image_tag, write_page

    iso = doc["iso1328"]
    cls = (iso.get("class") or {}).get("overall")
    rows = [[k, left, right, tol, c] for k, left, right, tol, c in class_table(doc)]
    run = doc["run"]
    dev = run["mill_deviation_um"]
    facts = [[k, v] for k, v in run["durations_s"].items()]
    facts += [
        [f"mill {a} deviation mean / p-p [um]", f"{d['mean']:.3f} / {d['peak_to_peak']:.3f}"] for a, d in dev.items()
    ]
    checks = [
        ["ideal machine", it["round"], it["max_residual_um"]]
        for it in doc["copying"]["iterations"]
        if it["step"] != "path"
    ]
    checks += [["simulated machine", r["run"], r["max_residual_um"]] for r in doc["copying"]["machine_checks"]]
    body = [
        f"<h1>skive run: {html.escape(Path(path).name)}</h1>",
        f'<p class="verdict">ISO 1328-1:2013 class of the gear: {cls}</p>',
        f"<p>Form milling by the copying method (seed 003): a profiled {plan.mill.summary().get('type', 'disc')} mill "
        "on the planned spatial path, one pass "
        "per flank, on the simulated form-milling machine. Measured: the exact swept surface of the passes the "
        "machine made, against the design.</p>",
        "<h2>ISO 1328-1 deviations against the design [um]</h2>",
        html_table(["parameter", "left", "right", "tolerance", "class"], rows),
        "<h2>Accuracy check (step 15): largest residual against the design [um]</h2>",
        html_table(["where", "round", "residual [um]"], checks),
        *[image_tag(c) for c in charts],
        "<h2>Run</h2>",
        html_table(["", ""], facts),
        "<h2>Path and mill</h2>",
        f"<pre>{html.escape(format_plan(plan))}</pre>",
        "<h2>Job file</h2>",
        f"<pre>{html.escape(Path(path).read_text())}</pre>",
    ]
    write_page(page, "skive run", body)


def _record(rrd: Path, job: Job, record, stl_path: Path, doc: dict[str, Any], charts: list[Path]) -> None:
    """A Rerun recording: the axes and the encoders' following errors over machine time, the gear, the charts."""
    from virtual_machine.output.recorder import APP_ID, Recorder
    from virtual_machine.processes.base import run_identity

    t = np.asarray(record.trace_t, dtype=float)
    with Recorder(rrd, APP_ID, **run_identity(job)) as rec:
        rec.series("machine/axes", t, record.trace_q[:, :5], ["A [rad]", "X [mm]", "Y [mm]", "Z [mm]", "B [rad]"])
        errors = ["A [arcsec]", "X [um]", "Y [um]", "Z [um]", "B [arcsec]"]
        rec.series("machine/following_error", t, record.trace_error, errors)
        rec.mesh_file("gear", stl_path)
        for c in charts:
            rec.image(f"measurement/{c.stem}", c)
