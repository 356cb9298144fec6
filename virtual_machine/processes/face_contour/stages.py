"""Face tooth contours by continuous indexing (seed 004) as `skive setup`, `skive cut` and `skive run` do them.

- `skive setup`: the setting sheet (setting angle lambda, |V| along the slot, the flat-bottom e, the straight-slot
  ratio amplitude) of :func:`cutting.face_contour.slots.setting_sheet`.
- `skive cut`: the ideal kinematics cut the first ``process.slots_cut`` slots
(:func:`cutting.face_contour.slots.cut_slots`).
- `skive run`: the face-contour machine (MuJoCo, its electronic gearbox) cuts them; the slots are cut from the
  motion it recorded (:mod:`virtual_machine.processes.face_contour.cnc`), under the cutting forces of the job's
  material (:mod:`cutting.face_contour.forces`; a feed the machine's motors cannot cut is refused before the run);
  the forces section of measurement.json gives per slot the layer, F_c and thrust and the drives' twists, and the
  slot spacing with the forces and, on the same machine, without them.

Either way the coupling is measured exactly (from the motion) and on the manifold solid
(:mod:`metrology.face_slots`): slot bottom form (+ concave), side deviations and bows, slot spacing; written to
measurement.json with coupling.stl.
"""

from __future__ import annotations

import hashlib
import html
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from cutting.face_contour.slots import ExactSlots, FaceCoupling, cut_slots, setting_sheet
from metrology.face_slots import measure_mesh, measure_slots, slot_spacing
from virtual_machine.job import Job, flatten_model
from virtual_machine.output.json_file import write_json

UM = 1e3
ARCSEC = math.pi / 180 / 3600


def tool_speed(job: Job) -> float:
    """The head's angular speed [rad/s]."""
    return job.process.tool_speed * 2 * math.pi / 60


def format_setting_sheet(job: Job) -> str:
    c: FaceCoupling = job.coupling
    s = setting_sheet(c, tool_speed(job))
    lines = [
        f"FACE COUPLING (seed 004): {c.m} slots by continuous indexing, control {c.control!r}",
        f"  setting angle lambda = arcsin(L / (R m)) = {s['setting_angle_deg']:.4f} deg (L {c.L:g}, R {c.R:g} mm)",
        f"  cutting speed |V|: inner end {s['V_inner_mm_s'] * 0.06:.1f}, M {s['V_M_mm_s'] * 0.06:.1f}, outer end "
        f"{s['V_outer_mm_s'] * 0.06:.1f} m/min at {job.process.tool_speed:g} rpm; V turns "
        f"{s['V_direction_inner_deg']:+.3f} / {s['V_direction_outer_deg']:+.3f} deg from radial at the ends",
        f"  eccentric: e for a flat slot bottom = {s['flat_bottom_e_mm']:.4f} mm (N = {c.eccentric_ratio})"
        + (f"; set e = {c.e:.4f} mm" if c.eccentric_on else ""),
        f"  cyclic ratio: amplitude for straight slots = {math.degrees(s['straight_slot_amplitude_rad']):.5f} deg "
        f"(q = {c.ratio_cycles})" + (f"; set {math.degrees(c.ratio_amplitude):.5f} deg" if c.cyclic_on else ""),
        f"  work setting: the work's move along the tool axis T (1 - cos q_s phi) for straight slots, T = "
        f"{s['straight_slot_offset_mm'] * UM:.1f} um (q_s = {c.setting_cycles})"
        + (f"; set T = {c.setting_offset * UM:.1f} um" if c.work_setting_on else ""),
        f"  cycle: {s['tool_revolutions']:.0f} tool revolutions (plunge at S = {c.S:g} mm/rev, one workpiece "
        "revolution of spark-out)",
    ]
    return "\n".join(lines)


def measurement(c: FaceCoupling, exact: list, mesh: list | None, cut, tol: float) -> dict[str, Any]:
    """The coupling's measurement: per slot bottom form and side deviations [um], the spacing [arcsec] (exact),
    and the mesh's figures beside them."""

    def slot(m) -> dict[str, Any]:
        return {
            "slot": m.slot,
            "bottom_form_um": m.form * UM,
            "bottom_shape": m.shape,
            "side_bow_um": (m.side_bow * UM).tolist(),
            "side_deviation_um": {"max": float(np.max(np.abs(m.side_deviation)) * UM)},
        }

    doc: dict[str, Any] = {
        "slots": [slot(m) for m in exact],
        "spacing_arcsec": (slot_spacing(c, exact) / ARCSEC).tolist() if len(exact) > 1 else [],
        "bottom_radii_mm": exact[0].radii.tolist(),
        "bottom_z_um": (exact[0].bottom * UM).tolist(),
    }
    if mesh is not None:
        doc["mesh"] = {
            "sweep_error_um": tol * UM,
            "hulls": cut.hulls,
            "slots": [slot(m) for m in mesh],
            "bottom_form_difference_um": float(max(abs(a.form - b.form) for a, b in zip(exact, mesh, strict=True)))
            * UM,
        }
    return doc


def cut_face_job(job: Job, out: Path, stage=None) -> dict[str, Any]:
    """`skive cut`: the ideal kinematics cut and measured; writes coupling.stl and measurement.json."""
    stage = stage or (lambda name: None)
    c: FaceCoupling = job.coupling
    slots = tuple(range(job.process.slots_cut))
    tol = job.process.sweep_error
    stage("cut: the elements' swept volumes (manifold3d)")
    cut = cut_slots(c, slots, tol)
    stage("measurement: exact and on the solid")
    doc = measurement(c, measure_slots(ExactSlots(c), c, slots), measure_mesh(cut, c), cut, tol)
    doc["setting_sheet"] = setting_sheet(c, tool_speed(job))
    doc["cut"] = {"motion": "ideal kinematics", "seconds": cut.seconds, "chord_error_um": cut.chord_error * UM}
    _write(out, doc, cut)
    return doc


def machine_params(job: Job):
    from machine_models.face_contour_machine import FaceMachineParams

    return FaceMachineParams().with_overrides(flatten_model(job.machine.model))


def simulate_face_job(job: Job, progress=None):
    """`skive simulate`: the face-contour machine cuts the slots; the record and its synchronisation figures."""
    from virtual_machine.processes.face_contour.cnc import simulate_face_contour

    slots = tuple(range(job.process.slots_cut))
    load = cutting_load(job)
    record = simulate_face_contour(
        job.coupling,
        machine_params(job),
        slots,
        job.process.tool_speed,
        progress=progress,
        hold_speed=job.process.head_speed == "held",
        load=load,
        master=job.process.master,
    )
    sync = record.trace_sync
    summary = {
        "machine_time_s": float(record.sim_time),
        "wall_time_s": float(record.wall_time),
        "synchronisation_peak_to_peak": {
            "work_arcsec": float(np.ptp(sync[:, 0])),
            "eccentric_arcsec": float(np.ptp(sync[:, 1])) if record.eccentric else None,
            "infeed_um": float(np.ptp(sync[:, 2])),
            "cross_slide_um": float(np.ptp(record.trace_cross[:, 1])) if job.coupling.work_setting_on else None,
        },
        "following_error_peak": {
            axis: float(np.max(np.abs(record.trace_error[:, i])))
            for i, axis in enumerate(("A_arcsec", "H_arcsec", "E_arcsec", "Z_um"))
        }
        | ({"Y_um": float(np.max(np.abs(record.trace_cross[:, 3])))} if job.coupling.work_setting_on else {}),
    }
    summary["cutting_load"] = motor_loads(job, load)
    return record, summary


def cutting_load(job: Job):
    """The cutting forces of the job's elements in its material (:class:`cutting.face_contour.forces.FaceLoad`)
    over the passes' windows (the tip below the face)."""
    from cutting.face_contour.forces import FaceLoad
    from cutting.materials import material
    from virtual_machine.processes.face_contour.cnc import pass_window

    c: FaceCoupling = job.coupling
    return FaceLoad(c, material(job.process.material), pass_window(c, 0.0))


def motor_loads(job: Job, load) -> dict[str, Any]:
    """The motors' torques under the cycle's heaviest pass (the pre-run check's sizing) [N m]."""
    from virtual_machine.reach.face import check_cutting_load

    size = check_cutting_load(job.coupling, load, machine_params(job))
    first = next(iter(size.values()))
    return {
        "heaviest_layer_mm": job.coupling.m * job.coupling.S,
        "F_c_peak_N": first["F_c_N"],
        "thrust_peak_N": first["thrust_N"],
        "motors_N_m": {k: {"needed": v["needed_N_m"], "peak": v["peak_N_m"]} for k, v in size.items()},
    }


def forces_report(job: Job, record, load, slots: tuple[int, ...]) -> dict[str, Any]:
    """The forces section of the run: per recorded slot the layer at M, the mean and peak F_c and thrust over its
    final pass (where the element cuts), the work drive's and the head drive's twists when the tip passes M
    (arcsec, and um at radius L) and the slot shift they make, work twist - head twist / m (the slot k is cut where
    the head's real angle passes 2 pi k, the work then at a = (2 pi k - head twist) / m + work twist), and the whole
    shift, the work's error against the head's real angle then (the twists and the servos' following errors); then
    the slot spacing and the bottom's depth at M measured with the forces and on the same machine without them (a
    second run, cutting air)."""
    from cutting.face_contour.forces import chip
    from cutting.face_contour.slots import workpiece_angle
    from virtual_machine.processes.face_contour.cnc import measure_recorded, simulate_face_contour

    c: FaceCoupling = job.coupling
    rows = []
    for p in record.passes:
        mid = 2 * math.pi * p.turn
        f = load.passes(p.turn)
        fc = np.sum([x.F_c for x in f], axis=0)
        fp = np.sum([x.lift for x in f], axis=0)  # the thrust out of the face: what the infeed carries
        cut = fc > 0
        i = int(np.argmin(np.abs(p.phi - mid)))
        work, head = p.twist[i]
        sync = float(p.a[i] - workpiece_angle(c, p.phi[i]))  # the work's error at the head's real angle: the shift
        rows.append(
            {
                "slot": p.slot,
                "turn": p.turn,
                # the layer at M: the element passing first takes it (the others follow it within the turn)
                "layer_um": max(float(chip(c, mid - b, j).layer) for j, b in enumerate(c.phases)) * UM,
                "F_c_mean_N": float(fc[cut].mean()) if cut.any() else 0.0,
                "F_c_peak_N": float(fc.max()),
                "thrust_mean_N": float(fp[cut].mean()) if cut.any() else 0.0,
                "thrust_peak_N": float(fp.max()),
                "work_drive_twist_arcsec": work / ARCSEC,
                "work_drive_twist_um_at_L": work * c.L * UM,
                "head_drive_twist_arcsec": head / ARCSEC,
                "slot_shift_from_twists_um_at_L": (work - head / c.m) * c.L * UM,
                "sync_at_M_arcsec": sync / ARCSEC,
                "sync_at_M_um_at_L": sync * c.L * UM,
            }
        )
    free = simulate_face_contour(
        c,
        machine_params(job),
        slots,
        job.process.tool_speed,
        hold_speed=job.process.head_speed == "held",
        master=job.process.master,
    )
    with_f, without_f = measure_recorded(record, slots), measure_recorded(free, slots)
    loaded, unloaded = slot_spacing(c, with_f), slot_spacing(c, without_f)
    for row, a, b in zip(rows, with_f, without_f, strict=True):
        deeper = np.interp(c.L, b.radii, b.bottom) - np.interp(c.L, a.radii, a.bottom)
        row["bottom_depth_change_um_at_M"] = float(deeper) * UM  # the bottom at radius L, + deeper with the forces
        row["bottom_form_without_forces_um"] = b.form * UM
    return {
        "model": "the oblique model per edge segment (tip edge, flanks) at its working rake and inclination: F_c "
        "along -V, the thrust off each cut surface, the passive force along the edges; thrust: the force out of the "
        "face (cutting/face_contour/forces.py, docs/forces.md)",
        "material": load.material.key,
        "slots": rows,
        "spacing_with_forces_arcsec": (loaded / ARCSEC).tolist(),
        "spacing_without_forces_arcsec": (unloaded / ARCSEC).tolist(),
        "spacing_change_um_at_L": ((loaded - unloaded) * c.L * UM).tolist(),
        "cutting_load": motor_loads(job, load),
    }


def format_simulation(summary: dict[str, Any]) -> str:
    s = summary["synchronisation_peak_to_peak"]
    ecc = f", eccentric - N phi {s['eccentric_arcsec']:.2f} arcsec" if s["eccentric_arcsec"] is not None else ""
    if s.get("cross_slide_um") is not None:
        ecc += f", cross slide - T (1 - cos q_s phi) {s['cross_slide_um']:.2f} um"
    return (
        "FACE-CONTOUR MACHINE (seed 004): the electronic gearbox's synchronisation, peak to peak: work - a(phi) "
        f"{s['work_arcsec']:.2f} arcsec{ecc}, infeed - z(phi) {s['infeed_um']:.2f} um; "
        f"{summary['machine_time_s']:.2f} s of machine time in {summary['wall_time_s']:.1f} s"
    )


def run_face_job(job: Job, path: Path, out: Path, progress=None, stage=None, rrd: Path | None = None) -> dict[str, Any]:
    """`skive run`: the face-contour machine cuts the slots; they are cut and measured from its recorded motion."""
    from virtual_machine.processes.face_contour.cnc import cut_recorded, measure_recorded

    stage = stage or (lambda name: None)
    c: FaceCoupling = job.coupling
    slots = tuple(range(job.process.slots_cut))
    tol = job.process.sweep_error
    durations = {}
    t0 = time.perf_counter()
    stage("machine: the face-contour machine cuts the slots (electronic gearbox)")
    record, summary = simulate_face_job(job, progress)
    durations["machine"] = time.perf_counter() - t0
    stage("cut and measurement of the recorded motion")
    t0 = time.perf_counter()
    cut = cut_recorded(record, tol)
    doc = measurement(c, measure_recorded(record, slots), measure_mesh(cut, c), cut, tol)
    durations["cut and measurement"] = time.perf_counter() - t0
    stage("cutting forces: the slots again on the machine without them")
    t0 = time.perf_counter()
    doc["forces"] = forces_report(job, record, cutting_load(job), slots)
    durations["machine without forces"] = time.perf_counter() - t0
    ideal = measure_slots(ExactSlots(c), c, slots[:1])[0]
    doc["ideal_bottom_form_um"] = ideal.form * UM
    doc["setting_sheet"] = setting_sheet(c, tool_speed(job))
    text = Path(path).read_text()
    doc["run"] = {
        "job": {"path": str(path), "sha256": hashlib.sha256(text.encode()).hexdigest(), "kind": job.kind},
        "seed": None,
        "durations_s": {**{k: round(v, 3) for k, v in durations.items()}, "machine_time": float(record.sim_time)},
        **{k: summary[k] for k in ("synchronisation_peak_to_peak", "following_error_peak")},
    }
    _write(out, doc, cut)
    _report(out / "report.html", path, doc, job)
    if rrd is not None:
        stage("recording")
        _record(rrd, record, out / "coupling.stl", job)
    return doc


def _record(rrd: Path, record, stl: Path, job: Job) -> None:
    """The axes, the synchronisation errors over machine time and the coupling."""
    from virtual_machine.output.recorder import APP_ID, Recorder
    from virtual_machine.processes.base import run_identity

    t = np.asarray(record.trace_t, dtype=float)
    with Recorder(rrd, APP_ID, **run_identity(job)) as rec:
        rec.series("machine/axes", t, record.trace_q, ["A [rad]", "phi [rad]", "E [rad]", "Z [mm]"])
        rec.series(
            "machine/synchronisation",
            t,
            record.trace_sync,
            ["A - a(phi) [arcsec]", "E - N phi [arcsec]", "Z - z(phi) [um]"],
        )
        if record.trace_cross is not None and record.coupling.work_setting_on:
            rec.series(
                "machine/cross_slide",
                t,
                record.trace_cross[:, :2],
                ["Y [um]", "Y - T (1 - cos q_s phi) [um]"],
            )
        rec.mesh_file("coupling", stl)


def format_result(doc: dict[str, Any]) -> str:
    lines = ["FACE COUPLING measured (exact from the motion; the manifold solid beside it)"]
    for s in doc["slots"]:
        lines.append(
            f"  slot {s['slot']}: bottom {s['bottom_shape']} {s['bottom_form_um']:+.2f} um, side bows "
            f"{s['side_bow_um'][0]:+.2f} / {s['side_bow_um'][1]:+.2f} um"
        )
    if doc["spacing_arcsec"]:
        lines.append("  spacing deviation: " + ", ".join(f"{v:+.3f}" for v in doc["spacing_arcsec"]) + " arcsec")
    if "mesh" in doc:
        lines.append(
            f"  the solid ({doc['mesh']['hulls']} hulls, sweep error {doc['mesh']['sweep_error_um']:.1f} um): bottom "
            f"form within {doc['mesh']['bottom_form_difference_um']:.2f} um of the exact"
        )
    if "ideal_bottom_form_um" in doc:
        lines.append(f"  the ideal kinematics' bottom form: {doc['ideal_bottom_form_um']:+.2f} um")
    if "forces" in doc:
        f = doc["forces"]
        lines.append(f"  cutting forces ({f['material']}, oblique model):")
        for s in f["slots"]:
            lines.append(
                f"    slot {s['slot']}: layer {s['layer_um']:.1f} um, F_c mean {s['F_c_mean_N']:.0f} / peak "
                f"{s['F_c_peak_N']:.0f} N, thrust {s['thrust_mean_N']:.0f} / {s['thrust_peak_N']:.0f} N; work drive "
                f"{s['work_drive_twist_arcsec']:+.2f} arcsec ({s['work_drive_twist_um_at_L']:+.3f} um at L), head "
                f"drive {s['head_drive_twist_arcsec']:+.1f} arcsec"
            )
        lines.append(
            "    spacing with forces "
            + ", ".join(f"{v:+.3f}" for v in f["spacing_with_forces_arcsec"])
            + " arcsec, without "
            + ", ".join(f"{v:+.3f}" for v in f["spacing_without_forces_arcsec"])
            + " arcsec"
        )
    return "\n".join(lines)


def _write(out: Path, doc: dict[str, Any], cut) -> None:
    import trimesh

    out.mkdir(parents=True, exist_ok=True)
    mesh = cut.solid.to_mesh()
    tm = trimesh.Trimesh(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts), process=False)
    tm.export(out / "coupling.stl")
    write_json(out / "measurement.json", doc)


def _forces_tables(f: dict[str, Any] | None) -> list[str]:
    """The report's forces section: per slot the layer, F_c and thrust, the drives' twists; the spacing with and
    without the forces."""
    from virtual_machine.output.report import html_table

    if not f:
        return []
    keys = (
        "layer_um",
        "F_c_mean_N",
        "F_c_peak_N",
        "thrust_mean_N",
        "thrust_peak_N",
        "work_drive_twist_arcsec",
        "work_drive_twist_um_at_L",
        "head_drive_twist_arcsec",
        "slot_shift_from_twists_um_at_L",
        "sync_at_M_um_at_L",
        "bottom_depth_change_um_at_M",
    )
    rows = [[s["slot"], *(s[k] for k in keys)] for s in f["slots"]]
    spacing = zip(f["spacing_with_forces_arcsec"], f["spacing_without_forces_arcsec"], strict=True)
    return [
        f"<h2>Cutting forces ({html.escape(f['material'])})</h2><p>{html.escape(f['model'])}</p>",
        html_table(["slot", *keys], rows),
        html_table(["spacing with forces [arcsec]", "without [arcsec]"], [list(v) for v in spacing]),
    ]


def _report(page: Path, path: Path, doc: dict[str, Any], job: Job) -> None:
    from virtual_machine.output.report import html_table, write_page

    rows = [[s["slot"], s["bottom_shape"], s["bottom_form_um"], *s["side_bow_um"]] for s in doc["slots"]]
    body = [
        f"<h1>skive run: {html.escape(Path(path).name)}</h1>",
        "<p>Face coupling by continuous indexing (seed 004) on the simulated face-contour machine: the slots cut "
        "from the motion it recorded, measured exactly and on the manifold solid.</p>",
        html_table(["slot", "bottom", "bottom form [um]", "side bow 1 [um]", "side bow 2 [um]"], rows),
        html_table(["spacing deviation [arcsec]"], [[v] for v in doc["spacing_arcsec"]]),
        *_forces_tables(doc.get("forces")),
        html_table(["", ""], [[k, v] for k, v in doc["run"]["durations_s"].items()]),
        f"<pre>{html.escape(format_setting_sheet(job))}</pre>",
        f"<pre>{html.escape(Path(path).read_text())}</pre>",
    ]
    write_page(page, "skive run", body)
