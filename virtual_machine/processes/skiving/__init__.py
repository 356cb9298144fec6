"""Gear skiving (seed 000, the setting sheets S1-S4): the process of a "skiving" job.

- setup: the machine setting sheet of the job's structure (:mod:`virtual_machine.setting.sheet`);
- simulate: the machine runs through the passes without cutting (:mod:`virtual_machine.runtime.machine_run`):
trajectory.npz,
  motion.npz, simulation.json, sync_error.png;
- cut: the ideal kinematics (or a simulated trajectory) cut the gear (:mod:`cutting.skiving.ideal_cut`), measured on its
  exact swept surface and on gear.stl;
- run: the simulated machine cuts it under its cutting forces (:mod:`virtual_machine.processes.skiving.run`),
measured, reported.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import ClassVar

from metrology.charts import finite
from virtual_machine.job import Job
from virtual_machine.output.json_file import write_json
from virtual_machine.output.model_scope import model_scope
from virtual_machine.output.progress import Reporter
from virtual_machine.processes.base import Process, Product, reporter_or_default, run_identity, written
from virtual_machine.processes.options import (
    MachineSimulateOptions,
    SkivingCutOptions,
    SkivingRunOptions,
    SkivingSheetOptions,
    StageOptions,
)
from virtual_machine.processes.sheets import sheet_product
from virtual_machine.setting.plan import SkivingPlan

RUN_FILES = ("gear.stl", "measurement.json", "report.html", "charts/*.png")


class Skiving(Process):
    kind = "skiving"
    title = "gear skiving"
    stages: ClassVar[dict[str, type[StageOptions]]] = {
        "setup": SkivingSheetOptions,
        "simulate": MachineSimulateOptions,
        "cut": SkivingCutOptions,
        "run": SkivingRunOptions,
    }

    def setup(self, job: Job, options: SkivingSheetOptions | None = None) -> Product:
        """The setting sheet, the cutter's working angles per pass from the setup alone (docs/cutter.md) and the
        passes' balance; with ``balance_passes`` the increments that would balance them."""
        from cutting.skiving.edge import make_edge
        from cutting.skiving.interference import body_interference
        from cutting.skiving.working_angles import working_angle_summaries

        o = self._options("setup", options)
        sheet = sheet_product(job, o.structure)
        st = job.skiving
        edge = make_edge(st, job.cutter_options.edge)
        angles = working_angle_summaries(st, edge, job.process.min_working_clearance)
        body = body_interference(st, edge)
        doc = {**sheet.data, "working_angles": finite(angles), "body_interference": finite(body)}
        text = sheet.text + "\n" + format_working_angles(angles) + "\n" + format_body(body)
        if o.balance_passes:
            balance = _balance(st, edge)
            doc["pass_balance"] = finite(balance.as_dict())
            text += "\n" + format_balance(balance)
        return Product("setup", doc, text, sheet.files, sheet.out)

    def simulate(
        self, job: Job, out: Path, options: MachineSimulateOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        from virtual_machine.output import motion_io
        from virtual_machine.runtime.machine_run import simulate

        o = self._options("simulate", options)
        job = o.machine_of(job)
        duration, rrd = o.duration, o.rrd
        rep = reporter_or_default(reporter)
        plan = SkivingPlan.of(job)
        st = plan.setup
        total = duration or (sum(st.pass_times) + 0.5 + 1.2 * (len(st.passes) - 1))  # strokes, run-up, returns
        bar = rep.task("machine time", total, "s", value_format="{:.2f}")

        def progress(t: float) -> None:
            bar.set_total(t)
            bar.update_to(t)

        t0 = time.perf_counter()
        with rep:
            rec = simulate(job, duration=duration, progress=progress, plan=plan)
        wall = time.perf_counter() - t0
        meta = {
            "job": job.source,
            "structure": job.machine.structure,
            "synchronization": job.machine.synchronization,
            "adaptive_correction": job.machine.adaptive_correction,
            "wall_seconds": wall,
        }
        doc = motion_io.save(rec, out, meta, st.gear.teeth)
        if rrd is not None:
            from virtual_machine.output.recording import write_recording

            write_recording(
                rrd,
                model_xml=rec.model_xml,
                motion=rec,
                setup=st,
                charts=[out / "sync_error.png"],
                **run_identity(job, setting_sheet=sheet_product(job, None).text),
            )
            doc["recording"] = str(rrd)
        files = written(out, "trajectory.npz", "motion.npz", "simulation.json", "sync_error.png", "*.xml")
        return Product("simulate", doc, format_simulation(doc, job, wall, out), files + ([rrd] if rrd else []), out)

    def cut(
        self, job: Job, out: Path, options: SkivingCutOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        from cutting.gear_file import write_gear_stl
        from cutting.skiving.ideal_cut import cut_ideal
        from metrology.charts import write_charts
        from virtual_machine.job import dexel_spacing
        from virtual_machine.output.cutter_charts import write_cutter_charts
        from virtual_machine.output.formatting import format_gear_stl, format_measurement, format_removal
        from virtual_machine.processes.skiving.run import measure_written_cut, with_mesh_tolerance

        o = self._options("cut", options)
        edge, workers, trajectory, removal = o.edge, o.workers, o.trajectory, o.removal
        job = with_mesh_tolerance(job, None if o.mesh_tolerance is None else o.mesh_tolerance * 1e-3)
        rep = reporter_or_default(reporter)
        plan = SkivingPlan.of(job)
        st = plan.setup
        bars: dict = {}

        def progress(i: int, done: int, total: int) -> None:
            if i not in bars:
                bars[i] = rep.task(f"pass {i + 1}/{len(st.passes)}", total, "passages")
            bars[i].update_to(done)

        kind = edge or job.cutter_options.edge
        motions, path = _cut_motions(job, plan, trajectory, rep)
        with rep:  # the passes' bars end with the cut
            report = cut_ideal(
                st,
                kind,
                job.process.sweep_error,
                job.process.roughing_sweep_error,
                progress,
                workers,
                motions=motions,
                removal=removal,
                spacing=dexel_spacing(job),
            )
        rep.stage("measurement: the exact swept surface and the mesh")
        out.mkdir(parents=True, exist_ok=True)
        stl = write_gear_stl(report.result.gear, out / "gear.stl", job.process.stl_tolerance)
        result = measure_written_cut(job, report.edge, motions, report.result, stl, out / "gear.stl")
        motion = "ideal" if path is None else "ideal, finishing pass along the modification's path"
        result["cut"] = _cut_summary(report, stl, kind, motion if trajectory is None else str(trajectory), workers, st)
        result["model_scope"] = model_scope(job, None, "cut")
        if path is not None:
            from virtual_machine.processes.skiving.modification_path import path_summary

            result["modification_path"] = path_summary(path)
        doc = finite(result)
        write_json(out / "measurement.json", doc)
        write_charts(out, result)
        write_cutter_charts(out, result)
        lines = [format_measurement(doc, str(out / "gear.stl"))]
        if path is not None:
            lines.append(format_path(doc["modification_path"]))
        lines.append(format_removal(result["cut"], len(st.passes), sum(st.pass_times)))
        lines.append(format_gear_stl(result["cut"]["gear_stl"]))
        files = written(out, "gear.stl", "measurement.json", "*.png")
        return Product("cut", doc, "\n".join(lines), files, out)

    def run(
        self, job: Job, out: Path, options: SkivingRunOptions | None = None, reporter: Reporter | None = None
    ) -> Product:
        from virtual_machine.output.formatting import format_measurement
        from virtual_machine.processes.skiving.run import run_job, with_mesh_tolerance
        from virtual_machine.runtime.program import program_duration

        o = self._options("run", options)
        rrd, workers, removal = o.rrd, o.workers, o.removal
        if o.view is not None:  # before anything runs: a run streamed to no viewer is refused, nothing lost
            from virtual_machine.output.recorder import check_viewer

            check_viewer(o.view)
        job = with_mesh_tolerance(job, None if o.mesh_tolerance is None else o.mesh_tolerance * 1e-3)
        rep = reporter_or_default(reporter)
        plan = SkivingPlan.of(job)
        total = program_duration(plan.setup, passes=plan.passes)
        bar = rep.task("machine and cut", total, "s of machine time", value_format="{:.2f}")

        def progress(t: float, passages: int) -> None:
            bar.set_total(t)
            bar.update_to(t, engagements=passages)

        def announce(name: str) -> None:
            if name != "machine and cut":
                rep.stage(name)

        with rep:
            doc = run_job(job, out, rrd, progress, announce, workers, None, removal, plan, view=o.view)
        lines = [format_measurement(doc, str(out / "gear.stl"))]
        if doc.get("modification_path"):
            lines.append(format_path(doc["modification_path"]))
        lines.append(format_run(doc["run"], out, rrd))
        return Product("run", doc, "\n".join(lines), written(out, *RUN_FILES) + ([rrd] if rrd else []), out)


def _cut_motions(job: Job, plan: SkivingPlan, trajectory: Path | None, rep: Reporter) -> tuple[list, object | None]:
    """What `skive cut` cuts along: the ideal passes, the finishing pass along a flank modification's path (and the
    path), or the passes of a simulated ``trajectory`` file."""
    if trajectory is not None:
        from cutting.skiving.sampled_motion import sampled_passes
        from virtual_machine.output.motion_io import load_trajectory

        return sampled_passes(plan.setup, load_trajectory(trajectory)), None
    if job.modification is None:
        return list(plan.passes), None
    from virtual_machine.processes.skiving.modification_path import plan_path

    rep.stage("path for the flank modification (seed 003: radial and tangential corrections, accuracy check)")
    path = plan_path(job, plan=plan)
    return path.motions, path


def _cut_summary(report, stl, edge: str, motion: str, workers: int | None, st) -> dict:
    """measurement.json's ``cut``: the edge and motion cut along, the removal's figures, gear.stl, the chips."""
    from cutting.parallel import default_workers
    from cutting.skiving.tooling import tooling_summary
    from virtual_machine.output.formatting import chip_record

    r = report.result
    return {
        "edge": edge,
        "cutter": tooling_summary(st.rake, st.cutter_errors, st.clamping),
        "motion": motion,
        "sweep_error_um": r.sweep_error * 1e3,
        "pass_sweep_error_um": [r.pass_sweep_error.get(i, 0.0) * 1e3 for i in range(len(st.passes))],
        "sweeps": r.sweeps,
        "subtractions": r.subtractions,
        "passages": len(r.chips),
        "triangles": stl.solid_triangles,
        "gear_stl": stl.summary(),
        "workers": workers or default_workers(),
        "seconds": report.seconds,
        "pass_seconds": report.pass_seconds,
        "pass_stock_triangles": report.pass_triangles,
        "machine_seconds": list(st.pass_times),
        "removal": report.removal,
        "chips": [chip_record(c) for c in r.chips],
    }


def format_simulation(doc: dict, job: Job, wall: float, out: Path) -> str:
    """The simulation's synchronisation error per pass and its periodic parts."""
    lines = [
        f"\nSIMULATION  {job.source}  ({job.machine.structure}, {job.machine.synchronization}, "
        f"adaptive correction {'on' if job.machine.adaptive_correction else 'off'})",
        f"{doc['machine_seconds']:.2f} s of machine time in {wall:.1f} s wall "
        f"({doc['machine_seconds'] / wall:.1f}x real time)",
        "synchronisation error while cutting (arc on the reference circle, um):",
    ]
    motors = "/".join(doc["passes"][0]["peak_torque_Nm"]) if doc["passes"] else ""
    lines.append(f"{'pass':>5} {'mean':>8} {'rms':>8} {'rms-mean':>9} {'p-p':>8}   peak torque {motors} [N m]")
    for p in doc["passes"]:
        s, tq = p["sync_error_in_cut"], p["peak_torque_Nm"]
        if s:
            lines.append(
                f"{p['pass'] + 1:>5} {s['mean_um']:8.3f} {s['rms_um']:8.3f} {s['rms_about_mean_um']:9.3f} "
                f"{s['peak_to_peak_um']:8.3f}   " + " / ".join(f"{v:.1f}" for v in tq.values())
            )
    for name, v in doc.get("periodic_part", {}).items():
        lines.append(f"periodic part per {name.replace('_', ' ')}: {v['peak_to_peak_um']:.3f} um p-p")
    lines.append(
        f"written: {out / 'trajectory.npz'}, {out / 'motion.npz'}, {out / 'simulation.json'}, {out / 'sync_error.png'}"
    )
    return "\n".join(lines)


def format_path(path: dict) -> str:
    """The accuracy check's iterations and what the path cannot make."""
    lines = ["", "PATH  the finishing pass's radial and tangential corrections (seed 003's accuracy check)"]
    for where, rows, converged in (
        ("ideal machine", path["iterations"], path["converged"]),
        ("simulated machine", path.get("machine_iterations"), path.get("machine_converged")),
    ):
        if rows is None:
            continue
        for it in rows:
            r, c = it["residual_um"], it["C_beta_um"]
            lines.append(
                f"  {where}, iteration {it['iteration']}: largest residual left {r['left']:.2f} um, right "
                f"{r['right']:.2f} um; C_beta {c['left']:.2f} / {c['right']:.2f} um"
            )
        lines.append(f"  {where}: " + ("converged" if converged else "NOT converged: the residual stopped falling"))
    for side, um in path["beyond_path_um"].items():
        if um > 0.05:
            lines.append(
                f"  {side} flank: {um:.2f} um of the design vary over the profile: a modified cutter makes them"
            )
    return "\n".join(lines)


def format_run(run: dict, out: Path, rrd: Path | None) -> str:
    """The end-of-run table: stages and their wall time, what the machine and the chips did, the files."""
    from virtual_machine.output.formatting import format_gear_stl

    d = run["durations_s"]
    wall = sum(v for k, v in d.items() if k != "machine")
    lines = ["", f"RUN  {run['job']['path']}  ({run['machine']['structure']} / {run['machine']['synchronization']})"]
    lines += [f"  {k:18s} {v:8.1f} s" for k, v in d.items() if k != "machine"]
    lines.append(f"  {'total':18s} {wall:8.1f} s for {d['machine']:.2f} s of machine time")
    sync, f = run["synchronisation"]["sync_error_in_cut"], run["forces"]
    if sync:
        lines.append(f"  sync error while cutting: RMS {sync['rms_um']:.3f} um, p-p {sync['peak_to_peak_um']:.3f} um")
    lines.append(
        f"  {run['cut']['passages']} engagements, {run['cut']['chip_volume_mm3']:.1f} mm^3 of chips, peak force "
        f"{f['peak_force_N']:.0f} N, cutting energy {f['chip_energy_J']:.0f} J ({f['material']})"
    )
    for p in f.get("passes", []):
        normal = p.get("flank_normal_deflection_um") or {}
        lines.append(
            f"  pass {p['pass']}: cutting {p['cutting_mean_N']:.0f} N, thrust {p['thrust_mean_N']:.0f} N, passive "
            f"{p['passive_mean_N']:.0f} N (means); the tool off the flanks by {normal.get('mean', 0.0):.2f} um "
            f"(peak {normal.get('peak', 0.0):.1f} um) at the generating point"
        )
    for v in run.get("vibration", []):
        if "warning" not in v:
            continue
        lines.append(f"  warning: {v['warning']}")
        marks, expected = v.get("flanks"), v.get("surface_wavelength_mm")
        if marks and expected:  # the finishing pass: the flanks it left carry the marks
            lines.append(
                f"  the flanks show it: their helix traces wave {marks['amplitude_um']:.1f} um at "
                f"{marks['wavelength_mm']:.2f} mm along the face (this vibration's marks: {expected:.2f} mm)"
            )
    added = run.get("machine_added") or {}
    if "deviations_um" in added:
        dev = added["deviations_um"]
        parts = [f"{k} {'/'.join(f'{v:+.1f}' for v in dev[k].values())}" for k in dev]
        size = ", ".join(f"{k[:-3]} {v:+.1f}" for k, v in added["size"].items())
        lines.append(
            f"  the machine added (this gear minus the ideal cut, um, left/right): {', '.join(parts)}; {size}; class "
            f"{added['class']['run']} against the ideal cut's {added['class']['ideal_cut']}"
        )
    elif added.get("error"):
        lines.append(f"  the ideal cut beside it could not be measured: {added['error']}")
    lines.append("  " + format_gear_stl(run["cut"]["gear_stl"]))
    if run.get("modification"):
        lines.append(f"  modification: {run['modification']}")
    files = ["gear.stl", "measurement.json", "report.html", "charts/"]
    lines.append(f"  files: {', '.join(str(out / x) for x in files)}" + (f", {rrd}" if rrd else ""))
    return "\n".join(lines)


def _balance(setup, edge):
    """The pass balance with a line of progress per map evaluation (it takes a few seconds each)."""
    from cutting.skiving.pass_balance import balance_passes

    rep = reporter_or_default(None)
    rep.stage(f"balancing {len(setup.passes)} passes (a working-angle map of every pass per step, at most 7 steps)")

    def told(step: int, passes: tuple[float, ...], chips: tuple[float, ...]) -> None:
        rep.stage(
            f"  step {step}: increments {', '.join(f'{d:.3f}' for d in passes)} mm -> largest chips "
            f"{', '.join(f'{h * 1e3:.0f}' for h in chips)} um"
        )

    return balance_passes(setup, edge, progress=told)


def format_body(p: dict) -> str:
    """The relieved tooth against the finished teeth (:func:`cutting.skiving.interference.body_interference`)."""
    from cutting.skiving.interference import TOLERANCE

    where = f"{p['depth_mm']:.2f} mm behind the {p['edge']} edge, {p['edge_position_mm']:.2f} mm along it"
    if p["body_intrusion_max_mm"] > TOLERANCE:
        return (
            f"relieved tooth: ENTERS the finished teeth by {p['body_intrusion_max_mm'] * 1e3:.2f} um ({where}): "
            "`skive cut` and `skive run` refuse this cutter"
        )
    clear = -p["body_intrusion_max_mm"] * 1e3
    return f"relieved tooth: clear of the finished teeth over the whole mesh by >= {clear:.2f} um ({where})"


def format_balance(b) -> str:
    """The proposal of :func:`cutting.skiving.pass_balance.balance_passes` (a :class:`PassBalance`), for the sheet."""

    def um(chips: tuple[float, ...]) -> str:
        return " / ".join(f"{h * 1e3:.0f}" for h in chips)

    job_spread = max(b.before_chips) / min(b.before_chips)
    return "\n".join(
        [
            "pass balance (the largest uncut chip of each pass, every point of its map):",
            f"  the job's  process.passes = [{', '.join(f'{d:g}' for d in b.before_passes)}]: "
            f"{um(b.before_chips)} um (largest / smallest {job_spread:.2f})",
            f"  proposed   process.passes = [{', '.join(f'{d:.3f}' for d in b.passes)}]: "
            f"{um(b.chips)} um (largest / smallest {b.spread:.2f}, {b.steps} map evaluations)",
        ]
    )


def format_working_angles(passes: list[dict]) -> str:
    """The working angles' extremes per pass, a line each."""
    lines = ["working angles (ISO 3002-2, tool in use), the middle passage of each pass:"]
    for p in passes:
        at = p.get("clearance_min_at") or {}
        lines.append(
            f"  pass {p['pass']}: rake {p['rake_min_deg']:.1f} .. {p['rake_max_deg']:.1f} deg; clearance on the "
            f"generated flank >= {p['clearance_min_deg']:.2f} deg ({at.get('edge', '-')} edge, "
            f"{at.get('edge_position_mm', float('nan')):.2f} mm along it), on the engaged edge >= "
            f"{p['clearance_min_engaged_deg']:.1f} deg; inclination <= {p['inclination_max_deg']:.1f} deg; uncut chip "
            f"<= {p['chip_thickness_max_mm'] * 1e3:.0f} um; cutting speed <= {p['cutting_speed_max_m_min']:.0f} m/min"
        )
        if "warning" in p:
            lines.append(f"    warning: {p['warning']}")
    chips = [p["chip_thickness_max_mm"] for p in passes if p.get("chip_thickness_max_mm", 0) > 0]
    if len(chips) > 1:
        lines.append(
            f"passes' balance: largest uncut chip {' / '.join(f'{h * 1e3:.0f}' for h in chips)} um (largest / smallest "
            f"{max(chips) / min(chips):.2f}); `skive setup --balance-passes` proposes increments that even them"
        )
    return "\n".join(lines)
