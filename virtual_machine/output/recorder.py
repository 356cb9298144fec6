"""The one way skive writes a Rerun recording (.rrd): a :class:`Recorder` opens the file, keeps the timeline of
machine time and no wall clock, and takes what a process logs: time series, meshes, images, text.

Every process records through it (skiving's full recording in :mod:`virtual_machine.output.recording`; form
milling, face contours and turning log their axes, errors and workpiece), so a recording reads the same whatever
made it: lengths in mm, timeline ``sim_time`` = simulated seconds, static entities for what does not move.

    with Recorder(path, "skive_turning") as rec:
        rec.series("lathe/carriage_mm", t, values, ["made", "commanded"])
        rec.mesh_file("workpiece", stl_path)
"""

from __future__ import annotations

import datetime
import hashlib
import socket
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr
import rerun.blueprint as rrb

from virtual_machine.processes.options import DEFAULT_VIEWER

TIMELINE = "sim_time"

#: every process's recordings show under one application; each run is its own recording (run_recording_id)
APP_ID = "skive"
#: how the viewer draws many samples per pixel: the least and the largest, so a 4 kHz signal keeps its peaks at any
#: zoom (the viewer's default averages them: a 1,118 N force peak showed as ~995 N)
AGGREGATION = "MinMax"


def check_viewer(url: str, timeout: float = 2.0) -> None:
    """InputError unless a Rerun viewer (or its server) answers at ``url`` (``rerun+http://host:port/proxy``): a run
    streamed to no viewer would log into the void, so ``--view`` asks before the run starts (nothing is lost)."""
    from urllib.parse import urlparse

    from cutting.errors import InputError, Problem

    parts = urlparse(url)
    fix = f"start a viewer with `rerun` (it listens on {DEFAULT_VIEWER}), give its address, or leave out --view"
    if not parts.scheme.startswith("rerun") or parts.hostname is None or parts.port is None:
        raise InputError(Problem("--view", url, "not a Rerun viewer's address", f"e.g. {DEFAULT_VIEWER}; {fix}"))
    try:
        socket.create_connection((parts.hostname, parts.port), timeout=timeout).close()
    except OSError as exc:
        raise InputError(
            Problem("--view", url, f"no Rerun viewer answers there ({exc.strerror or exc})", fix)
        ) from None


def run_recording_id(job_text: str, started: datetime.datetime | None = None) -> str:
    """A recording id of one run: the job's hash (its text's SHA-256, 12 hex digits) and the run's start (UTC, to the
    microsecond), so that two runs of the same job open side by side in one viewer instead of merging."""
    at = started or datetime.datetime.now(datetime.UTC)
    digest = hashlib.sha256(job_text.encode("utf-8")).hexdigest()[:12]
    return f"{digest}-{at.strftime('%Y%m%dT%H%M%S%fZ')}"


class Recorder:
    """One .rrd file. ``app_id``: the application the viewer shows; ``recording_id``: the recording's id and name
    (default: Rerun's random id; a run's: :func:`run_recording_id`); ``blueprint``: the default layout;
    ``documents``: texts the run is read with (name -> text, under ``/run/<name>``: the job, the setting sheet);
    ``view``: also stream it to the Rerun viewer at that address (:func:`check_viewer` first).
    Use as a context manager (the file is flushed and closed on exit, also when logging fails); ``stream`` is the
    underlying RecordingStream for the archetypes this interface does not wrap."""

    def __init__(
        self,
        path: str | Path,
        app_id: str,
        *,
        recording_id: str | None = None,
        blueprint: rrb.Blueprint | None = None,
        documents: Mapping[str, str] | None = None,
        view: str | None = None,
    ) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        kw: dict[str, Any] = {"recording_id": recording_id} if recording_id is not None else {}
        self.stream = rr.RecordingStream(app_id, send_properties=False, **kw)
        if view is None:
            self.stream.save(self.path, default_blueprint=blueprint)
        else:  # the file and a viewer (``view``: its address) take the same recording
            self.stream.set_sinks(rr.FileSink(str(self.path)), rr.GrpcSink(view), default_blueprint=blueprint)
            if blueprint is not None:  # the viewer showed the run's live signals in a layout of its own
                self.stream.send_blueprint(blueprint, make_active=True)
        rr.set_log_time_enabled(False, recording=self.stream)  # no wall clock: the same run, the same timeline
        if recording_id is not None:
            self.stream.send_recording_name(recording_id)
        for name, text in (documents or {}).items():  # the run's job text, setting sheet, ... under /run
            self.stream.log(f"/run/{name}", rr.TextDocument(text, media_type=rr.MediaType.TEXT), static=True)

    def __enter__(self) -> Recorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self.stream.flush()
        self.stream.disconnect()

    def series(self, entity: str, t: np.ndarray, values: np.ndarray, names: Sequence[str]) -> None:
        """A bulk scalar series over machine time ``t`` [s]: ``values`` (n,) or (n, k), one line name per column."""
        send_series(self.stream, entity, t, values, list(names))

    def mesh(self, entity: str, vertices: np.ndarray, triangles: np.ndarray, **style: Any) -> None:
        """A static triangle mesh (vertices in mm); ``style``: further Mesh3D fields (colours, normals)."""
        self.stream.log(
            entity,
            rr.Mesh3D(vertex_positions=np.asarray(vertices), triangle_indices=np.asarray(triangles), **style),
            static=True,
        )

    def mesh_file(self, entity: str, path: str | Path) -> None:
        """A static mesh read from an STL (or any file trimesh reads)."""
        import trimesh

        m = trimesh.load(path, force="mesh")
        self.mesh(entity, m.vertices, m.faces)

    def image(self, entity: str, path: str | Path) -> None:
        """A static encoded image (a chart PNG)."""
        self.stream.log(entity, rr.EncodedImage(path=path), static=True)

    def markdown(self, entity: str, text: str) -> None:
        """A static text document (e.g. a measurement's class table)."""
        self.stream.log(entity, rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN), static=True)


def send_series(
    stream: rr.RecordingStream,
    entity: str,
    t: np.ndarray,
    values: np.ndarray,
    names: list[str],
    colours: Sequence[tuple[int, int, int]] | None = None,
) -> None:
    """A bulk scalar series with its line names (static SeriesLines, drawn min-max; ``colours``: one per line from
    the start of the sequence) on the ``sim_time`` timeline."""
    style: dict[str, Any] = {"colors": [colours[k % len(colours)] for k in range(len(names))]} if colours else {}
    stream.log(entity, rr.SeriesLines(names=names, aggregation_policy=AGGREGATION, **style), static=True)
    stream.send_columns(
        entity,
        indexes=[rr.TimeColumn(TIMELINE, duration=np.asarray(t, dtype=float))],
        columns=rr.Scalars.columns(scalars=np.asarray(values, dtype=float)),
    )


class LiveView:
    """A run as it goes, streamed to a Rerun viewer at ``url`` (``skive run --view``) under the run's
    ``recording_id``, so that the full recording made at the end joins it in the same viewer: the machine's carriage
    P3 and radial slide X [mm] and the cutting force [N] under ``/live``, sent a chunk of machine time at a time.
    Raises InputError (:func:`check_viewer`) when no viewer answers."""

    def __init__(self, url: str, recording_id: str, app_id: str = APP_ID):
        check_viewer(url)
        self.stream = rr.RecordingStream(app_id, recording_id=recording_id, send_properties=False)
        self.stream.connect_grpc(url)
        rr.set_log_time_enabled(False, recording=self.stream)
        for entity, name in (("carriage", "P3 carriage [mm]"), ("radial_slide", "X radial slide [mm]")):
            self.stream.log(
                f"/live/{entity}", rr.SeriesLines(names=[name], aggregation_policy=AGGREGATION), static=True
            )
        force = rr.SeriesLines(names=["cutting force [N]"], aggregation_policy=AGGREGATION)
        self.stream.log("/live/cutting_force", force, static=True)

    def __call__(self, machine_rows: np.ndarray, load_rows: np.ndarray) -> None:
        """The machine's new rows (t [s], B1, B2 [rad], P3, X [m], TV [rad]) and load rows (t [s], force (3) [N],
        torque [N m])."""
        if len(machine_rows):
            t = [rr.TimeColumn(TIMELINE, duration=machine_rows[:, 0])]
            for entity, column in (("carriage", 3), ("radial_slide", 4)):
                scalars = rr.Scalars.columns(scalars=machine_rows[:, column] * 1e3)
                self.stream.send_columns(f"/live/{entity}", indexes=t, columns=scalars)
        if len(load_rows):
            force = np.linalg.norm(load_rows[:, 1:4], axis=1)
            self.stream.send_columns(
                "/live/cutting_force",
                indexes=[rr.TimeColumn(TIMELINE, duration=load_rows[:, 0])],
                columns=rr.Scalars.columns(scalars=force),
            )

    def close(self) -> None:
        self.stream.flush()
        self.stream.disconnect()
