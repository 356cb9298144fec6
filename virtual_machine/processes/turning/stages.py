"""Vibration turning (seed 004) on the lathe of seed 001, as `skive setup`, `skive simulate` and `skive run` do it.

The lathe is set up as for a thread whose lead is the feed S0 (master-slave: the carriage's servo follows the
spindle's encoder 6 through counter 7 and block 8); the feed vibration is added to the slave's command at the
spindle's angle (:class:`virtual_machine.structures.thread_group.ThreadMasterSlave`), so the carriage really has
to make it: what the turned surface shows is the path the simulated carriage made (B1, P2 recorded), not the
command. The surface and the chip breaks come from :mod:`cutting.turning.vibration` on that path
(:class:`cutting.turning.vibration.SampledTurning`), its crests are measured by :mod:`metrology.turned_surface`;
`skive run` also cuts it with manifold3d and measures the solid's crests beside the exact envelope.

The lathe cuts under its cutting forces (:mod:`cutting.turning.forces`): at every physics step the chip at
the spindle's angle, from the path the simulated carriage has made, gives by the oblique model F_c (a torque braking
the spindle), the thrust's axial part F_f (pushing the carriage back against the feed through the nut stage) and its
radial part F_p (which no joint of the model takes); the run without them is the comparison
(:func:`forces_section`). A spindle motor too weak for the cut refuses the job before the run
(:func:`check_spindle_holds`).
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

from cutting.errors import InputError, Problem
from cutting.materials import material
from cutting.turning.forces import ChipTracker, NoseGeometry, TurningForces, path_forces, reach_turns
from cutting.turning.vibration import TWO_PI, SampledTurning, TurningSetup, cut_workpiece
from machine_models.parameters import override
from machine_models.thread_lathe import ThreadLatheParams
from metrology.turned_surface import crest_heights, roughness, solid_crests, turned_surface_summary
from virtual_machine.job import Job, flatten_model
from virtual_machine.output.json_file import write_json

#: settling after the spindle's run-up before the measured revolutions start [s]
SETTLE = 0.2
#: axial angles at which the manifold solid's crests are compared with the envelope's
SOLID_ANGLES = 12


def ideal_setup(job: Job) -> TurningSetup:
    t = job.turning
    return TurningSetup(t["diameter"] / 2, t["feed"], t["nose_radius"], t["depth"], job.vibration)


def spindle_speed(job: Job) -> float:
    """Spindle speed [rev/s] of the cutting speed at the workpiece diameter."""
    return job.process.cutting_speed * 1000 / 60 / (math.pi * job.turning["diameter"])


def format_prediction(job: Job) -> str:
    """`skive setup` of a turning job: the geometry the feed and the vibration predict."""
    s = turned_surface_summary(ideal_setup(job), job.process.revolutions)
    t, v = job.turning, job.vibration
    lines = [
        "VIBRATION TURNING (seed 004) on the lathe of seed 001 (master-slave: the feed follows the spindle's encoder)",
        f"  workpiece {t['diameter']:.2f} mm, feed S0 = {t['feed']:.3f} mm/rev, nose radius {t['nose_radius']:.2f} mm, "
        f"depth {t['depth']:.2f} mm; spindle {spindle_speed(job) * 60:.0f} rpm",
        "  vibration: none (plain turning)"
        if v is None
        else f"  vibration: A = {v.amplitude:.3f} mm, {v.cycles_per_rev:g} cycles/rev "
        f"({v.cycles_per_rev * spindle_speed(job):.1f} Hz), xi = T_in/T_out = {v.xi:g}, {v.form}",
        *_summary_lines(s),
    ]
    try:
        f, model = commanded_forces(job)
    except InputError as exc:  # an unknown material: say so here, `skive simulate` refuses the job
        lines.append(f"  cutting forces: not estimated ({exc.problems[0]})")
    else:
        torque = model.spindle_torque(f[:, 0])
        lines.append(
            f"  cutting forces along the command ({model.material.key}, oblique model, rake "
            f"{math.degrees(model.rake):g} deg): F_c mean {f[:, 0].mean():.0f} / peak {f[:, 0].max():.0f} N, F_f mean "
            f"{f[:, 1].mean():.0f} N, F_p mean {f[:, 2].mean():.0f} N; spindle torque peak {torque.max():.2f} N m"
        )
    return "\n".join(lines)


def _summary_lines(s: dict[str, Any]) -> list[str]:
    sp = s["spacing_um"]
    return [
        f"  distance of successive paths: {sp['min']:.1f} .. {sp['max']:.1f} um (S0 {sp['S0']:.0f} um; "
        f"Delta_max / S0 = {sp['max'] / sp['S0']:.2f})",
        f"  crests: Rt max {s['Rt_max_um']:.2f} um, mean Rt {s['Rt_mean_um']:.2f} um, mean crest "
        f"{s['crest_mean_um']:.2f} um (plain turning {s['plain_turning_crest_um']:.2f} um)",
        f"  chip breaks per revolution: {s['chip_breaks_per_rev']:.2f}"
        + ("" if s["chip_breaks_per_rev"] else " (a continuous chip)"),
    ]


def lathe_params(job: Job) -> ThreadLatheParams:
    """The job's lathe: its [machine.model] over the defaults."""
    return override(ThreadLatheParams(), flatten_model(job.machine.model))


def turning_forces(job: Job) -> TurningForces:
    """The force model of the job's cut (:mod:`cutting.turning.forces`): its nose, depth and ``process.material``
    (an unknown material raises :class:`InputError` listing the known ones)."""
    try:
        steel = material(job.process.material)
    except InputError as exc:
        raise InputError(exc.problems, job.source) from None
    return TurningForces(NoseGeometry.of(ideal_setup(job)), steel)


def commanded_forces(job: Job, revs: int = 4, samples_per_rev: int = 3600) -> tuple[np.ndarray, TurningForces]:
    """Forces (n, 3) [N] along the commanded path over ``revs`` turns of the steady cut, and the model."""
    model = turning_forces(job)
    theta = TWO_PI * (reach_turns(ideal_setup(job)) + np.arange(revs * samples_per_rev) / samples_per_rev)
    return path_forces(ideal_setup(job), model, theta)[1], model


def check_spindle_holds(job: Job, params: ThreadLatheParams) -> dict[str, float]:
    """Refuse (InputError) a job whose peak cutting torque along the commanded path, with the spindle's bearing
    friction, exceeds the spindle motor M1's peak torque (referred through the spindle drive); returns the
    estimate (peak F_c [N], spindle torque [N m], torque needed at M1 [N m]) when it holds."""
    from virtual_machine.setting.thread_layout import thread_layout

    f, model = commanded_forces(job)
    peak = float(f[:, 0].max())
    torque = float(model.spindle_torque(peak))
    ratio = thread_layout(job, params).spindle_ratio  # spindle rad per M1 rad: M1 carries ratio x the torque
    need = (torque + params.spindle_friction) * ratio
    if need > params.spindle_motor_torque:
        raise InputError(
            Problem(
                "machine.model.spindle_motor_torque",
                params.spindle_motor_torque,
                f"the spindle motor M1 cannot hold the cut: F_c up to {peak:.0f} N at r = {model.nose.mean_radius:.1f}"
                f" mm is {torque:.1f} N m at the spindle, {need:.1f} N m at M1 with the bearings' "
                f"{params.spindle_friction:g} N m, against its peak {params.spindle_motor_torque:g} N m",
                f"set machine.model.spindle_motor_torque >= {math.ceil(need)}, or take a smaller turning.depth, "
                "turning.feed or turning.diameter",
            ),
            job.source,
        )
    return {"F_c_peak_N": peak, "spindle_torque_Nm": torque, "M1_torque_Nm": need}


def simulate_turning(
    job: Job,
    progress: Callable[[float], None] | None = None,
    params: ThreadLatheParams | None = None,
    forces: bool = True,
):
    """The lathe turns ``process.revolutions`` revolutions after its run-up; returns the record and the path it
    made as a :class:`SampledTurning` (theta from the first measured revolution, which the vibration met at the
    spindle angle ``path.theta0`` after the feed engaged: :func:`commanded_path`). ``params``: the lathe (default:
    the job's, its [machine.model] over the defaults).

    ``forces``: the cut loads the lathe (:mod:`cutting.turning.forces`): at every physics step the chip between
    the nose where the *simulated* carriage has it and the surface the path the simulated carriage made one and
    more turns earlier left (:class:`ChipTracker`; before the simulation the commanded path), from the end of the
    run-up on. The simulated path is there in the loop (every earlier turn is recorded before it is needed), so
    the carriage's own deflections feed back into the chips it cuts. Refused (InputError) before the run if the
    spindle motor cannot hold the cut (:func:`check_spindle_holds`)."""
    from virtual_machine.reach.lathe import check_lathe_reach
    from virtual_machine.runtime.lathe_run import CuttingLoad, simulate_thread
    from virtual_machine.setting.thread_layout import thread_layout

    n = job.process.revolutions
    params = params or lathe_params(job)
    duration = params.runup_time + SETTLE + (n + 1) / spindle_speed(job)
    check_lathe_reach(job, params, thread_layout(job, params), duration)  # before the path is sampled
    cut = None
    if forces:
        check_spindle_holds(job, params)
        model = turning_forces(job)
        ideal = ideal_setup(job)
        tracker = ChipTracker(
            model,
            reach_turns(ideal),
            lambda theta: np.asarray(ideal.path(theta)),
            params.runup_time,
            math.ceil(duration / params.timestep) + 16,
        )
        cut = CuttingLoad(tracker, model.nose.mean_radius)
    rec = simulate_thread(job, params, duration=duration, vibration=job.vibration, cut=cut)
    if progress is not None:
        progress(1.0)
    theta = rec.b1 - rec.b1[0]
    z = rec.hand_sign * (rec.p2 - rec.p2[0])  # along the feed [mm]
    k0 = int(np.searchsorted(rec.t, rec.runup + SETTLE))
    t = job.turning
    path = SampledTurning(
        t["diameter"] / 2,
        t["feed"],
        t["nose_radius"],
        t["depth"],
        job.vibration,
        theta=theta[k0:] - theta[k0],
        z=z[k0:] - z[k0],
        theta0=float(theta[k0]),
    )
    return rec, path


def commanded_path(job: Job, path: SampledTurning) -> np.ndarray:
    """The commanded axial position [mm] at the path's angles, from the same start (the vibration's phase)."""
    ideal = ideal_setup(job)
    return np.asarray(ideal.path(path.theta + path.theta0)) - float(ideal.path(path.theta0))


def simulate_summary(job: Job, forces: bool = True) -> tuple[dict[str, Any], Any, SampledTurning]:
    """`skive simulate` of a turning job: the machine's path against the command, the surface it leaves; with
    ``forces`` the lathe cuts under its cutting forces and the same run without them is the comparison
    (:func:`forces_section`)."""
    rec, path = simulate_turning(job, forces=forces)
    n = min(job.process.revolutions, path.revolutions)
    commanded = ideal_setup(job)
    dev = (path.z - commanded_path(job, path)) * 1e3
    doc = {
        "path_deviation_um": {"mean": float(dev.mean()), "peak_to_peak": float(np.ptp(dev))},
        "machine": turned_surface_summary(path, n),
        "commanded": turned_surface_summary(commanded, n),
        "machine_time_s": float(rec.t[-1]),
    }
    if forces:
        free_rec, free_path = simulate_turning(job, forces=False)
        doc["forces"] = forces_section(job, (rec, path), (free_rec, free_path), n)
    return doc, rec, path


def _stats(x: np.ndarray) -> dict[str, float]:
    return {"mean": float(x.mean()), "peak": float(x.max()), "min": float(x.min())}


def forces_section(job: Job, loaded: tuple[Any, SampledTurning], free: tuple[Any, SampledTurning], n: int) -> dict:
    """What the cutting forces do, over the measured revolutions: F_c, F_f, F_p [N] (mean, peak), the spindle
    torque [N m] and its share of M1's peak torque, the carriage's mean axial deflection under F_f against the run
    without forces [um] (on the path, and in the nut stage: P2 - t_TV/(2 pi) TV, with F_f / k_axial, k_axial the
    nut stage's stiffness: the screw's angle is what the feed servo holds, so the nut, screw and thrust bearing
    between the screw's encoder and the tool are all that yields), and the crests with and without forces [um]."""
    from virtual_machine.setting.thread_layout import thread_layout

    params = lathe_params(job)
    model = turning_forces(job)
    lay = thread_layout(job, params)
    (rec, path), (rec0, path0) = loaded, free
    k0, j0 = len(rec.t) - len(path.theta), len(rec0.t) - len(path0.theta)
    f = rec.force[k0:]
    torque = np.asarray(model.spindle_torque(f[:, 0]))

    def ahead(r, k: int) -> np.ndarray:
        """The carriage ahead of its command along the feed [um], from the feed's start (the record's lead error
        is the part without the vibration)."""
        a = job.vibration.axial(r.b1[k:] - r.b1[0]) * 1e3 if job.vibration is not None else 0.0
        return r.hand_sign * r.lead_error_um[k:] - a

    def nut(r, k: int) -> np.ndarray:
        return r.p2[k:] * 1e-3 - lay.screw_lead * r.tv[k:]  # [m]: the nut stage's stretch, backlash included

    stretch = float(np.mean(nut(rec, k0)) - np.mean(nut(rec0, j0))) * rec.hand_sign  # along the feed
    k_axial = params.nut_stiffness
    rough, rough0 = roughness(path, 72, n), roughness(path0, 72, n)
    crests = {
        "with_forces": {"Rt_max": rough.rt_max * 1e3, "Rt_mean": rough.rt_mean * 1e3, "mean": rough.crest_mean * 1e3},
        "without_forces": {
            "Rt_max": rough0.rt_max * 1e3,
            "Rt_mean": rough0.rt_mean * 1e3,
            "mean": rough0.crest_mean * 1e3,
        },
    }
    crests["difference"] = {k: crests["with_forces"][k] - crests["without_forces"][k] for k in crests["with_forces"]}
    predicted, _ = commanded_forces(job)
    motor_peak = params.spindle_motor_torque
    return {
        "material": {"key": model.material.key, "kc11_N_mm2": model.material.kc11, "mc": model.material.mc},
        "model": {
            "kind": "oblique cutting per element of the nose arc (cutting/turning/forces.py, docs/forces.md)",
            "rake_deg": math.degrees(model.rake),
            "edge_radius_mm": model.edge_radius,
        },
        "F_c_N": _stats(f[:, 0]),
        "F_f_N": _stats(f[:, 1]),
        "F_p_N": _stats(f[:, 2]),
        "commanded_path_F_c_N": _stats(predicted[:, 0]),
        # the nose behind the foremost earlier pass (the chip broken): it only shaves the crest between two passes
        "crest_shaving_share": float(np.mean(np.asarray(path.uncut_thickness(path.theta)) <= 0)),
        "spindle_torque_Nm": _stats(torque),
        "spindle_motor_peak_Nm": motor_peak,
        "torque_share_of_motor_peak": float(torque.max()) * lay.spindle_ratio / motor_peak,
        "carriage": {
            "k_axial_N_um": k_axial * 1e-6 if k_axial is not None else None,
            "F_f_over_k_axial_um": float(f[:, 1].mean()) / k_axial * 1e6 if k_axial is not None else 0.0,
            "nut_deflection_um": -stretch * 1e6,
            "path_deflection_um": float(np.mean(ahead(rec0, j0)) - np.mean(ahead(rec, k0))),
        },
        "crests_um": crests,
    }


def run_turning(job: Job, path: Path, out: Path, rrd: Path | None = None, stage=None) -> dict[str, Any]:
    """`skive run` of a turning job: the lathe turns, the surface it leaves is measured exactly and as the
    manifold solid; writes measurement.json, report.html (and the recording)."""
    stage = stage or (lambda name: None)
    durations: dict[str, float] = {}
    t0 = time.perf_counter()
    stage("machine: the lathe turns with the feed vibration")
    doc, rec, sampled = simulate_summary(job)
    durations["machine"] = time.perf_counter() - t0
    stage("the turned surface with manifold3d, its crests against the exact envelope")
    t0 = time.perf_counter()
    n = min(20, sampled.revolutions)
    solid = cut_workpiece(sampled, n, job.process.sweep_error)
    phis = (np.arange(SOLID_ANGLES) + 0.5) * 2 * math.pi / SOLID_ANGLES
    diffs, rts = [], []
    for phi in phis:
        a, b = solid_crests(solid, float(phi)), crest_heights(sampled.surface(float(phi), n))
        rts.append(a.rt)
        if len(a.height) and len(b.height):
            big = b.height > 5e-4
            if big.any():
                near = np.abs(a.z[:, None] - b.z[big][None, :]).argmin(axis=0)
                diffs.append(np.max(np.abs(a.height[near] - b.height[big])))
    durations["solid"] = time.perf_counter() - t0
    doc["solid"] = {
        "revolutions": n,
        "sweep_error_um": job.process.sweep_error * 1e3,
        "Rt_max_um": float(max(rts)) * 1e3,
        "largest_crest_difference_to_envelope_um": float(max(diffs)) * 1e3 if diffs else None,
    }
    out.mkdir(parents=True, exist_ok=True)
    (out / "workpiece.stl").write_bytes(_stl(solid.solid))
    text = Path(path).read_text()
    doc["run"] = {
        "job": {"path": str(path), "sha256": hashlib.sha256(text.encode()).hexdigest(), "kind": job.kind},
        "seed": None,
        "durations_s": {k: round(v, 3) for k, v in durations.items()},
        "spindle_rpm": spindle_speed(job) * 60,
    }
    write_json(out / "measurement.json", doc)
    _report(out / "report.html", path, doc, job)
    if rrd is not None:
        stage("recording")
        _record(rrd, rec, sampled, job)
    return doc


def format_run(doc: dict[str, Any]) -> str:
    m, c = doc["machine"], doc["commanded"]
    lines = [
        "VIBRATION TURNING (seed 004): the path the lathe made",
        f"  carriage against the command: mean {doc['path_deviation_um']['mean']:.2f} um, peak to peak "
        f"{doc['path_deviation_um']['peak_to_peak']:.2f} um",
        *_summary_lines(m),
        f"  (the command alone: Rt max {c['Rt_max_um']:.2f} um, chip breaks {c['chip_breaks_per_rev']:.2f} per rev)",
        f"  the crests' geometric prediction from the path positions: Rt max {m['predicted_Rt_max_um']:.2f} um",
    ]
    if "forces" in doc:
        lines += _force_lines(doc["forces"])
    if "solid" in doc:
        lines.append(solid_line(doc["solid"]))
    return "\n".join(lines)


def solid_line(s: dict[str, Any]) -> str:
    """The report's line of the manifold solid's crests (None: the surface shows no crest to compare)."""
    diff = s["largest_crest_difference_to_envelope_um"]
    return (
        f"  manifold solid ({s['revolutions']} revs, sweep error {s['sweep_error_um']:.1f} um): Rt max "
        f"{s['Rt_max_um']:.2f} um, "
        + (f"crests within {diff:.2f} um of the exact envelope" if diff is not None else "no crests to compare")
    )


def _force_lines(f: dict[str, Any]) -> list[str]:
    c, w, wo, d = f["carriage"], f["crests_um"]["with_forces"], f["crests_um"]["without_forces"], f["crests_um"]
    k = f"{c['k_axial_N_um']:.0f} N/um" if c["k_axial_N_um"] is not None else "rigid"
    return [
        f"  cutting forces ({f['material']['key']}, oblique model, rake {f['model']['rake_deg']:g} deg, edge radius "
        f"{f['model']['edge_radius_mm'] * 1e3:g} um): F_c mean {f['F_c_N']['mean']:.0f} / peak "
        f"{f['F_c_N']['peak']:.0f} N, F_f {f['F_f_N']['mean']:.0f} / {f['F_f_N']['peak']:.0f} N, F_p "
        f"{f['F_p_N']['mean']:.0f} / {f['F_p_N']['peak']:.0f} N",
        f"  spindle torque mean {f['spindle_torque_Nm']['mean']:.2f} / peak {f['spindle_torque_Nm']['peak']:.2f} N m "
        f"({100 * f['torque_share_of_motor_peak']:.1f} % of M1's peak {f['spindle_motor_peak_Nm']:g} N m)",
        f"  carriage pushed back by F_f: {c['path_deflection_um']:.2f} um (nut stage {c['nut_deflection_um']:.2f} um; "
        f"mean F_f / k_axial = {c['F_f_over_k_axial_um']:.2f} um at {k})",
        f"  crests with forces: Rt max {w['Rt_max']:.2f} um, mean crest {w['mean']:.2f} um; without: "
        f"{wo['Rt_max']:.2f} / {wo['mean']:.2f} um (difference {d['difference']['Rt_max']:+.3f} / "
        f"{d['difference']['mean']:+.3f} um)",
    ]


def _stl(solid) -> bytes:
    import trimesh

    mesh = solid.to_mesh()
    tm = trimesh.Trimesh(np.asarray(mesh.vert_properties)[:, :3], np.asarray(mesh.tri_verts), process=False)
    return tm.export(file_type="stl")


def _report(page: Path, path: Path, doc: dict[str, Any], job: Job) -> None:
    from virtual_machine.output.report import html_table, write_page

    m, c = doc["machine"], doc["commanded"]
    rows = [
        [k.replace("_um", " [um]"), m[k], c[k]]
        for k in ("Rt_max_um", "Rt_mean_um", "crest_mean_um", "predicted_Rt_max_um", "plain_turning_crest_um")
    ]
    rows.append(["chip breaks per revolution", m["chip_breaks_per_rev"], c["chip_breaks_per_rev"]])
    rows.append(["Delta max [um]", m["spacing_um"]["max"], c["spacing_um"]["max"]])
    body = [
        f"<h1>skive run: {html.escape(Path(path).name)}</h1>",
        "<p>Vibration turning (seed 004) on the lathe of seed 001: the surface the simulated carriage's path leaves "
        "(exact envelope of the nose circles), the geometric prediction from the path positions, and the same for "
        "the commanded path.</p>",
        html_table(["", "machine", "command"], rows),
        *(_force_table(doc["forces"]) if "forces" in doc else []),
        "<h2>Manifold solid</h2>",
        html_table(["", ""], [[k, v] for k, v in doc["solid"].items()]),
        "<h2>Run</h2>",
        html_table(["", ""], [[k, v] for k, v in doc["run"]["durations_s"].items()]),
        "<h2>Setup</h2>",
        f"<pre>{html.escape(format_prediction(job))}</pre>",
        "<h2>Job file</h2>",
        f"<pre>{html.escape(Path(path).read_text())}</pre>",
    ]
    write_page(page, "skive run", body)


def _force_table(f: dict[str, Any]) -> list[str]:
    from virtual_machine.output.report import html_table

    rows = [
        [name, f[key]["mean"], f[key]["peak"]]
        for name, key in (
            ("F_c [N]", "F_c_N"),
            ("F_f [N]", "F_f_N"),
            ("F_p [N]", "F_p_N"),
            ("spindle torque [N m]", "spindle_torque_Nm"),
        )
    ]
    c, cr = f["carriage"], f["crests_um"]
    crest_rows = [[k, cr["with_forces"][k], cr["without_forces"][k], cr["difference"][k]] for k in cr["with_forces"]]
    return [
        "<h2>Cutting forces</h2>",
        f"<p>The oblique model on the uncut chip ({html.escape(f['material']['key'])}, kc1.1 = "
        f"{f['material']['kc11_N_mm2']:g} N/mm^2, mc = {f['material']['mc']:g}; rake {f['model']['rake_deg']:g} deg, "
        f"edge radius {f['model']['edge_radius_mm'] * 1e3:g} um): F_c along the cutting speed, F_f and F_p the "
        f"thrust's axial and radial parts, fed back into the lathe at every physics step. Peak spindle "
        f"torque {100 * f['torque_share_of_motor_peak']:.1f} % of M1's peak {f['spindle_motor_peak_Nm']:g} N m; "
        f"the carriage pushed back {c['path_deflection_um']:.2f} um (nut stage {c['nut_deflection_um']:.2f} um, "
        f"F_f / k_axial {c['F_f_over_k_axial_um']:.2f} um).</p>",
        html_table(["", "mean", "peak"], rows),
        html_table(["crests [um]", "with forces", "without", "difference"], crest_rows),
    ]


def _record(rrd: Path, rec, sampled: SampledTurning, job: Job) -> None:
    """The carriage's path against the command and the uncut chip thickness over machine time."""
    from virtual_machine.output.recorder import APP_ID, Recorder
    from virtual_machine.processes.base import run_identity

    commanded = commanded_path(job, sampled)
    k0 = len(rec.t) - len(sampled.theta)
    t = rec.t[k0:]
    thickness = np.asarray(sampled.uncut_thickness(sampled.theta))
    with Recorder(rrd, APP_ID, **run_identity(job)) as stream:
        stream.series("lathe/carriage_mm", t, np.column_stack([sampled.z, commanded]), ["made", "commanded"])
        stream.series("lathe/uncut_chip_mm", t, np.clip(thickness, -1.0, 1.0)[:, None], ["uncut chip"])
        if rec.force is not None:
            stream.series("lathe/cutting_force_N", t, rec.force[k0:], ["F_c", "F_f", "F_p"])
