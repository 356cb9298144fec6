"""The ``skive`` command line. It only assembles stages and prints; the work lives in the packages."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import click

from cutting.errors import InputError
from virtual_machine.job import STRUCTURES, default_job_path, load_job
from virtual_machine.setup_sheet import SetupSheet, setup_sheet


def _fail(exc: Exception) -> None:
    click.echo(f"skive: {exc}", err=True)
    sys.exit(2)


@click.group(help="skive: a physics-based virtual gear-skiving machine.")
def main() -> None:
    pass


def format_sheet(sheet: SetupSheet, source: str) -> str:
    """The setting sheet as a setter reads it."""
    lines = [f"SETTING SHEET  {source}", f"structure: {sheet.structure}", ""]
    g = sheet.geometry
    if sheet.kind == "gear":
        gear, cut = g["gear"], g["cutter"]
        kind = "internal" if gear["internal"] else "external"
        lines += [
            f"gear    z2 = {gear['z']} {kind}, mn = {gear['mn_mm']:g} mm, alpha_n = {gear['alpha_n_deg']:g} deg, "
            f"beta = {gear['beta_deg']:+g} deg, d = {gear['d_mm']:.4f}, db = {gear['db_mm']:.4f}, "
            f"da = {gear['da_mm']:.4f}, df = {gear['df_mm']:.4f} mm, lead = {gear['lead_mm']:.3f} mm",
            f"cutter  z0 = {cut['z']}, beta0 = {cut['beta_deg']:+g} deg, x0 = {cut['x']:+g}, d0 = {cut['d_mm']:.4f}, "
            f"da0 = {cut['da_mm']:.4f} mm, edge = {cut['edge']}",
            f"shaft angle Sigma = {g['shaft_angle_deg']:+.4f} deg, finishing centre distance a = "
            f"{g['centre_distance_final_mm']:.4f} mm, generated root diameter {g['generated_root_diameter_mm']:.4f} mm",
            f"speed ratio n2/n0 = {g['speed_ratio_n2_n0']:+.9f}, work speed {g['work_speed_rpm']:.2f} rpm, "
            f"differential rotation {g['differential_rotation_deg_per_mm']:+.6f} deg per mm of carriage travel (+z)",
        ]
    else:
        lines.append(
            f"thread  lead P = {g['lead_mm']:g} mm {g['hand']} hand, d = {g['diameter_mm']:g} mm, "
            f"spindle {g['spindle_speed_rpm']:.1f} rpm"
        )
    lines += ["", "settings:"]
    for name, s in sheet.settings.items():
        real = "-" if s.realised is None else f"{s.realised:.9g}"
        how = s.realisation.get("describe") or ", ".join(
            f"{k} {v}" for k, v in s.realisation.items() if k not in ("set",) and v is not None
        )
        lines.append(f"  {name:3s} = {s.value:<16.9g} {s.formula:24s} {s.organ}")
        lines.append(f"        set {real}  ({how}); error {s.relative_error:+.2e}")
        if s.effect:
            lines.append("        -> " + ", ".join(f"{k} {v:+.4g}" for k, v in s.effect.items()))
    lines += ["", "constants: " + ", ".join(f"{k} = {v:g}" for k, v in sheet.constants.items()), "", "passes:"]
    for p in sheet.passes:
        extra = (
            f"a = {p['centre_distance_mm']:.4f} mm, depth {p['depth_mm']:.3f} mm, travel {p['travel_mm']:.2f} mm, "
            if "centre_distance_mm" in p
            else ""
        )
        lines.append(f"  {p['pass']}: infeed {p['infeed_mm']:.3f} mm, {extra}time {p['time_s']:.1f} s")
    s = sheet.sanity
    lines += [
        "",
        f"sanity: cutting speed {s['cutting_speed_m_min']:.1f} m/min, total machine time {s['total_time_s']:.1f} s",
    ]
    lines += [f"note: {n}" for n in sheet.notes]
    return "\n".join(lines)


@main.command(help="Print the machine setting sheet of JOB (default: the default job).")
@click.argument("job", required=False, type=click.Path(path_type=Path))
@click.option("--structure", type=click.Choice(STRUCTURES), help="Machine structure (default: the job's).")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of text.")
def setup(job: Path | None, structure: str | None, as_json: bool) -> None:
    path = job or default_job_path()
    try:
        sheet = setup_sheet(load_job(path), structure)
    except (InputError, ValueError) as exc:
        _fail(exc)
    if as_json:
        click.echo(json.dumps(_finite(sheet.to_json()), indent=2, allow_nan=False))
    else:
        click.echo(format_sheet(sheet, str(path)))


@main.command(help="Measure a gear MESH (STL, PLY, OBJ, 3MF, GLB) as the gear of JOB's [gear] section.")
@click.argument("mesh", type=click.Path(path_type=Path))
@click.option("--job", "job_path", type=click.Path(path_type=Path), help="Job file (default: the default job).")
@click.option("--json", "as_json", is_flag=True, help="Print the measurement JSON instead of the summary.")
@click.option("--out", type=click.Path(path_type=Path), help="Write measurement.json and the charts here.")
def measure(mesh: Path, job_path: Path | None, as_json: bool, out: Path | None) -> None:
    from metrology.charts import finite, write_charts
    from metrology.datum import load_mesh
    from metrology.measure import MeasureOptions, measure_gear
    from virtual_machine.job import load_gear_section

    try:
        gear, options = load_gear_section(job_path or default_job_path())
        data = load_mesh(mesh)
        result = measure_gear(
            data, gear, MeasureOptions(**{k: v for k, v in options.items() if v is not None}), str(mesh)
        )
    except (InputError, ValueError, RuntimeError) as exc:
        _fail(exc)
    doc = finite(result)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        (out / "measurement.json").write_text(json.dumps(doc, indent=2, allow_nan=False))
        write_charts(out, result)
    if as_json:
        click.echo(json.dumps(doc, indent=2, allow_nan=False))
    else:
        click.echo(format_measurement(doc, str(mesh)))
        if out is not None:
            click.echo(f"\nwrote {out / 'measurement.json'}, profile.png, helix.png, pitch.png")


@main.command(help="Cut JOB with the ideal kinematics, write DIR/gear.stl and measure it.")
@click.argument("job", required=False, type=click.Path(path_type=Path))
@click.option("--out", type=click.Path(path_type=Path), default=Path("out"), show_default=True)
@click.option("--edge", type=click.Choice(["conjugate", "involute"]), help="Override the job's cutter.edge.")
@click.option("--workers", type=click.IntRange(1, 64), help="Worker processes (default: one per core, at most 8).")
@click.option(
    "--trajectory",
    type=click.Path(exists=True, dir_okay=False, path_type=Path),
    help="Cut along a simulated pose trajectory (trajectory.npz of `skive simulate`) instead of the ideal motion.",
)
def cut(job: Path | None, out: Path, edge: str | None, workers: int | None, trajectory: Path | None) -> None:
    from tqdm import tqdm

    from cutting.ideal_cut import cut_ideal, default_workers, to_trimesh
    from metrology.charts import finite, write_charts
    from metrology.datum import check_mesh
    from metrology.measure import MeasureOptions, measure_gear

    path = job or default_job_path()
    try:
        j = load_job(path)
    except (InputError, ValueError) as exc:
        _fail(exc)
    st = j.skiving
    bars: dict[int, tqdm] = {}

    def progress(i: int, done: int, total: int) -> None:
        if i not in bars:
            bars[i] = tqdm(total=total, desc=f"pass {i + 1}/{len(st.passes)}", unit="passage", leave=True)
        if bars[i].n != done:  # the engine reports every 0.25 s; redraw only on progress (quiet logs)
            bars[i].n = done
            bars[i].refresh()

    kind = edge or j.cutter_options["edge"]
    motions = None
    if trajectory is not None:
        from cutting.sampled_motion import sampled_passes
        from virtual_machine.motion_io import load_trajectory

        try:
            motions = sampled_passes(st, load_trajectory(trajectory))
        except (InputError, ValueError, OSError) as exc:
            _fail(exc)
    try:
        report = cut_ideal(
            st, kind, j.process["sweep_error"], j.process["roughing_sweep_error"], progress, workers, motions=motions
        )
    except InputError as exc:
        _fail(exc)
    for b in bars.values():
        b.close()
    out.mkdir(parents=True, exist_ok=True)
    mesh = to_trimesh(report.result.gear)
    mesh.export(out / "gear.stl")
    opts = MeasureOptions(**{k: v for k, v in (j.measurement or {}).items() if v is not None})
    result = measure_gear(check_mesh(mesh), j.gear, opts, str(out / "gear.stl"))
    r = report.result
    result["cut"] = {
        "edge": kind,
        "motion": "ideal" if trajectory is None else str(trajectory),
        "sweep_error_um": r.sweep_error * 1e3,
        "pass_sweep_error_um": [r.pass_sweep_error.get(i, 0.0) * 1e3 for i in range(len(st.passes))],
        "sweeps": r.sweeps,
        "subtractions": r.subtractions,
        "passages": len(r.chips),
        "triangles": len(mesh.faces),
        "workers": workers or default_workers(),
        "seconds": report.seconds,
        "pass_seconds": report.pass_seconds,
        "pass_stock_triangles": report.pass_triangles,
        "machine_seconds": list(st.pass_times),
        "chips": [
            {"pass": c.pass_index, "cutter_tooth": c.cutter_tooth, "time_s": c.time, "volume_mm3": c.volume}
            for c in r.chips
        ],
    }
    doc = finite(result)
    (out / "measurement.json").write_text(json.dumps(doc, indent=2, allow_nan=False))
    write_charts(out, result)
    click.echo(format_measurement(doc, str(out / "gear.stl")))
    click.echo(
        f"\ncut: {len(r.chips)} tooth passages, {r.sweeps} sweeps, {r.subtractions} subtractions, sweep error <= "
        f"{r.pass_sweep_error.get(len(st.passes) - 1, 0.0) * 1e3:.2f} um in the finishing pass, "
        f"{report.seconds:.1f} s wall for {sum(st.pass_times):.1f} s of machine time"
    )


def format_measurement(doc: dict, source: str) -> str:
    """The class table a gear engineer reads first."""
    iso = doc["iso1328"]
    lines = [f"MEASUREMENT  {source}", ""]
    lines.append(f"{'parameter':10s} {'left':>9s} {'right':>9s} {'tol':>7s} {'class':>6s}")
    rows = [
        ("f_p", "pitch"),
        ("F_p", "pitch"),
        ("F_alpha", "profile"),
        ("f_Halpha", "profile"),
        ("f_falpha", "profile"),
        ("F_beta", "helix"),
        ("f_Hbeta", "helix"),
        ("f_fbeta", "helix"),
    ]
    tol = iso.get("tolerances") or {}
    cls = iso.get("class") or {}
    for key, block in rows:
        left, right = doc[block]["left"][key], doc[block]["right"][key]
        t = tol.get(key)
        lines.append(f"{key:10s} {left:9.2f} {right:9.2f} {t if t is not None else '-':>7} {cls.get(key, '-')!s:>6}")
    fr = doc["runout"]["F_r"]
    lines.append(f"{'F_r':10s} {fr:9.2f} {'':9s} {tol.get('F_r', '-')!s:>7} {cls.get('F_r', '-')!s:>6}")
    lines.append("")
    if iso.get("error"):
        lines.append(f"ISO 1328-1: {iso['error']}")
    else:
        lines.append(f"ISO 1328-1:2013 class of the gear: {cls.get('overall')}")
    th = doc["thickness"]
    ob = th["over_balls"]
    lines.append(
        f"over balls (D = {ob['ball_diameter_mm']:g} mm): M = {ob['M_dK_mm']:.4f} mm "
        f"(nominal {ob['M_dK_nominal_mm']:.4f})"
    )
    sp = th["span"]
    if sp.get("k"):
        lines.append(f"span W_{sp['k']} = {sp['W_k_mm']:.4f} mm (nominal {sp['W_k_nominal_mm']:.4f})")
    lines.append(f"tip diameter {th['tip_diameter_mm']:.4f} mm, root diameter {th['root_diameter_mm']:.4f} mm")
    return "\n".join(lines)


def _finite(obj: object) -> object:
    """JSON has no inf: an infinite lead (spur gear) becomes null."""
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite(v) for v in obj]
    return obj


if __name__ == "__main__":
    main()


@main.command(help="Run the machine through JOB's passes (no cutting); write the pose trajectory and motion record.")
@click.argument("job", required=False, type=click.Path(path_type=Path))
@click.option("--duration", type=click.FloatRange(min=0.0, min_open=True), help="Stop after S seconds of machine time.")
@click.option("--out", type=click.Path(path_type=Path), default=Path("out"), show_default=True)
@click.option("--json", "as_json", is_flag=True, help="Print the summary as JSON.")
@click.option("--structure", type=click.Choice(STRUCTURES), help="Override the job's machine.structure.")
@click.option(
    "--synchronization", type=click.Choice(["equal-coordinates", "master-slave"]), help="Override the scheme."
)
@click.option(
    "--correction/--no-correction", default=None, help="Override machine.adaptive_correction (S4 and the thread group)."
)
@click.option("--rrd", type=click.Path(dir_okay=False, path_type=Path), help="Also write a Rerun recording of the run.")
def simulate(
    job: Path | None,
    duration: float | None,
    out: Path,
    as_json: bool,
    structure: str | None,
    synchronization: str | None,
    correction: bool | None,
    rrd: Path | None,
) -> None:
    import time

    from tqdm import tqdm

    from virtual_machine import motion_io
    from virtual_machine.physics import SimulationDivergedError
    from virtual_machine.simulate import simulate as run

    path = job or default_job_path()
    try:
        j = load_job(path)
    except (InputError, ValueError) as exc:
        _fail(exc)
    overrides = {"structure": structure, "synchronization": synchronization, "adaptive_correction": correction}
    overrides = {k: v for k, v in overrides.items() if v is not None}
    if overrides:
        import dataclasses

        j = dataclasses.replace(j, machine={**j.machine, **overrides})
    if j.kind == "thread":
        _simulate_thread(j, path, duration, out, as_json)
        return
    st = j.skiving
    total = duration or (sum(st.pass_times) + 0.5 + 1.2 * (len(st.passes) - 1))  # strokes + run-up + returns (approx.)
    bar = tqdm(
        total=round(total, 2),
        unit="s",
        desc="machine time",
        disable=as_json,
        bar_format="{l_bar}{bar}| {n:.2f}/{total:.2f} s",
    )
    last = [0.0]

    def progress(t: float) -> None:
        if t - last[0] >= 0.05:
            bar.update(round(t - last[0], 2))
            last[0] = t

    t0 = time.perf_counter()
    try:
        rec = run(j, duration=duration, progress=progress)
    except (SimulationDivergedError, NotImplementedError) as exc:
        bar.close()
        _fail(exc)
    bar.n = bar.total  # the estimate of the total is approximate: end the bar where the run ended
    bar.close()
    wall = time.perf_counter() - t0
    meta = {
        "job": str(path),
        "structure": j.machine["structure"],
        "synchronization": j.machine["synchronization"],
        "adaptive_correction": j.machine["adaptive_correction"],
        "wall_seconds": wall,
    }
    doc = motion_io.save(rec, out, meta, st.gear.teeth)
    if rrd is not None:
        from virtual_machine.recording import write_recording

        write_recording(rrd, model_xml=rec.model_xml, motion=rec, setup=st, charts=[out / "sync_error.png"])
        doc["recording"] = str(rrd)
    if as_json:
        click.echo(json.dumps(doc, indent=2))
        return
    click.echo(
        f"\nSIMULATION  {path}  ({j.machine['structure']}, {j.machine['synchronization']}, "
        f"adaptive correction {'on' if j.machine['adaptive_correction'] else 'off'})"
    )
    click.echo(
        f"{doc['machine_seconds']:.2f} s of machine time in {wall:.1f} s wall "
        f"({doc['machine_seconds'] / wall:.1f}x real time)"
    )
    click.echo("synchronisation error while cutting (arc on the reference circle, um):")
    motors = "/".join(doc["passes"][0]["peak_torque_Nm"]) if doc["passes"] else ""
    click.echo(f"{'pass':>5} {'mean':>8} {'rms':>8} {'rms-mean':>9} {'p-p':>8}   peak torque {motors} [N m]")
    for p in doc["passes"]:
        s, tq = p["sync_error_in_cut"], p["peak_torque_Nm"]
        if s:
            click.echo(
                f"{p['pass'] + 1:>5} {s['mean_um']:8.3f} {s['rms_um']:8.3f} {s['rms_about_mean_um']:9.3f} "
                f"{s['peak_to_peak_um']:8.3f}   " + " / ".join(f"{v:.1f}" for v in tq.values())
            )
    for name, v in doc.get("periodic_part", {}).items():
        click.echo(f"periodic part per {name.replace('_', ' ')}: {v['peak_to_peak_um']:.3f} um p-p")
    click.echo(
        f"written: {out / 'trajectory.npz'}, {out / 'motion.npz'}, {out / 'simulation.json'}, {out / 'sync_error.png'}"
    )


def _simulate_thread(j, path: Path, duration: float | None, out: Path, as_json: bool) -> None:
    """skive simulate for a thread job (seed 001): one threading stroke on the lathe, its lead error."""
    import time

    import numpy as np

    from machine_models.thread_lathe import ThreadLatheParams, build_thread_lathe_spec
    from virtual_machine import motion_io
    from virtual_machine.physics import SimulationDivergedError
    from virtual_machine.simulate_thread import simulate_thread

    t0 = time.perf_counter()
    try:
        rec = simulate_thread(j, duration=duration)
    except (SimulationDivergedError, ValueError) as exc:
        _fail(exc)
    wall = time.perf_counter() - t0
    out.mkdir(parents=True, exist_ok=True)
    motion_io.write_model(build_thread_lathe_spec(j, ThreadLatheParams()).to_xml(), out)
    np.savez_compressed(
        out / "thread_motion.npz",
        t=rec.t,
        b1=rec.b1,
        p2=rec.p2,
        tv=rec.tv,
        torque=rec.torque,
        lead_error_um=rec.lead_error_um,
        on_thread=rec.on_thread,
    )
    drift, travel = rec.drift() if rec.on_thread.sum() > 2 else (0.0, 0.0)
    doc = {
        "job": str(path),
        "form": rec.form,
        "lead_mm": rec.lead,
        "machine_seconds": float(rec.t[-1]),
        "wall_seconds": wall,
        "lead_error_on_thread": rec.stats(),
        "lead_drift_um": drift,
        "travel_mm": travel,
    }
    (out / "simulation.json").write_text(json.dumps(doc, indent=2))
    if as_json:
        click.echo(json.dumps(doc, indent=2))
        return
    s = doc["lead_error_on_thread"]
    click.echo(f"THREAD SIMULATION  {path}  ({rec.form}), lead {rec.lead} mm")
    click.echo(f"{doc['machine_seconds']:.2f} s of machine time in {wall:.1f} s wall")
    if s:
        click.echo(
            f"lead error on the thread: mean {s['mean_um']:.3f} um, p-p {s['peak_to_peak_um']:.3f} um, "
            f"drift {drift:+.3f} um over {abs(travel):.1f} mm"
        )
    click.echo(f"written: {out / 'thread_motion.npz'}, {out / 'simulation.json'}, {out / 'scene.xml'}")
