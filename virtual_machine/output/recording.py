"""One Rerun recording (.rrd) of a simulated run: the machine moving, the blank as it is cut, the cutter path,
the signals, the measurement and the finished gear coloured by its flank deviation.

Entities (lengths in mm everywhere, timeline ``sim_time`` = simulated seconds):

- ``/machine/<body>``: every body of the MJCF, its pose over time from MuJoCo's forward kinematics of the
  recorded axes (``Transform3D``, decimated to ``rate_hz``); ``/machine/<body>/<geom>``: its visual geoms (static,
  in the body frame); ``/machine/<blank body>/blank_frame/blank/pass_<n>``: the blank snapshots (``Mesh3D`` at their
  times, one entity per pass);
- ``/gear/cutter_path/pass_<n>``: the cutter centre in the blank frame per feed stroke (n from 1);
  ``/gear/finished``: the finished gear coloured by deviation on the topography chart's map and scale
  (metrology.charts.DEVIATION_CMAP: missing material blue, white 0, excess red; grey off the flanks);
- ``/signals/axes/spindles`` (B1, B2, TV speeds [rpm]), ``/signals/axes/carriage`` (P3 [mm]),
  ``/signals/axes/radial_slide`` (X [mm]), ``/signals/sync_error``, ``/signals/torque`` (the structure's motors),
  ``/signals/program/{segment,cutting,events}``, ``/signals/extra/<name>`` (the label's unit in its line name, not
  the entity): time series at the record's full rate (``send_columns``), drawn min-max; ``/signals/legend``: what
  the element names mean;
- ``/measurement/<chart stem>`` (PNG), ``/measurement/summary`` (ISO 1328 class table),
  ``/measurement/flank_deviation`` (range of the colour map's data).

The file carries a default blueprint and no wall clock (no ``log_time``, no recording start time).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np
import rerun as rr
import rerun.blueprint as rrb
import rerun.blueprint.components as rrbc

from cutting.flank import SIDES, base_tangent_deviation, flank_polar_angle
from cutting.gear import Gear
from cutting.skiving.edge import CuttingEdge, edge_polygon
from cutting.skiving.interference import relieved_cutter
from machine_models.skiving_machine import CUTTER_GEOMS
from metrology.charts import DEVIATION_CMAP, deviation_limit, deviation_rgba
from virtual_machine.output.recorder import APP_ID, TIMELINE, Recorder, send_series
from virtual_machine.runtime.machine_run import SEGMENTS, MotionRecord, PassTrajectory
from virtual_machine.runtime.physics import AXES

if TYPE_CHECKING:
    from cutting.skiving.kinematics import SkivingSetup

MACHINE, GEAR, SIGNALS, MEASUREMENT = "/machine", "/gear", "/signals", "/measurement"
BLANK_SITE = "blank_frame"
REQUIRED_BODIES = ("work_spindle", "tool_spindle")
LINEAR_AXES = ("P3", "X")  # recorded in mm, metres in the model
SPINDLES = ("B1", "B2", "TV")  # recorded as speeds [rpm]
#: the machine's elements as the seeds name them (seed 000, fig. 1-4; docs/machines.md)
ELEMENTS = {
    "B1": "tool spindle",
    "B2": "work spindle",
    "TV": "lead screw",
    "P3": "carriage along the work axis",
    "X": "radial slide (centre distance)",
}
#: each structure's actuators (``MotionRecord.actuators``), as its figure names them
MOTORS = {
    ("M1", "M2", "M3"): ("M1 tool-spindle motor", "M2 work-spindle motor", "M3 lead-screw motor"),
    ("M1", "M2"): ("M1 main motor (tool spindle, change gears)", "M2 setting-traverse motor"),
    ("M1", "GShD1", "GShD2", "GShD3"): (
        "M1 main motor (tool spindle)",
        "GShD1 hydraulic stepping motor, work spindle",
        "GShD2 hydraulic stepping motor, additional turn",
        "GShD3 hydraulic stepping motor, lead screw",
    ),
}
#: distinct line colours within a view (Okabe-Ito: told apart also with a colour-vision deficiency)
LINE_COLOURS = ((0, 114, 178), (213, 94, 0), (0, 158, 115), (204, 121, 167), (230, 159, 0), (86, 180, 233))
M_TO_MM = 1e3
PASS_COLOURS = ((230, 120, 20), (40, 120, 220), (40, 170, 80), (200, 40, 160), (120, 120, 120))

Mesh = tuple[np.ndarray, np.ndarray]
Snapshot = tuple[float, np.ndarray, np.ndarray]


def write_recording(
    path: str | Path,
    *,
    model_xml: str,
    motion: MotionRecord,
    setup: SkivingSetup | None,
    snapshots: Sequence[Snapshot] = (),
    gear_mesh: Mesh | None = None,
    measurement: Mapping[str, Any] | None = None,
    charts: Sequence[str | Path] = (),
    series: Mapping[str, tuple[np.ndarray, np.ndarray]] | None = None,
    rate_hz: float = 200.0,
    recording_id: str | None = None,
    documents: Mapping[str, str] | None = None,
    edge: CuttingEdge | None = None,
    engagements: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
    view: str | None = None,
) -> Path:
    """Write one .rrd file of the run with its default blueprint; returns the path.

    Parameters
    ----------
    model_xml: the MJCF the run used (``motion.model_xml``), lengths in metres
    motion: the simulation record (4 kHz ticks)
    setup: the job's :class:`cutting.skiving.kinematics.SkivingSetup` (its gear colours ``gear_mesh``), or None
    snapshots: (time [s], vertices (n, 3) mm, triangles (m, 3)) of the blank in the blank frame
    gear_mesh: (vertices mm, triangles) of the finished gear in the blank frame (z = 0 mid face)
    measurement: the dict of :func:`metrology.measure.measure_gear` (or its JSON form)
    charts: PNG files (e.g. from :func:`metrology.charts.write_charts`)
    series: extra time series, name -> (t [s], values (n,) or (n, k))
    rate_hz: the least rate of the body poses [Hz] (the record is decimated to it), raised where a spindle would turn
        more than MAX_STEP_DEG between two frames (:func:`smooth_rate`)
    recording_id: the recording's id and name (a run's: :func:`virtual_machine.output.recorder.run_recording_id`;
        None: Rerun's random id)
    documents: texts to read the run with (name -> text, under ``/run/<name>``: the job, the setting sheet)
    edge: the run's cutting edge: with ``setup`` the cutter is drawn with its teeth (:func:`log_cutter_teeth`)
        instead of the model's disc
    engagements: the chip being cut, (t (n,) [s], where the engaged edge's centroid is in the blank frame (n, 3)
        [mm], chip volume (n,) [mm^3]): marked on the blank (:func:`log_engagements`)
    view: also stream the recording to the Rerun viewer at this address

    Raises
    ------
    ValueError: the model lacks a body, joint or site named above, or any array has the wrong shape or length.
    """
    model = compile_model(model_xml)
    series = dict(series or {})
    _check_inputs(model, motion, snapshots, gear_mesh, series, charts, rate_hz)
    rate_hz = max(rate_hz, smooth_rate(motion))
    path = Path(path)
    motors = [m.split()[0] for m in motor_names(motion.actuators)]
    blueprint = recording_blueprint(series, [Path(c).stem for c in charts], cutting_zone(model, setup), motors)
    with Recorder(
        path, APP_ID, recording_id=recording_id, blueprint=blueprint, documents=documents, view=view
    ) as recorder:
        rec = recorder.stream
        first_snapshot = min((float(s[0]) for s in snapshots), default=None)
        teeth = setup is not None and edge is not None
        log_machine(rec, model, motion, rate_hz, first_snapshot, skip=CUTTER_GEOMS if teeth else ())
        if teeth:
            log_cutter_teeth(rec, model, setup, edge)
        log_snapshots(rec, model, snapshots, motion)
        if engagements is not None and len(engagements[0]):
            log_engagements(rec, model, *engagements)
        log_cutter_paths(rec, motion.passes)
        log_signals(rec, motion, series)
        log_measurement(rec, measurement, charts)
        if gear_mesh is not None and setup is not None:
            finished = float(motion.t[-1])  # the gear appears when the run has cut it
            log_finished_gear(rec, setup.gear, gear_mesh, measurement, finished)
    return path


# ---- input checks --------------------------------------------------------------------------------------
def compile_model(model_xml: str) -> mujoco.MjModel:
    """The MuJoCo model of ``model_xml``, checked for the bodies, joints and site the recording needs."""
    try:
        model = mujoco.MjModel.from_xml_string(model_xml)
    except Exception as exc:  # mujoco raises ValueError or its own FatalError
        raise ValueError(f"model_xml does not compile: {exc}") from exc
    bodies = {model.body(b).name for b in range(model.nbody)}
    joints = {model.joint(j).name for j in range(model.njnt)}
    sites = {model.site(s).name for s in range(model.nsite)}
    missing = [f"body {b!r}" for b in REQUIRED_BODIES if b not in bodies]
    missing += [f"joint {j!r}" for j in AXES if j not in joints]
    missing += [f"site {BLANK_SITE!r}"] if BLANK_SITE not in sites else []
    if missing:
        raise ValueError(f"model_xml is not a skiving machine: it has no {', '.join(missing)}")
    return model


def _check_inputs(
    model: mujoco.MjModel,
    motion: MotionRecord,
    snapshots: Sequence[Snapshot],
    gear_mesh: Mesh | None,
    series: Mapping[str, tuple[np.ndarray, np.ndarray]],
    charts: Sequence[str | Path],
    rate_hz: float,
) -> None:
    """Raise ValueError naming the first input of the wrong shape, length or value."""
    if not (rate_hz > 0 and math.isfinite(rate_hz)):
        raise ValueError(f"rate_hz must be a positive number, got {rate_hz!r}")
    n = len(motion.t)
    if n == 0:
        raise ValueError("motion is empty (no ticks recorded)")
    if np.any(np.diff(motion.t) <= 0):
        raise ValueError("motion.t must be strictly increasing")
    shapes = {
        "motion.q": (np.shape(motion.q), (n, len(AXES))),
        "motion.torque": (np.shape(motion.torque), (n, len(motion.actuators))),
        "motion.sync_um": (np.shape(motion.sync_um), (n,)),
        "motion.segment": (np.shape(motion.segment), (n,)),
        "motion.pass_index": (np.shape(motion.pass_index), (n,)),
        "motion.cutting": (np.shape(motion.cutting), (n,)),
    }
    for name, (got, want) in shapes.items():
        if tuple(got) != want:
            raise ValueError(f"{name} has shape {tuple(got)}, expected {want} (len(motion.t) = {n})")
    for k, (time, vertices, triangles) in enumerate(snapshots):
        if not math.isfinite(float(time)):
            raise ValueError(f"snapshots[{k}]: time {time!r} is not finite")
        _check_mesh(f"snapshots[{k}]", vertices, triangles)
    if gear_mesh is not None:
        _check_mesh("gear_mesh", *gear_mesh)
    for name, (t, values) in series.items():
        if np.ndim(t) != 1 or np.ndim(values) not in (1, 2) or len(values) != len(t):
            raise ValueError(
                f"series[{name!r}]: t must be 1-D and values (n,) or (n, k) of the same length, "
                f"got {np.shape(t)} and {np.shape(values)}"
            )
    for chart in charts:
        if not Path(chart).is_file():
            raise ValueError(f"chart {str(chart)!r} does not exist")


def _check_mesh(name: str, vertices: np.ndarray, triangles: np.ndarray) -> None:
    v, f = np.asarray(vertices), np.asarray(triangles)
    if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"{name}: vertices must be (n, 3) and triangles (m, 3), got {v.shape} and {f.shape}")
    if f.size and (f.min() < 0 or f.max() >= len(v)):
        raise ValueError(f"{name}: triangle indices outside 0..{len(v) - 1}")


# ---- 1. the machine --------------------------------------------------------------------------------------
def _part(name: str) -> str:
    """An entity path part from a MuJoCo name."""
    return re.sub(r"[^A-Za-z0-9_\-]", "_", name) or "_"


def body_path(model: mujoco.MjModel, body: int) -> str:
    """Entity path of a body: ``/machine/<name>`` (``body_<id>`` if unnamed)."""
    return f"{MACHINE}/{_part(model.body(body).name or f'body_{body}')}"


def _xyzw(wxyz: np.ndarray) -> np.ndarray:
    """MuJoCo's (w, x, y, z) quaternions as Rerun's (x, y, z, w)."""
    return np.asarray(wxyz)[..., [1, 2, 3, 0]]


def _is_blank(model: mujoco.MjModel, geom: int) -> bool:
    """The blank cylinder: a cylinder of the blank site's body centred on the site."""
    site = model.site(BLANK_SITE).id
    return (
        model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_CYLINDER
        and model.geom_bodyid[geom] == model.site_bodyid[site]
        and np.allclose(model.geom_pos[geom], model.site_pos[site], atol=1e-9)
    )


def geom_archetype(model: mujoco.MjModel, geom: int) -> Any | None:
    """One visual geom as a Rerun primitive in its body's frame [mm]; None for types not drawn (plane, mesh...)."""
    kind, size = model.geom_type[geom], model.geom_size[geom] * M_TO_MM
    centre, quat = model.geom_pos[geom] * M_TO_MM, _xyzw(model.geom_quat[geom])
    colour = np.round(np.clip(model.geom_rgba[geom], 0, 1) * 255).astype(np.uint8)
    solid = rr.components.FillMode.Solid
    g = mujoco.mjtGeom
    if kind == g.mjGEOM_BOX:
        return rr.Boxes3D(half_sizes=[size], centers=[centre], quaternions=[quat], colors=[colour], fill_mode=solid)
    if kind == g.mjGEOM_CYLINDER:
        return rr.Cylinders3D(
            lengths=[2 * size[1]],
            radii=[size[0]],
            centers=[centre],
            quaternions=[quat],
            colors=[colour],
            fill_mode=solid,
        )
    if kind == g.mjGEOM_CAPSULE:  # Rerun's capsule starts at its translation, MuJoCo's is centred
        rot = np.array(model.geom_quat[geom], dtype=float)
        mat = np.zeros(9)
        mujoco.mju_quat2Mat(mat, rot)
        start = centre - mat.reshape(3, 3) @ np.array([0.0, 0.0, size[1]])
        return rr.Capsules3D(
            lengths=[2 * size[1]], radii=[size[0]], translations=[start], quaternions=[quat], colors=[colour]
        )
    if kind in (g.mjGEOM_SPHERE, g.mjGEOM_ELLIPSOID):
        half = [size[0]] * 3 if kind == g.mjGEOM_SPHERE else size
        return rr.Ellipsoids3D(
            half_sizes=[half], centers=[centre], quaternions=[quat], colors=[colour], fill_mode=solid
        )
    return None


def machine_frames(model: mujoco.MjModel, motion: MotionRecord, rate_hz: float) -> tuple[np.ndarray, ...]:
    """Record indices at ``rate_hz`` and the body poses there by MuJoCo forward kinematics.

    The axes B1, B2, P3, X, TV come from ``motion.q`` (P3, X in mm -> m); every other joint (the motors) stays at
    the ``home`` keyframe (``qpos0`` without one). Returns (indices, positions (k, nbody, 3) mm,
    quaternions (k, nbody, 4) x y z w)."""
    index = decimation(motion.t, rate_hz)
    data = mujoco.MjData(model)
    data.qpos[:] = model.key_qpos[0] if model.nkey else model.qpos0
    adr = [model.joint(a).qposadr[0] for a in AXES]
    scale = np.array([1 / M_TO_MM if a in LINEAR_AXES else 1.0 for a in AXES])
    pos = np.empty((len(index), model.nbody, 3))
    quat = np.empty((len(index), model.nbody, 4))
    for k, i in enumerate(index):
        data.qpos[adr] = motion.q[i] * scale
        mujoco.mj_kinematics(model, data)
        pos[k], quat[k] = data.xpos * M_TO_MM, _xyzw(data.xquat)
    return index, pos, quat


#: the largest turn of a spindle between two recorded frames [deg]: at 200 Hz the default job's work spindle jumped
#: ~76 deg from frame to frame and the viewer showed it stepping
MAX_STEP_DEG = 10.0


def smooth_rate(motion: MotionRecord, max_step_deg: float = MAX_STEP_DEG) -> float:
    """The frame rate [Hz] at which no rotary axis (B1, B2, TV) turns more than ``max_step_deg`` between frames (at
    most the record's own rate)."""
    if len(motion.t) < 2:
        return 0.0
    columns = [AXES.index(a) for a in SPINDLES]
    fastest = float(np.abs(np.diff(motion.q[:, columns], axis=0)).max() / np.median(np.diff(motion.t)))
    own = 1.0 / float(np.median(np.diff(motion.t)))
    return min(math.degrees(fastest) / max_step_deg, own)


def decimation(t: np.ndarray, rate_hz: float) -> np.ndarray:
    """Indices of every ``floor(1 / (rate_hz dt))``-th sample (dt: the median step of ``t``), from the first: at
    least ``rate_hz``."""
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 1.0 / rate_hz
    step = max(1, math.floor(1.0 / (rate_hz * dt) + 1e-9))
    return np.arange(0, len(t), step)


def _log_blank_model(rec: rr.RecordingStream, entity: str, archetype: Any, hide_at: float | None) -> None:
    """The model's blank cylinder: static without snapshots, else shown from t = 0 until ``hide_at``."""
    if hide_at is None:
        rec.log(entity, archetype, static=True)
    elif hide_at > 0:
        rec.set_time(TIMELINE, duration=0.0)
        rec.log(entity, archetype)
        rec.set_time(TIMELINE, duration=hide_at)
        rec.log(entity, rr.Clear(recursive=False))
        rec.reset_time()


def log_machine(
    rec: rr.RecordingStream,
    model: mujoco.MjModel,
    motion: MotionRecord,
    rate_hz: float,
    hide_blank_at: float | None,
    skip: Sequence[str] = (),
) -> None:
    """Part 1: the bodies' visual geoms (static, body frame; those named in ``skip`` left out) and their poses over
    time (Transform3D at rate_hz; a body that never moves once, static).

    With snapshots of the cut blank the model's blank cylinder is shown from t = 0 until the first snapshot."""
    rec.log(MACHINE, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    for geom in range(model.ngeom):
        archetype = geom_archetype(model, geom)
        if archetype is None or model.geom(geom).name in skip:
            continue
        body = body_path(model, model.geom_bodyid[geom])
        if _is_blank(model, geom):
            _log_blank_model(rec, f"{body}/blank_model", archetype, hide_blank_at)
        else:
            rec.log(f"{body}/{_part(model.geom(geom).name or f'geom_{geom}')}", archetype, static=True)
    index, pos, quat = machine_frames(model, motion, rate_hz)
    times = [rr.TimeColumn(TIMELINE, duration=motion.t[index])]
    for body in range(1, model.nbody):
        if np.ptp(pos[:, body], axis=0).max() == 0 and np.ptp(quat[:, body], axis=0).max() == 0:  # never moves
            rec.log(
                body_path(model, body), rr.Transform3D(translation=pos[0, body], quaternion=quat[0, body]), static=True
            )
            continue
        rec.send_columns(
            body_path(model, body),
            indexes=times,
            columns=rr.Transform3D.columns(translation=pos[:, body], quaternion=quat[:, body]),
        )


# ---- 1b. the cutter with its teeth ----------------------------------------------------------------------------
#: the relieved teeth are drawn through this many sections from the rake face to the cutter's back face
TOOTH_SECTIONS = 6
#: the cutting edges' colour (yellow: apart from the orange teeth) and line radius [mm]
EDGE_COLOUR, EDGE_RADIUS = (255, 200, 0, 255), 0.08


def log_cutter_teeth(rec: rr.RecordingStream, model: mujoco.MjModel, setup: SkivingSetup, edge: CuttingEdge) -> None:
    """Part 1b: the cutter as it is, under the tool spindle's ``cutter_frame`` site (static; the spindle turns it):
    every tooth's relieved body (:func:`relieved_teeth`) on the cutter's body (a disc to the root circle), and its
    cutting edge above the root as a line in its own rake frame (the rake face, the pitch deviations and the runout
    of ``setup.tooth_frames``; each tooth's own edge where the teeth differ)."""
    site = model.site("cutter_frame").id
    frame = f"{body_path(model, model.site_bodyid[site])}/cutter_frame"
    pose = rr.Transform3D(translation=model.site_pos[site] * M_TO_MM, quaternion=_xyzw(model.site_quat[site]))
    rec.log(frame, pose, static=True)
    vertices, triangles = relieved_teeth(setup, edge)
    rec.log(f"{frame}/teeth", _mesh3d(vertices, triangles, albedo_factor=(225, 140, 40, 255)), static=True)
    # the body the teeth stand on: a disc to the teeth's lowest radius, over the face width behind the rake face
    width = max(float(setup.cutter.face_width), 0.1)
    hub = float(np.hypot(vertices[:, 0], vertices[:, 1]).min())
    centre = (0.0, 0.0, float(setup.rake_frame[2, 3]) + setup.body_side * width / 2)
    body = rr.Cylinders3D(lengths=[width], radii=[hub], centers=[centre], colors=[(200, 120, 35, 255)])
    rec.log(f"{frame}/body", body, static=True)
    outlines = edge.tooth_outlines() or (edge.outline,) * setup.cutter.teeth
    strips = []
    for tooth, outline in zip(setup.tooth_frames, outlines, strict=True):
        cutting = outline[np.hypot(outline[:, 0], outline[:, 1]) >= setup.cutter.root_radius]  # above the root
        strips.append(np.column_stack([cutting, np.zeros(len(cutting))]) @ tooth[:, :3].T + tooth[:, 3])
    rec.log(f"{frame}/edges", rr.LineStrips3D(strips, colors=[EDGE_COLOUR], radii=EDGE_RADIUS), static=True)


def relieved_teeth(setup: SkivingSetup, edge: CuttingEdge, points: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """The cutter's teeth behind the rake face, in the cutter's frame [mm]: each tooth's section of the cutter with its
    profile shift reduced by d tan(alpha_a) / mn at TOOTH_SECTIONS depths d from the face to the face width (the
    conical relief), from the cutter's root circle to the relieved tip, lofted and closed at both ends; turned to
    each tooth's angle (a picture: the rake face's tilt and the runout are the edges', not the bodies')."""
    c = setup.cutter
    face = float(setup.rake_frame[2, 3])
    ra0 = setup.cutter_tip_diameter / 2
    sections = []
    for d in np.linspace(0.0, max(float(c.face_width), 0.1), TOOTH_SECTIONS):
        relieved, drop = relieved_cutter(setup, float(d))
        z = face + setup.body_side * d
        radii = np.linspace(c.root_radius, ra0 - drop, points)
        r_eff = np.maximum(radii, c.base_radius)
        theta = {side: np.asarray(flank_polar_angle(relieved, r_eff, z, side)) for side in ("left", "right")}
        ring = edge_polygon(radii, theta)
        sections.append(np.column_stack([ring, np.full(len(ring), z)]))
    one = np.concatenate(sections)
    n, s = len(sections[0]), len(sections)
    j, i = (a.ravel() for a in np.meshgrid(np.arange(s - 1), np.arange(n), indexing="ij"))
    a, b = j * n + i, j * n + (i + 1) % n
    tris = [np.stack([a, b, b + n], 1), np.stack([a, b + n, a + n], 1)]
    # the end sections closed by fans from their centres (added after the sections), wound outwards
    face_centre, back_centre = len(one), len(one) + 1
    one = np.concatenate([one, [sections[0].mean(axis=0)], [sections[-1].mean(axis=0)]])
    ring, nxt, back = np.arange(n), (np.arange(n) + 1) % n, (s - 1) * n
    tris.append(np.stack([np.full(n, face_centre), nxt, ring], 1))
    tris.append(np.stack([np.full(n, back_centre), back + ring, back + nxt], 1))
    tooth = np.concatenate(tris)
    angles = np.arctan2(setup.tooth_frames[:, 1, 0], setup.tooth_frames[:, 0, 0])
    angles = angles - angles[0]  # tooth 0's section is drawn at its nominal place, the others turned from it
    verts, faces = [], []
    for k, angle in enumerate(angles):
        rot = np.array([[math.cos(angle), -math.sin(angle), 0.0], [math.sin(angle), math.cos(angle), 0.0], [0, 0, 1]])
        verts.append(one @ rot.T)
        faces.append(tooth + k * len(one))
    return np.concatenate(verts), np.concatenate(faces)


# ---- 2. the blank as it is cut ---------------------------------------------------------------------------
def _mesh3d(vertices: np.ndarray, triangles: np.ndarray, **style: Any) -> rr.Mesh3D:
    """A triangle mesh in mm with smooth normals, coloured by ``style`` (albedo_factor or vertex_colors)."""
    return rr.Mesh3D(
        vertex_positions=np.asarray(vertices, dtype=np.float32),
        triangle_indices=np.asarray(triangles, dtype=np.uint32),
        vertex_normals=vertex_normals(vertices, triangles).astype(np.float32),
        **style,
    )


def vertex_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Area-weighted unit vertex normals (zero for unused vertices)."""
    v, f = np.asarray(vertices, dtype=float), np.asarray(triangles, dtype=np.int64)
    face = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
    n = np.stack([np.bincount(f.ravel(), np.repeat(face[:, c], 3), minlength=len(v)) for c in range(3)], -1)
    length = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def blank_frame_path(model: mujoco.MjModel) -> str:
    """Entity path of the blank frame: a child of the body that carries site ``blank_frame``."""
    return f"{body_path(model, model.site_bodyid[model.site(BLANK_SITE).id])}/{BLANK_SITE}"


def snapshot_passes(motion: MotionRecord, times: np.ndarray) -> np.ndarray:
    """The pass (0-based) each snapshot time belongs to: the last pass begun at or before it (0 before any)."""
    begun = np.maximum.accumulate(np.asarray(motion.pass_index))
    at = np.clip(np.searchsorted(motion.t, times, side="right") - 1, 0, len(motion.t) - 1)
    return np.maximum(begun[at], 0)


def log_snapshots(
    rec: rr.RecordingStream, model: mujoco.MjModel, snapshots: Sequence[Snapshot], motion: MotionRecord | None = None
) -> None:
    """Part 2: the blank frame (static, relative to its body) and the blank meshes at their times, one entity per
    pass (``.../blank/pass_<n>``, n from 1 as the report counts passes; the previous pass's stock cleared when the
    next one shows), so that passes can be told apart and compared."""
    site = model.site(BLANK_SITE).id
    frame = blank_frame_path(model)
    rec.log(
        frame,
        rr.Transform3D(translation=model.site_pos[site] * M_TO_MM, quaternion=_xyzw(model.site_quat[site])),
        static=True,
    )
    ordered = sorted(snapshots, key=lambda s: float(s[0]))
    times = np.array([float(s[0]) for s in ordered])
    passes = snapshot_passes(motion, times) if motion is not None and len(times) else np.zeros(len(times), int)
    shown, topology = None, {}
    for (time, vertices, triangles), k in zip(ordered, passes, strict=True):
        rec.set_time(TIMELINE, duration=float(time))
        entity = f"{frame}/blank/pass_{int(k) + 1}"
        if shown is not None and shown != entity:
            rec.log(shown, rr.Clear(recursive=False))
        same = entity in topology and np.array_equal(topology[entity], triangles)
        if same:  # the same triangles (the dexel stock's are): only the vertices move, the recording stays small
            normals = vertex_normals(vertices, triangles).astype(np.float32)
            rec.log(
                entity, rr.Mesh3D.from_fields(vertex_positions=np.asarray(vertices, np.float32), vertex_normals=normals)
            )
        else:
            rec.log(entity, _mesh3d(vertices, triangles, albedo_factor=(190, 190, 200, 255)))
            topology[entity] = np.asarray(triangles)
        shown = entity
    rec.reset_time()


#: the mark of the chip being cut: its colour and its radius [mm] for the largest chip (smaller chips by the cube root)
CHIP_COLOUR, CHIP_RADIUS = (255, 200, 0, 255), 0.8


def log_engagements(rec: rr.RecordingStream, model: mujoco.MjModel, t: np.ndarray, point: np.ndarray, volume) -> None:
    """The chip being cut, on the blank (``.../blank_frame/chip``): at each engagement's time a point where the
    engaged edge's centroid is, in the edges' colour, sized by the chip's volume (the viewer shows the latest: the
    current chip; between passes the last one stays until the next pass cuts)."""
    volume = np.asarray(volume, dtype=float)
    size = CHIP_RADIUS * np.cbrt(volume / max(float(volume.max()), 1e-12))
    entity = f"{blank_frame_path(model)}/chip"
    rec.send_columns(
        entity,
        indexes=[rr.TimeColumn(TIMELINE, duration=np.asarray(t, dtype=float))],
        columns=rr.Points3D.columns(
            positions=np.asarray(point, dtype=np.float32),
            radii=size.astype(np.float32),
            colors=np.tile(np.array(CHIP_COLOUR, dtype=np.uint8), (len(t), 1)),
        ).partition([1] * len(t)),
    )


# ---- 3. the cutter path ----------------------------------------------------------------------------------
def path_points(trans: np.ndarray, points_per_rev: int = 72) -> np.ndarray:
    """The cutter centre path decimated to about ``points_per_rev`` points per turn about the blank axis
    (the last point kept)."""
    trans = np.asarray(trans, dtype=float)
    if len(trans) < 3:
        return trans
    turn = np.abs(np.diff(np.unwrap(np.arctan2(trans[:, 1], trans[:, 0]))))
    step = max(1, int(2 * np.pi / points_per_rev / max(float(np.median(turn)), 1e-12)))
    keep = np.unique(np.append(np.arange(0, len(trans), step), len(trans) - 1))
    return trans[keep]


def log_cutter_paths(rec: rr.RecordingStream, passes: Sequence[PassTrajectory]) -> None:
    """Part 3: per feed stroke the cutter centre in the blank frame, static, ``/gear/cutter_path/pass_<n>`` (n from
    1, as the report and the setting sheet count passes)."""
    rec.log(GEAR, rr.ViewCoordinates.RIGHT_HAND_Z_UP, static=True)
    for p in passes:
        rec.log(
            f"{GEAR}/cutter_path/pass_{p.index + 1}",
            rr.LineStrips3D(
                [path_points(p.trans)],
                colors=[PASS_COLOURS[p.index % len(PASS_COLOURS)]],
                labels=[f"pass {p.index + 1}"],
                radii=[0.05],
            ),
            static=True,
        )


# ---- 4. time series --------------------------------------------------------------------------------------
def segment_events(motion: MotionRecord) -> tuple[np.ndarray, list[str]]:
    """Times [s] and texts of the program's segment changes (``feed, pass 1``...: passes counted from 1 as the report
    counts them), the first tick included, and the end of the record (the run stops after its last feed stroke)."""
    key = np.stack([motion.segment, motion.pass_index], -1)
    start = np.flatnonzero(np.r_[True, np.any(key[1:] != key[:-1], axis=1)])
    texts = [
        SEGMENTS[motion.segment[i]] + (f", pass {motion.pass_index[i] + 1}" if motion.pass_index[i] >= 0 else "")
        for i in start
    ]
    times = motion.t[start]
    if len(motion.t) and start[-1] != len(motion.t) - 1:
        last = int(np.max(motion.pass_index)) + 1
        times = np.r_[times, motion.t[-1]]
        texts.append(f"end of the record ({SEGMENTS[motion.segment[-1]]}" + (f", pass {last} done)" if last else ")"))
    return times, texts


def motor_names(actuators: Sequence[str]) -> list[str]:
    """The actuators' names as the structure's figure has them (the bare name where the structure is not known)."""
    return list(MOTORS.get(tuple(actuators), tuple(actuators)))


def series_entity(label: str) -> str:
    """The entity of an extra series: its label without the unit ("cutting force [N]" -> cutting_force)."""
    return _part(re.sub(r"\s*\[[^]]*\]\s*$", "", label).replace(" ", "_"))


def signals_legend(actuators: Sequence[str]) -> str:
    """What the signals' element names mean (a document beside the time series)."""
    lines = ["# Signals", "", "| name | element |", "|---|---|"]
    lines += [f"| {k} | {v} |" for k, v in ELEMENTS.items()]
    lines += [f"| {name.split()[0]} | {' '.join(name.split()[1:])} |" for name in motor_names(actuators)]
    lines += [
        "",
        "Spindle speeds in rpm (B1, B2, TV), slide positions in mm (P3 from the face's middle, X the centre distance), "
        "motor torques in N m; sync error: the work spindle's lag behind the tool spindle as arc on the work "
        "reference circle [um]. Every series is drawn min-max: its peaks show at any zoom.",
        "",
        "Program segments: " + ", ".join(f"{k} {s}" for k, s in enumerate(SEGMENTS)),
    ]
    return "\n".join(lines)


def from_pass_start(motion: MotionRecord, values: np.ndarray) -> np.ndarray:
    """``values`` less their value where the pass each sample belongs to began (the last pass begun at or before
    it; before the first, the record's start): every feed stroke reads from 0, so the passes compare."""
    k = np.asarray(motion.pass_index)
    begins = (k >= 0) & np.r_[True, k[1:] != k[:-1]]
    anchor = np.maximum.accumulate(np.where(begins, np.arange(len(k)), 0))
    return np.asarray(values) - np.asarray(values)[anchor]


def log_signals(
    rec: rr.RecordingStream, motion: MotionRecord, series: Mapping[str, tuple[np.ndarray, np.ndarray]]
) -> None:
    """Part 4: spindle speeds, slide positions, synchronisation error, motor torques, the program's segment and the
    extra series (labels with their units: "cutting force [N]"), all at the record's full rate, each element
    named as the seeds name it, with a legend document."""
    t = motion.t
    columns = [AXES.index(a) for a in SPINDLES]
    rpm = np.gradient(motion.q[:, columns], t, axis=0) * 60 / (2 * math.pi) if len(t) > 1 else motion.q[:, columns] * 0
    send_series(rec, f"{SIGNALS}/axes/spindles", t, rpm, [f"{a} {ELEMENTS[a]} [rpm]" for a in SPINDLES], LINE_COLOURS)
    for axis, entity in zip(LINEAR_AXES, ("carriage", "radial_slide"), strict=True):
        label = [f"{axis} {ELEMENTS[axis]}, from the pass's start [mm]"]
        values = from_pass_start(motion, motion.q[:, AXES.index(axis)])
        send_series(rec, f"{SIGNALS}/axes/{entity}", t, values, label, LINE_COLOURS)
    send_series(rec, f"{SIGNALS}/sync_error", t, motion.sync_um, ["sync error [um]"], LINE_COLOURS)
    names = [f"{m} [N m]" for m in motor_names(motion.actuators)]
    send_series(rec, f"{SIGNALS}/torque", t, motion.torque, names, LINE_COLOURS)
    send_series(rec, f"{SIGNALS}/program/segment", t, motion.segment, ["program segment (legend)"], LINE_COLOURS)
    cutting = motion.cutting.astype(float)
    send_series(rec, f"{SIGNALS}/program/cutting", t, cutting, ["cutter can touch the blank"], LINE_COLOURS[1:])
    # the passes marked on the shared time axis: the pass being cut (from 1, as the report counts them), 0 between
    passes = np.maximum(np.asarray(motion.pass_index, dtype=float) + 1.0, 0.0)
    send_series(rec, f"{SIGNALS}/program/pass", t, passes, ["pass being cut (0: none)"], LINE_COLOURS[2:])
    times, texts = segment_events(motion)
    rec.send_columns(
        f"{SIGNALS}/program/events",
        indexes=[rr.TimeColumn(TIMELINE, duration=times)],
        columns=rr.TextLog.columns(text=texts, level=["INFO"] * len(texts)),
    )
    rec.log(
        f"{SIGNALS}/legend",
        rr.TextDocument(signals_legend(motion.actuators), media_type=rr.MediaType.MARKDOWN),
        static=True,
    )
    for label, (ts, values) in series.items():
        width = 1 if np.ndim(values) == 1 else np.shape(values)[1]
        names = [label] if width == 1 else [f"{label} ({k})" for k in range(width)]
        send_series(rec, f"{SIGNALS}/extra/{series_entity(label)}", ts, values, names, LINE_COLOURS)


# ---- 5. measurement --------------------------------------------------------------------------------------
def _fmt(value: Any, digits: int = 2) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "-"
    return f"{value:.{digits}f}" if isinstance(value, float | np.floating) else str(value)


def measurement_markdown(measurement: Mapping[str, Any]) -> str:
    """The ISO 1328-1 class table of a measurement (deviations in um) as markdown."""
    iso = measurement.get("iso1328", {})
    tol, cls = iso.get("tolerances") or {}, iso.get("class") or {}
    rows = ["| parameter | left [um] | right [um] | tolerance [um] | class |", "|---|---:|---:|---:|---:|"]
    blocks = {
        "pitch": ("f_p", "F_p"),
        "profile": ("F_alpha", "f_Halpha", "f_falpha"),
        "helix": ("F_beta", "f_Hbeta", "f_fbeta"),
    }
    for block, keys in blocks.items():
        for key in keys:
            left, right = (measurement.get(block, {}).get(s, {}).get(key) for s in SIDES)
            rows.append(f"| {key} | {_fmt(left)} | {_fmt(right)} | {_fmt(tol.get(key))} | {_fmt(cls.get(key))} |")
    runout = measurement.get("runout", {}).get("F_r")
    rows.append(f"| F_r | {_fmt(runout)} | | {_fmt(tol.get('F_r'))} | {_fmt(cls.get('F_r'))} |")
    verdict = f"ISO 1328-1: {iso['error']}" if iso.get("error") else f"**ISO 1328-1:2013 class {cls.get('overall')}**"
    lines = ["# Measurement", "", *rows, "", verdict]
    thickness = measurement.get("thickness", {})
    balls, span = thickness.get("over_balls"), thickness.get("span") or {}
    if balls:
        lines.append(
            f"\nover balls (D = {_fmt(balls['ball_diameter_mm'], 3)} mm): M = {_fmt(balls['M_dK_mm'], 4)} mm "
            f"(nominal {_fmt(balls['M_dK_nominal_mm'], 4)})"
        )
    if span.get("k"):
        lines.append(f"\nspan W_{span['k']} = {_fmt(span['W_k_mm'], 4)} mm (nominal {_fmt(span['W_k_nominal_mm'], 4)})")
    return "\n".join(lines)


def log_measurement(
    rec: rr.RecordingStream, measurement: Mapping[str, Any] | None, charts: Sequence[str | Path]
) -> None:
    """Part 5: the chart PNGs at ``/measurement/<stem>`` and the class table at ``/measurement/summary``."""
    for chart in charts:
        rec.log(f"{MEASUREMENT}/{_part(Path(chart).stem)}", rr.EncodedImage(path=chart), static=True)
    if measurement is not None:
        text = measurement_markdown(measurement)
        rec.log(f"{MEASUREMENT}/summary", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN), static=True)


# ---- 6. the finished gear coloured by deviation ----------------------------------------------------------
def flank_band(gear: Gear, margin: float) -> tuple[float, float]:
    """Radii [mm] between which the surface is flank: from the start of the active profile on the root side
    (:func:`metrology.measure.form_roll_length`) to the tip circle, ``margin`` inside the tip."""
    from metrology.measure import form_roll_length

    form = math.hypot(gear.base_radius, form_roll_length(gear))
    if gear.internal:
        return gear.tip_radius + margin, form
    return max(form, gear.base_radius), gear.tip_radius - margin


def flank_deviation(gear: Gear, vertices: np.ndarray, margin: float = 0.01) -> tuple[np.ndarray, np.ndarray]:
    """Deviation of each vertex from the nominal flank along the base tangent [um], + = excess material.

    Each vertex belongs to the flank nearest by polar angle (side and tooth, :func:`cutting.flank.
    base_tangent_deviation` with the nearest tooth); vertices off the flanks (radius outside :func:`flank_band`,
    or within ``margin`` [mm] of an end face) get NaN. Returns (deviation [um], side index into SIDES, -1 off)."""
    v = np.asarray(vertices, dtype=float)
    e = np.stack([base_tangent_deviation(gear, v, side) for side in SIDES], -1)
    side = np.argmin(np.abs(e), axis=1)
    dev = np.take_along_axis(e, side[:, None], 1)[:, 0] * 1e3
    r_lo, r_hi = flank_band(gear, margin)
    r = np.hypot(v[:, 0], v[:, 1])
    on = (r >= r_lo) & (r <= r_hi) & (np.abs(v[:, 2]) <= gear.face_width / 2 - margin)
    return np.where(on, dev, np.nan), np.where(on, side, -1)


def deviation_colors(deviation_um: np.ndarray, limit_um: float = 5.0) -> np.ndarray:
    """RGBA (uint8) of the deviations on the report's colour map (:func:`metrology.charts.deviation_rgba`: excess
    material red, missing blue) over +-``limit_um``; grey where NaN."""
    return deviation_rgba(deviation_um, limit_um)


def deviation_markdown(deviation_um: np.ndarray, side: np.ndarray, limit_um: float) -> str:
    """Range of the flank deviation per side [um] and the colour scale, as markdown."""
    rows = ["| flank | vertices | min [um] | max [um] | mean [um] |", "|---|---:|---:|---:|---:|"]
    for k, name in enumerate(SIDES):
        d = deviation_um[side == k]
        if d.size:
            rows.append(f"| {name} | {d.size} | {d.min():+.2f} | {d.max():+.2f} | {d.mean():+.2f} |")
        else:
            rows.append(f"| {name} | 0 | - | - | - |")
    off = int(np.count_nonzero(side < 0))
    return "\n".join(
        [
            "# Finished gear: deviation from the nominal flank",
            "",
            "Along the base tangent, + = excess material (ISO 1328-1 sign).",
            f"Colours: the topography chart's map ({DEVIATION_CMAP}): blue {-limit_um:+.2f} um (missing material), "
            f"white 0, red {limit_um:+.2f} um (excess material), clipped beyond; the chart's scale (the measured "
            f"topography's largest deviation); grey: off the flanks (tip, root, end faces), {off} vertices.",
            "",
            *rows,
        ]
    )


def log_finished_gear(
    rec: rr.RecordingStream,
    gear: Gear,
    gear_mesh: Mesh,
    measurement: Mapping[str, Any] | None = None,
    at: float | None = None,
) -> None:
    """Part 6: the finished gear at ``/gear/finished`` from machine time ``at`` [s] on (None: static), and its
    measured flank deviation as the measurement took it: a surface per charted tooth and flank on the topography's
    grid (:func:`deviation_surfaces`, ``/gear/deviation/<side>/tooth_<n>``) in the topography chart's colours and
    scale, with a colour bar and the figures as text. Without a topography the gear is coloured by its vertices'
    deviation from the nominal flank (:func:`flank_deviation`)."""
    vertices, triangles = gear_mesh
    topo = (measurement or {}).get("topography")
    surfaces = deviation_surfaces(gear, measurement) if topo and "datum" in measurement["evaluation"] else []
    if at is not None:
        rec.set_time(TIMELINE, duration=at)
    static = at is None
    if surfaces:
        limit = deviation_limit(topo)
        rec.log(f"{GEAR}/finished", _mesh3d(vertices, triangles, albedo_factor=(200, 200, 205, 255)), static=static)
        for side, number, verts, tris, dev in surfaces:
            colours = deviation_rgba(dev, limit)
            rec.log(
                f"{GEAR}/deviation/{side}/tooth_{number}", _mesh3d(verts, tris, vertex_colors=colours), static=static
            )
        text = surface_markdown(topo, limit)
    else:
        limit = 5.0
        dev, side = flank_deviation(gear, vertices)
        rec.log(
            f"{GEAR}/finished", _mesh3d(vertices, triangles, vertex_colors=deviation_colors(dev, limit)), static=static
        )
        text = deviation_markdown(dev, side, limit)
    rec.reset_time()
    rec.log(f"{MEASUREMENT}/flank_deviation", rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN), static=True)
    bar = deviation_rgba(np.linspace(-limit, limit, 256), limit)[None, :, :3].repeat(24, axis=0)
    rec.log(f"{MEASUREMENT}/deviation_colours", rr.Image(bar), static=True)


#: the deviation surfaces stand this far [mm] off the nominal flank, outwards: above the gear's own faces (a few
#: micrometres from it), so the viewer draws them on top; nothing a reviewer sees at the gear's scale
SURFACE_LIFT = 0.02


def deviation_surfaces(
    gear: Gear, measurement: Mapping[str, Any]
) -> list[tuple[str, int, np.ndarray, np.ndarray, np.ndarray]]:
    """The measured flank topography as surfaces: per flank and charted tooth (side, tooth number, vertices (n, 3)
    [mm], triangles (m, 3), deviation [um] per vertex) on the measurement's own grid (roll lengths x face positions),
    each grid point on the nominal flank as the measurement's datum places it, SURFACE_LIFT outwards."""
    from types import SimpleNamespace

    from metrology.workpiece import nominal_flank

    topo, place = measurement["topography"], measurement["evaluation"]["datum"]
    datum = SimpleNamespace(rotation=math.radians(place["rotation_deg"]), z_mid=place["z_mid_mm"])
    L, z = np.asarray(topo["L_mm"], dtype=float), np.asarray(topo["z_mm"], dtype=float)
    n_l, n_z = len(L), len(z)
    i, j = (a.ravel() for a in np.meshgrid(np.arange(n_l - 1), np.arange(n_z - 1), indexing="ij"))
    a = i * n_z + j
    tris = np.concatenate([np.stack([a, a + n_z, a + n_z + 1], 1), np.stack([a, a + n_z + 1, a + 1], 1)])
    out = []
    for side in SIDES:
        for k, number in enumerate(topo["teeth"]):
            tooth = (int(number) - 1 + int(place["tooth_1_index"])) % gear.teeth
            p, n = nominal_flank(gear, datum, side, (L / gear.base_radius)[:, None], z[None, :], tooth)
            verts = (p + SURFACE_LIFT * n).reshape(-1, 3)
            dev = np.asarray(topo[side]["per_tooth_um"][k], dtype=float).ravel()
            out.append((side, int(number), verts, tris, dev))
    return out


def surface_markdown(topo: Mapping[str, Any], limit_um: float) -> str:
    """The deviation surfaces' figures per flank and tooth [um] and their colour scale, as markdown."""
    rows = ["| flank | tooth | min [um] | max [um] | mean [um] |", "|---|---:|---:|---:|---:|"]
    for side in SIDES:
        for k, number in enumerate(topo["teeth"]):
            d = np.asarray(topo[side]["per_tooth_um"][k], dtype=float)
            if np.isfinite(d).any():
                rows.append(f"| {side} | {number} | {np.nanmin(d):+.2f} | {np.nanmax(d):+.2f} | {np.nanmean(d):+.2f} |")
    return "\n".join(
        [
            "# Finished gear: measured flank deviation",
            "",
            f"On the measurement's topography grid ({len(topo['L_mm'])} roll lengths x {len(topo['z_mm'])} face "
            f"positions) of the charted teeth {', '.join(str(t) for t in topo['teeth'])}, along the base tangent, "
            "+ = excess material (ISO 1328-1 sign).",
            f"Colours: the topography chart's map and scale ({DEVIATION_CMAP}; the bar in 'Deviation colours'): blue "
            f"{-limit_um:+.2f} um (missing material), white 0, red {limit_um:+.2f} um (excess material), clipped "
            "beyond; grey where the probe found no flank.",
            "",
            *rows,
        ]
    )


# ---- 7. the blueprint ------------------------------------------------------------------------------------
def cutting_zone(model: mujoco.MjModel, setup: SkivingSetup | None) -> rrb.EyeControls3D | None:
    """The eye of the cutting-zone view: on the blank (the ``blank_frame`` site at the model's home pose, mm), from
    about two blank diameters off, above and beside it (the cutter meets the blank there); None without a blank site."""
    if BLANK_SITE not in [model.site(i).name for i in range(model.nsite)]:
        return None
    data = mujoco.MjData(model)
    data.qpos[:] = model.key_qpos[0] if model.nkey else model.qpos0
    mujoco.mj_kinematics(model, data)
    centre = data.site(BLANK_SITE).xpos * M_TO_MM
    size = 2.2 * (2 * setup.gear.tip_radius if setup is not None else 50.0)
    return rrb.EyeControls3D(
        position=centre + size * np.array([0.55, -0.75, 0.45]), look_target=centre, eye_up=[0.0, 0.0, 1.0]
    )


def recording_blueprint(
    series: Mapping[str, Any],
    chart_stems: Sequence[str],
    zone: rrb.EyeControls3D | None = None,
    motors: Sequence[str] = (),
) -> rrb.Blueprint:
    """The cutting zone (blank and cutter filling the view) and the whole machine and the gear beside it in 3D on
    the left; on the right the signals a reviewer reads together stacked on one time axis (sync error, cutting
    force, motor torques, program segment and pass), the other signals and the measurement in tabs below. The
    cutter paths are in the file but hidden (an opaque cage of ~45 turns per pass around the gear)."""
    force = [n for n in series if n.startswith("cutting force")]
    # stacked on one time axis: what a reviewer reads together (the passes marked in the program's view)
    # (their time axes linked: zoomed together; no legend boxes over plots this low: the view names say what the
    # lines are, in the legend's order and colours, and /signals/legend explains the names)
    shared = {"axis_x": rrb.TimeAxis(link=rrbc.LinkAxis.LinkToGlobal), "plot_legend": rrb.PlotLegend(visible=False)}
    stacked = [
        rrb.TimeSeriesView(origin=f"{SIGNALS}/sync_error", name="Sync error [um]", **shared),
        *(rrb.TimeSeriesView(origin=f"{SIGNALS}/extra/{series_entity(n)}", name=n, **shared) for n in force),
        rrb.TimeSeriesView(origin=f"{SIGNALS}/torque", name=f"Motor torques {', '.join(motors)} [N m]", **shared),
        rrb.TimeSeriesView(
            origin=f"{SIGNALS}/program", name="Program: segment, cutter can touch the blank, pass being cut", **shared
        ),
    ]
    signals = [
        rrb.TimeSeriesView(origin=f"{SIGNALS}/axes/spindles", name="Spindle speeds B1, B2, TV [rpm]"),
        rrb.TimeSeriesView(origin=f"{SIGNALS}/axes/carriage", name="Carriage P3 [mm]"),
        rrb.TimeSeriesView(origin=f"{SIGNALS}/axes/radial_slide", name="Radial slide X [mm]"),
    ]
    signals += [
        rrb.TimeSeriesView(origin=f"{SIGNALS}/extra/{series_entity(n)}", name=n) for n in series if n not in force
    ]
    results = [rrb.Spatial2DView(origin=f"{MEASUREMENT}/{_part(s)}", name=s) for s in chart_stems]
    results += [
        rrb.TextDocumentView(origin=f"{MEASUREMENT}/summary", name="ISO 1328 classes"),
        rrb.TextDocumentView(origin=f"{MEASUREMENT}/flank_deviation", name="Flank deviation"),
        rrb.Spatial2DView(origin=f"{MEASUREMENT}/deviation_colours", name="Deviation colours"),
        rrb.TextLogView(origin=f"{SIGNALS}/program/events", name="Program events"),
        rrb.TextDocumentView(origin=f"{SIGNALS}/legend", name="Signals: names and units"),
    ]
    spatial = [
        rrb.Spatial3DView(origin=MACHINE, name="Cutting zone [mm]", eye_controls=zone),
        rrb.Horizontal(
            rrb.Spatial3DView(origin=MACHINE, name="Machine [mm]"),
            rrb.Spatial3DView(
                origin=GEAR, contents=["+ $origin/**", "- $origin/cutter_path/**"], name="Gear in the blank frame [mm]"
            ),
        ),
    ]
    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Vertical(*spatial, row_shares=[3, 2]),
            rrb.Vertical(
                rrb.Vertical(*stacked, name="Signals on one time axis"),
                rrb.Tabs(*signals, name="More signals"),
                rrb.Tabs(*results, name="Measurement"),
                row_shares=[5, 2, 3],
            ),
            column_shares=[3, 2],
        ),
        collapse_panels=False,
    )
