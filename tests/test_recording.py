"""The Rerun recording of a run: written once from a short real simulation (0.8 s of spur_external), a real gear
mesh with an imposed +3 um on one flank, its measurement and charts, two blank snapshots; read back with
rerun.chunk.RrdReader."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import mujoco
import numpy as np
import pytest
import trimesh
from rerun.chunk import RrdReader

from cutting.skiving.edge import make_edge
from metrology.charts import write_charts
from metrology.measure import measure_gear
from metrology.reference_gear import reference_gear_mesh
from metrology.sections import MeshData
from virtual_machine.job import load_job
from virtual_machine.output.recording import decimation, smooth_rate, write_recording
from virtual_machine.runtime.machine_run import simulate

JOB = Path(__file__).resolve().parents[1] / "assets/jobs/spur_external.toml"
DURATION, RATE = 0.8, 200.0
EXCESS_MM = 3e-3  # imposed on the left flank of tooth 0


def _deviation(value: float):
    return lambda side, tooth, L, z: np.where((side == "left") & (np.asarray(tooth) == 0), value, 0.0)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """Simulate, build the meshes, measure, chart and write one recording."""
    job = load_job(JOB)
    motion = simulate(job, duration=DURATION)
    gear = job.skiving.gear
    cut = reference_gear_mesh(gear, _deviation(EXCESS_MM), flank_points=12)
    perfect = reference_gear_mesh(gear, _deviation(0.0), flank_points=12)  # same topology, nothing imposed
    out = tmp_path_factory.mktemp("recording")
    measurement = measure_gear(MeshData(cut.vertices, cut.faces), gear)
    charts = write_charts(out / "charts", measurement)
    snapshots = [
        (0.2, *(lambda m: (m.vertices, m.faces))(trimesh.creation.cylinder(radius=42.0, height=20.0))),
        (0.6, *(lambda m: (m.vertices, m.faces))(trimesh.creation.cylinder(radius=40.0, height=20.0))),
    ]
    force = np.column_stack([np.sin(motion.t), np.cos(motion.t)])
    path = write_recording(
        out / "run.rrd",
        model_xml=motion.model_xml,
        motion=motion,
        setup=job.skiving,
        snapshots=snapshots,
        gear_mesh=(cut.vertices, cut.faces),
        measurement=measurement,
        charts=charts,
        series={"cutting_force": (motion.t, force)},
        rate_hz=RATE,
        edge=make_edge(job.skiving, "conjugate"),
    )
    return {"job": job, "motion": motion, "path": path, "cut": cut, "perfect": perfect, "measurement": measurement}


def chunks(path: Path, entity: str, static: bool | None = None):
    return RrdReader(path).stream().filter(content=entity, is_static=static).to_chunks()


def column(entity_chunks, name: str) -> list:
    """One value per row (a list of instances for a component)."""
    return [v for c in entity_chunks for v in c.to_record_batch().column(name).to_pylist()]


def instances(entity_chunks, name: str) -> list:
    """The instances of a component over all rows."""
    return [v for row in column(entity_chunks, name) for v in row]


def rows(path: Path, entity: str) -> int:
    return sum(c.num_rows for c in chunks(path, entity, static=False))


def test_entities_and_timeline(run):
    all_chunks = RrdReader(run["path"]).stream().to_chunks()
    entities = {c.entity_path for c in all_chunks}
    expected = {
        "/machine/work_spindle",
        "/machine/tool_spindle",
        "/machine/carriage",
        "/machine/radial_slide",
        "/machine/work_spindle/blank_frame",
        "/machine/work_spindle/blank_frame/blank/pass_1",
        "/signals/sync_error",
        "/signals/torque",
        "/signals/axes/spindles",
        "/signals/axes/carriage",
        "/signals/axes/radial_slide",
        "/signals/legend",
        "/signals/program/segment",
        "/signals/program/events",
        "/signals/extra/cutting_force",
        "/gear/finished",
        "/measurement/summary",
        "/measurement/profile",
        "/measurement/helix",
        "/measurement/pitch",
        "/measurement/flank_deviation",
    }
    assert run["motion"].passes, "the 0.8 s run reaches the first feed stroke"
    expected.add("/gear/cutter_path/pass_1")
    assert expected <= entities
    assert any(e.startswith("/machine/tool_spindle/") for e in entities)  # the cutter's geoms
    timelines = {t for c in all_chunks for t in c.timeline_names}
    assert timelines == {"sim_time"}  # no wall clock
    reader = RrdReader(run["path"])
    (blueprint,) = reader.blueprints()
    views = {c.entity_path for c in reader.stream(store=blueprint).to_chunks() if c.entity_path.count("/") == 2}
    # 3D cutting zone, machine and gear; sync, torques, spindle speeds, carriage, radial slide, program, 1 extra;
    # 4 charts (profile, helix, pitch, topography), 2 documents, the deviation colours, events, the signals' legend
    assert sum(v.startswith("/view/") for v in views) == 3 + 7 + 9
    layout = reader.stream(store=blueprint).to_chunks()
    queries = [q for c in layout if c.entity_path.endswith("/ViewContents") for q in column([c], "ViewContents:query")]
    assert ["+ $origin/**", "- $origin/cutter_path/**"] in queries  # the cutter paths hidden by default
    # sync error, torques and program stacked on one time axis: their x axes linked, no legend boxes over them
    links = [v for c in layout if c.entity_path.endswith("/TimeAxis") for v in column([c], "TimeAxis:link")]
    hidden = [v for c in layout if c.entity_path.endswith("/PlotLegend") for v in column([c], "PlotLegend:visible")]
    assert links.count([2]) >= 3 and hidden.count([False]) >= 3  # 2: LinkAxis.LinkToGlobal
    (target,) = [
        v for c in layout if c.entity_path.endswith("/EyeControls3D") for v in column([c], "EyeControls3D:look_target")
    ]
    model = mujoco.MjModel.from_xml_string(run["motion"].model_xml)
    data = mujoco.MjData(model)
    data.qpos[:] = model.key_qpos[0] if model.nkey else model.qpos0
    mujoco.mj_kinematics(model, data)
    assert np.allclose(target[0], data.site("blank_frame").xpos * 1e3, atol=1e-3)  # the cutting zone on the blank


def test_row_counts(run):
    motion, path = run["motion"], run["path"]
    n = len(motion.t)
    assert n == 3200
    # the poses at least at RATE, and fast enough that no spindle turns more than 10 deg between two frames
    index = decimation(motion.t, max(RATE, smooth_rate(motion)))
    frames = len(index)
    assert frames > round(DURATION * RATE)
    step = np.degrees(np.abs(np.diff(motion.q[index][:, [0, 1, 4]], axis=0)))
    assert step.max() <= 10.0
    for body in ("work_spindle", "tool_spindle", "carriage", "lead_screw"):
        assert rows(path, f"/machine/{body}") == frames
    signals = ("sync_error", "torque", "axes/spindles", "axes/carriage", "axes/radial_slide", "extra/cutting_force")
    for entity in signals:
        assert rows(path, f"/signals/{entity}") == n
    torque = column(chunks(path, "/signals/torque", static=False), "Scalars:scalars")  # 3 instances per row
    assert np.allclose(np.array(torque), motion.torque)
    from virtual_machine.output.recording import from_pass_start

    for entity, k in (("carriage", 2), ("radial_slide", 3)):  # P3, X [mm], from each pass's start
        slide = instances(chunks(path, f"/signals/axes/{entity}", static=False), "Scalars:scalars")
        assert np.allclose(np.ravel(slide), from_pass_start(motion, motion.q[:, k]))
    # the spindles' speeds [rpm]: B1, B2 and TV turn as the kinematics say
    speeds = np.array(column(chunks(path, "/signals/axes/spindles", static=False), "Scalars:scalars"))
    assert np.allclose(speeds, np.gradient(motion.q[:, [0, 1, 4]], motion.t, axis=0) * 60 / (2 * math.pi))
    ratio = abs(np.median(speeds[n // 2 :, 1] / speeds[n // 2 :, 0]))  # work / tool = z0 / z2, opposite senses
    st = run["job"].skiving
    assert ratio == pytest.approx(st.cutter.teeth / st.gear.teeth, rel=0.02)
    sync = instances(chunks(path, "/signals/sync_error", static=False), "Scalars:scalars")
    assert np.allclose(np.ravel(sync), motion.sync_um)
    events = instances(chunks(path, "/signals/program/events", static=False), "TextLog:text")
    assert events[0] == "runup" and "feed, pass 1" in events  # passes counted from 1, as the report counts them
    assert events[-1].startswith("end of the record (feed, pass 1 done")  # the program's events complete


def test_body_poses_follow_the_axes(run):
    """Transforms are MuJoCo's kinematics of the recorded axes, in mm: B2 turns the table about z, P3 lifts the
    carriage, X moves the radial slide."""
    motion, path = run["motion"], run["path"]
    q = motion.q[decimation(motion.t, max(RATE, smooth_rate(motion)))]
    work = chunks(path, "/machine/work_spindle", static=False)
    quat = np.array(instances(work, "Transform3D:quaternion"))
    b2 = 2 * np.arctan2(quat[:, 2], quat[:, 3])
    assert np.allclose(np.angle(np.exp(1j * (b2 - q[:, 1]))), 0.0, atol=1e-6)  # Rerun stores float32
    assert np.allclose(quat[:, :2], 0.0, atol=1e-7)
    carriage = np.array(instances(chunks(path, "/machine/carriage", static=False), "Transform3D:translation"))
    assert np.allclose(carriage[:, 2], q[:, 2], atol=1e-4)
    radial = np.array(instances(chunks(path, "/machine/radial_slide", static=False), "Transform3D:translation"))
    assert np.allclose(radial[:, 0], q[:, 3], atol=1e-4)


def test_each_snapshot_goes_to_its_pass():
    """The pass a snapshot belongs to is the last one begun at or before it: the stock at a pass's end and during
    the return after it is that pass's (entity pass_<n>, n from 1)."""
    from types import SimpleNamespace

    from virtual_machine.output.recording import snapshot_passes

    motion = SimpleNamespace(t=np.arange(10.0), pass_index=np.array([-1, -1, 0, 0, -1, -1, 1, 1, -1, -1]))
    assert snapshot_passes(motion, np.array([0.5, 2.0, 3.9, 5.0, 6.0, 9.5])).tolist() == [0, 0, 0, 0, 1, 1]


def test_snapshots_and_cutter_path(run):
    path, motion = run["path"], run["motion"]
    snaps = chunks(path, "/machine/work_spindle/blank_frame/blank/pass_1", static=False)  # one entity per pass
    assert sum(c.num_rows for c in snaps) == 2
    times = column(snaps, "sim_time")
    assert sorted(t.total_seconds() for t in times) == [0.2, 0.6]
    cleared = column(chunks(path, "/machine/work_spindle/blank_model", static=False), "sim_time")
    assert sorted(t.total_seconds() for t in cleared) == [0.0, 0.2]  # model blank shown until the first snapshot
    strip = np.array(instances(chunks(path, "/gear/cutter_path/pass_1", static=True), "LineStrips3D:strips")[0])
    first = motion.passes[0]
    assert 10 < len(strip) < len(first.trans)  # decimated
    assert np.allclose(np.hypot(strip[:, 0], strip[:, 1]), np.hypot(first.trans[0, 0], first.trans[0, 1]), atol=1e-3)
    assert np.allclose(strip[[0, -1]], first.trans[[0, -1]], atol=1e-4)


def _rgba(packed: list[int]) -> np.ndarray:
    p = np.array(packed, dtype=np.uint32)
    return np.stack([(p >> 24) & 255, (p >> 16) & 255, (p >> 8) & 255, p & 255], -1).astype(int)


def _chart_rgba(values_um: np.ndarray, limit: float) -> np.ndarray:
    """The topography chart's colour of each value (metrology.charts: pcolormesh of DEVIATION_CMAP over
    +-limit), as 0-255 RGBA."""
    import matplotlib as mpl

    from metrology.charts import DEVIATION_CMAP

    norm = mpl.colors.Normalize(vmin=-limit, vmax=limit, clip=True)
    return np.round(mpl.colormaps[DEVIATION_CMAP](norm(values_um)) * 255)


def test_the_finished_gear_carries_its_measured_deviation_on_the_measurements_grid(run):
    """The finished gear (shown when the run has cut it) in one colour, and on each charted tooth and flank a
    surface on the measurement's topography grid in the chart's colours and scale: the imposed +3 um on tooth 1's
    left flank red as the chart draws +3 um, the other flanks the map's white; each surface on its nominal flank
    (lifted 20 um), and a colour bar."""
    from metrology.charts import deviation_limit
    from virtual_machine.output.recording import SURFACE_LIFT

    path, measurement, gear = run["path"], run["measurement"], run["job"].skiving.gear
    finished = chunks(path, "/gear/finished", static=False)
    assert [t.total_seconds() for t in column(finished, "sim_time")] == [pytest.approx(run["motion"].t[-1])]
    names = finished[0].to_record_batch().schema.names
    assert "Mesh3D:vertex_colors" not in names and "Mesh3D:albedo_factor" in names
    topo = measurement["topography"]
    limit = deviation_limit(topo)
    assert measurement["evaluation"]["datum"]["tooth_1_index"] == 0  # tooth 1 is the nominal tooth 0
    for side in ("left", "right"):
        for k, number in enumerate(topo["teeth"]):
            surface = chunks(path, f"/gear/deviation/{side}/tooth_{number}", static=False)
            rgba = _rgba(instances(surface, "Mesh3D:vertex_colors"))
            dev = np.asarray(topo[side]["per_tooth_um"][k], dtype=float).ravel()
            assert rgba.shape == (len(dev), 4) and np.isfinite(dev).mean() > 0.9
            ok = np.isfinite(dev)
            assert np.all(np.abs(rgba[ok] - _chart_rgba(dev[ok], limit)) <= 1)
            v = np.array(instances(surface, "Mesh3D:vertex_positions"))
            r = np.hypot(v[:, 0], v[:, 1])
            assert r.min() > gear.base_radius and r.max() < gear.tip_radius + SURFACE_LIFT
    # tooth 1's left flank stands the imposed 3 um off the others (the reference mesh's 12 points per flank leave
    # the same chord deviation, about -2.4 um, on every flank)
    medians = {side: [np.nanmedian(g) for g in topo[side]["per_tooth_um"]] for side in ("left", "right")}
    assert medians["left"][0] - np.median(medians["left"][1:]) == pytest.approx(EXCESS_MM * 1e3, abs=0.3)
    assert np.ptp(medians["left"][1:] + medians["right"]) < 0.3
    red = _chart_rgba(np.array([EXCESS_MM * 1e3]), limit)[0]
    assert red[0] > 150 and red[2] < red[0]  # excess material: red
    bar = chunks(path, "/measurement/deviation_colours", static=True)
    assert bar and "Image:buffer" in bar[0].to_record_batch().schema.names
    text = instances(chunks(path, "/measurement/flank_deviation"), "TextDocument:text")[0]
    assert "topography grid" in text and "| left | 1 |" in text


def test_deviation_colours_are_the_charts_at_plus_and_minus_4_um(run, tmp_path):
    """The issue's known answer: a grid point at +4 um and one at -4 um (on a topography whose largest mean
    deviation is 5 um) take the colours the topography chart's colour map gives +4 and -4 um."""
    import copy

    import rerun as rr

    from virtual_machine.output.recording import log_finished_gear

    measurement = copy.deepcopy(run["measurement"])
    topo = measurement["topography"]
    for key, (i, j), value in (("per_tooth_um", (3, 4), 4.0), ("per_tooth_um", (9, 6), -4.0)):
        topo["left"][key][0][i][j] = value
    topo["left"]["deviation_um"][0][0] = 5.0  # the chart's scale: +-5 um
    rec = rr.RecordingStream("skive-test")
    rec.save(tmp_path / "dev.rrd")
    cut = run["cut"]
    log_finished_gear(rec, run["job"].skiving.gear, (cut.vertices, cut.faces), measurement, None)
    rec.flush()
    rec.disconnect()
    number = topo["teeth"][0]
    rgba = _rgba(
        instances(chunks(tmp_path / "dev.rrd", f"/gear/deviation/left/tooth_{number}"), "Mesh3D:vertex_colors")
    )
    n_z = len(topo["z_mm"])
    for (i, j), value in (((3, 4), 4.0), ((9, 6), -4.0)):
        assert np.all(np.abs(rgba[i * n_z + j] - _chart_rgba(np.array([value]), 5.0)[0]) <= 1)
    assert rgba[3 * n_z + 4][0] > rgba[3 * n_z + 4][2] and rgba[9 * n_z + 6][2] > rgba[9 * n_z + 6][0]


def test_measurement_documents(run):
    summary = instances(chunks(run["path"], "/measurement/summary"), "TextDocument:text")[0]
    assert "f_falpha" in summary and "class" in summary
    blob = instances(chunks(run["path"], "/measurement/profile"), "EncodedImage:blob")[0]
    assert bytes(blob[:8]) == b"\x89PNG\r\n\x1a\n"


def test_bad_input_is_a_value_error(run, tmp_path):
    motion, job = run["motion"], run["job"]
    kw = {"motion": motion, "setup": job.skiving}
    bare = "<mujoco><worldbody><body name='other'><joint name='B1'/><geom size='0.1'/></body></worldbody></mujoco>"
    with pytest.raises(ValueError, match="work_spindle"):
        write_recording(tmp_path / "a.rrd", model_xml=bare, **kw)
    with pytest.raises(ValueError, match="does not compile"):
        write_recording(tmp_path / "b.rrd", model_xml="<mujoco><nonsense/>", **kw)
    short = dataclasses.replace(motion, sync_um=motion.sync_um[:-1])
    with pytest.raises(ValueError, match=r"motion\.sync_um"):
        write_recording(tmp_path / "c.rrd", model_xml=motion.model_xml, motion=short, setup=job.skiving)
    with pytest.raises(ValueError, match="series"):
        write_recording(tmp_path / "d.rrd", model_xml=motion.model_xml, series={"f": (motion.t, motion.t[:5])}, **kw)
    bad_mesh = (np.zeros((3, 3)), np.array([[0, 1, 3]]))
    with pytest.raises(ValueError, match="gear_mesh"):
        write_recording(tmp_path / "e.rrd", model_xml=motion.model_xml, gear_mesh=bad_mesh, **kw)
    with pytest.raises(ValueError, match="rate_hz"):
        write_recording(tmp_path / "f.rrd", model_xml=motion.model_xml, rate_hz=math.nan, **kw)
    assert not list(tmp_path.glob("*.rrd"))


def test_recorder_writes_what_a_process_logs(tmp_path):
    """The one recorder every process uses: a series on the sim_time timeline (values read back equal), a static
    mesh from an STL, an image and a document; no wall clock; the file is closed when the block ends."""
    from virtual_machine.output.recorder import Recorder

    t = np.linspace(0.0, 0.5, 11)
    values = np.column_stack([t**2, -t])
    box = trimesh.creation.box(extents=(1.0, 2.0, 3.0))
    box.export(tmp_path / "box.stl")
    png = tmp_path / "chart.png"
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.figure(figsize=(1, 1))
    plt.savefig(png)
    plt.close("all")
    path = tmp_path / "sub" / "p.rrd"
    with Recorder(path, "skive_test") as rec:
        rec.series("machine/axes", t, values, ["A [rad]", "Z [mm]"])
        rec.mesh_file("workpiece", tmp_path / "box.stl")
        rec.image("measurement/chart", png)
        rec.markdown("measurement/summary", "# class 6")
    entities = {c.entity_path for c in RrdReader(path).stream().to_chunks()}
    assert {"/machine/axes", "/workpiece", "/measurement/chart", "/measurement/summary"} <= entities
    assert rows(path, "/machine/axes") == len(t)
    got = np.array(column(chunks(path, "/machine/axes", static=False), "Scalars:scalars"))
    assert np.allclose(got, values)
    (mesh,) = chunks(path, "/workpiece", static=True)
    assert len(instances([mesh], "Mesh3D:vertex_positions")) == len(box.vertices)
    assert {t for c in RrdReader(path).stream().to_chunks() for t in c.timeline_names} <= {"sim_time"}


def test_each_run_is_its_own_recording():
    """Two runs of the same job get two recording ids (its hash and each run's start): a viewer opens them side by
    side instead of merging them; the id is the job's (the same text and start give the same id)."""
    import datetime

    from virtual_machine.output.recorder import run_recording_id
    from virtual_machine.processes.base import run_identity

    a, b = run_identity(load_job(JOB)), run_identity(load_job(JOB))
    assert a["recording_id"] != b["recording_id"]
    assert a["recording_id"].split("-")[0] == b["recording_id"].split("-")[0]  # the same job
    assert a["documents"]["job"] == JOB.read_text()
    at = datetime.datetime(2026, 11, 28, 12, 0, 0, 1234, tzinfo=datetime.UTC)
    assert run_recording_id("x = 1", at) == run_recording_id("x = 1", at) != run_recording_id("x = 2", at)


def test_signals_are_named_as_the_machine_names_its_elements(run):
    """Each line named by its element as the seeds name it, with its unit in the label (not the entity), distinct
    colours within a view, and a legend document."""
    static = {c.entity_path: c for c in RrdReader(run["path"]).stream().to_chunks() if c.is_static}
    names = static["/signals/torque"].to_record_batch().column("SeriesLines:names").to_pylist()[0]
    assert names == ["M1 tool-spindle motor [N m]", "M2 work-spindle motor [N m]", "M3 lead-screw motor [N m]"]
    colours = static["/signals/torque"].to_record_batch().column("SeriesLines:colors").to_pylist()[0]
    assert len(set(colours)) == 3
    spindles = static["/signals/axes/spindles"].to_record_batch().column("SeriesLines:names").to_pylist()[0]
    assert spindles == ["B1 tool spindle [rpm]", "B2 work spindle [rpm]", "TV lead screw [rpm]"]
    legend = static["/signals/legend"].to_record_batch().column("TextDocument:text").to_pylist()[0][0]
    assert "| TV | lead screw |" in legend and "| M3 | lead-screw motor |" in legend


def test_every_series_is_drawn_min_max(run):
    """The viewer's default averages the samples under a pixel (a 4 kHz force's peaks vanish when zoomed out):
    every series declares the min-max aggregation, so the extremes stay visible at any zoom."""
    static = [c for c in RrdReader(run["path"]).stream().to_chunks() if c.is_static]
    policies = [
        c.to_record_batch().column("SeriesLines:aggregation_policy").to_pylist()[0]
        for c in static
        if "SeriesLines:aggregation_policy" in c.to_record_batch().schema.names
    ]
    assert len(policies) >= 7 and all(p == [5] for p in policies)  # 5: AggregationPolicy.MinMax


def test_the_cutter_is_drawn_with_its_teeth_and_edges(run):
    """The cutter as it is, not a disc: its z0 relieved teeth (closed bodies under the tool spindle's cutter_frame,
    each tooth's section receding by the clearance towards the back face) and each tooth's cutting edge in its own
    rake frame; the model's disc and angle mark are left out."""
    st = run["job"].skiving
    frame = "/machine/tool_spindle/cutter_frame"
    (teeth,) = chunks(run["path"], f"{frame}/teeth", static=True)
    v = np.array(instances([teeth], "Mesh3D:vertex_positions"), dtype=float)
    f = np.array(instances([teeth], "Mesh3D:triangle_indices"))
    mesh = trimesh.Trimesh(v, f, process=False)
    bodies = mesh.split(only_watertight=True)
    assert len(bodies) == st.cutter.teeth
    r = np.hypot(v[:, 0], v[:, 1])
    tip = st.cutter_tip_diameter / 2
    assert r.max() == pytest.approx(tip, abs=1e-5)  # (float32) the face's section reaches the tip circle
    back = np.isclose(v[:, 2], v[:, 2].min()) if st.body_side < 0 else np.isclose(v[:, 2], v[:, 2].max())
    drop = st.cutter.face_width * math.tan(st.rake.clearance_angle)
    assert r[back].max() == pytest.approx(tip - drop, abs=1e-5)  # the back face's: the relief's drop lower
    strips = instances(chunks(run["path"], f"{frame}/edges", static=True), "LineStrips3D:strips")
    assert len(strips) == st.cutter.teeth
    for strip, tooth in zip(strips, st.tooth_frames, strict=True):
        local = (np.array(strip) - tooth[:, 3]) @ tooth[:, :3]
        assert np.abs(local[:, 2]).max() < 1e-5  # in its rake plane (float32)
        assert np.hypot(local[:, 0], local[:, 1]).min() >= st.cutter.root_radius - 1e-5  # above the root circle
    assert r.min() == pytest.approx(st.cutter.root_radius, abs=1e-5)  # the teeth stand on the body's disc
    entities = {c.entity_path for c in RrdReader(run["path"]).stream().to_chunks()}
    assert not {"/machine/tool_spindle/cutter", "/machine/tool_spindle/cutter_mark"} & entities


def test_view_asks_for_a_viewer_before_the_run_and_says_how_to_start_one(tmp_path):
    """`skive run --view URL` streams to a viewer: with none answering at URL it is refused before the machine
    starts (nothing written, exit 2), naming the address and `rerun`; a listening address passes the check."""
    import socket

    from click.testing import CliRunner

    from cutting.errors import InputError
    from virtual_machine.cli import main
    from virtual_machine.output.recorder import check_viewer

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        free = s.getsockname()[1]  # closed again: nothing listens there
    url = f"rerun+http://127.0.0.1:{free}/proxy"
    res = CliRunner().invoke(main, ["run", str(JOB), "--out", str(tmp_path / "out"), "--view", url])
    assert res.exit_code == 2, res.output
    assert "no Rerun viewer answers there" in res.output and "`rerun`" in res.output and url in res.output
    assert "machine and cut" not in res.output and not (tmp_path / "out").exists()
    with pytest.raises(InputError, match="not a Rerun viewer's address"):
        check_viewer("http://nowhere")
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        check_viewer(f"rerun+http://127.0.0.1:{server.getsockname()[1]}/proxy")  # something answers: on with the run


def test_positions_read_from_each_pass_start():
    """The carriage and the radial slide are drawn from each pass's start (every feed stroke from 0); before the
    first pass, from the record's start."""
    from types import SimpleNamespace

    from virtual_machine.output.recording import from_pass_start

    motion = SimpleNamespace(pass_index=np.array([-1, -1, 0, 0, 0, -1, 1, 1, -1]))
    values = np.array([5.0, 6.0, 10.0, 9.0, 8.0, 12.0, 20.0, 19.0, 25.0])
    assert from_pass_start(motion, values).tolist() == [0.0, 1.0, 0.0, -1.0, -2.0, 2.0, 0.0, -1.0, 5.0]
