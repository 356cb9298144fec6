"""What the machine added: the gear the run cut against the ideal cut of the same job (the same cutter as made, the
same clamping, the exact kinematics, no machine), parameter by parameter and flank by flank.

The ideal cut is measured as the run's gear is (the exact swept surface of its passes, probed the same way); it
depends on the job alone, so :func:`start_ideal` measures it in a worker process while the machine runs (its
measurement costs about what the run's does: on two cores it comes nearly free). What the machine added is the
difference of the two measurements' values: its deviations, its size (span, dimension over balls) and its class.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
from typing import Any

from virtual_machine.output.formatting import class_table


def ideal_measurement(job, edge_kind: str) -> dict[str, Any]:
    """The measurement document of the job's ideal cut (runs in a worker process: picklable in and out): the exact
    kinematics on the machine as designed (its geometric errors, cutting/skiving/machine_geometry.py, and its thermal
    drift are the machine's and show in what the machine added)."""
    from cutting.skiving.edge import make_edge
    from cutting.skiving.exact_sweep import SweptVolumes
    from cutting.skiving.trajectory import ideal_passes
    from metrology.measure import measure_gear

    setup = job.skiving
    if not setup.geometry.exact or setup.thermal is not None:  # the machine's geometry and drift are the machine's:
        setup = dataclasses.replace(setup, geometry=setup.geometry.without_errors(), thermal=None)  # what it added
    exact = SweptVolumes(job.gear, make_edge(setup, edge_kind), ideal_passes(setup))
    return measure_gear(exact, job.gear)


def exact_measurement(job) -> dict[str, Any]:
    """What `skive cut` measures of a skiving ``job``'s flanks, without its solid: the exact swept surface of every
    pass on the ideal kinematics of the machine as built (its geometry and thermal drift), its datum, profiles (in
    the mid section), helices, pitch and traces measured with the job's options, and the model's scope (the study
    stage "exact": a case of `skive diagnose`'s sensitivity study in a tenth of a cut's time; the solid, the chips,
    the charts, the runout, the thickness and the class are what it leaves out)."""
    from cutting.skiving.edge import make_edge
    from cutting.skiving.exact_sweep import SweptVolumes
    from cutting.skiving.trajectory import ideal_passes
    from metrology.charts import finite
    from metrology.measure import MeasureOptions, measure_gear
    from virtual_machine.output.model_scope import model_scope

    setup = job.skiving
    exact = SweptVolumes(job.gear, make_edge(setup, job.cutter_options.edge), ideal_passes(setup))
    options = MeasureOptions.from_job(job.measurement, job.modification)
    options = dataclasses.replace(options, flanks_only=True, sections=(0.5,))  # the profile traces are the mid's
    doc = measure_gear(exact, job.gear, options)
    doc["model_scope"] = model_scope(job, None, "cut")
    return finite(doc)


def tool_maps(job, edge_kind: str) -> tuple[bytes, list] | None:
    """The working-angle maps of the job's ideal passes (cutting.skiving.working_angles.working_angle_maps: they
    depend on the job alone, and cost the run's measurement seconds) with the key of the edge they were made for;
    None if they cannot be made (the run makes them itself and says why)."""
    from cutting.skiving.edge import make_edge
    from cutting.skiving.exact_sweep import edge_key
    from cutting.skiving.working_angles import working_angle_maps

    try:
        edge = make_edge(job.skiving, edge_kind)
        return edge_key(edge), working_angle_maps(job.skiving, edge)
    except Exception:
        return None


def _measure_into(conn, job, edge_kind: str) -> None:
    """The worker's body: the tool's working-angle maps first (the run's measurement needs them), then the ideal cut's
    measurement (or the error), sent back through ``conn``."""
    try:
        conn.send(("maps", tool_maps(job, edge_kind)))
        conn.send(("ok", ideal_measurement(job, edge_kind)))
    except Exception as exc:
        conn.send(("error", f"{type(exc).__name__}: {exc}"))
    finally:
        conn.close()


class IdealReference:
    """The ideal cut's measurement, made in a worker process (a daemon: it dies with the run) from :meth:`start` on;
    :meth:`added` waits for it. The worker makes the ideal passes' working-angle maps first (:meth:`maps`)."""

    def __init__(self, job, edge_kind: str):
        ctx = multiprocessing.get_context("spawn")
        self._conn, child = ctx.Pipe(duplex=False)
        self._process = ctx.Process(target=_measure_into, args=(child, job, edge_kind), daemon=True)
        self._process.start()
        child.close()
        self.error: str | None = None
        self._messages: dict[str, Any] = {}  # what the worker sent, by kind ("maps", "ok", "error")

    def _until(self, *kinds: str) -> tuple[str, Any]:
        """The first message of one of ``kinds`` (waiting for it; the ones before it kept); ("error", why) if the
        worker ended first."""
        while not any(k in self._messages for k in kinds):
            try:
                kind, value = self._conn.recv()
            except EOFError:
                kind, value = "error", f"the worker ended without a result (exit code {self._process.exitcode})"
            self._messages[kind] = value
            if kind == "error":
                break
        kind = next((k for k in kinds if k in self._messages), "error")
        return kind, self._messages.get(kind)

    @staticmethod
    def maps(ref: IdealReference | None) -> tuple[bytes, list] | None:
        """The worker's working-angle maps and their edge's key (waiting for them; :func:`tool_maps`), None without
        a reference or if the worker could not make them."""
        if ref is None:
            return None
        kind, value = ref._until("maps", "ok")
        return value if kind == "maps" else None

    @classmethod
    def start(cls, job) -> IdealReference | None:
        """The reference of ``job``, started; None where the run makes none: a flank modification's runs (their
        path is iterated against the design, not an ideal cut), and a study's case (a worker process: the study
        compares its cases itself, and a worker may not start processes of its own)."""
        if job.modification is not None or _in_worker():
            return None
        return cls(job, job.cutter_options.edge)

    def result(self) -> dict[str, Any] | None:
        """The ideal cut's measurement (waiting for it), None if it failed (:attr:`error` says why)."""
        try:
            status, value = self._until("ok", "error")
        finally:
            self._process.join(timeout=5)
        if status == "ok":
            return value
        self.error = value
        return None

    @staticmethod
    def cancel(ref: IdealReference | None) -> None:
        """Stop the worker (the run failed or was stopped)."""
        if ref is not None and ref._process.is_alive():
            ref._process.terminate()
            ref._process.join(timeout=5)

    @staticmethod
    def added(ref: IdealReference | None, measurement: dict[str, Any]) -> dict[str, Any] | None:
        """:func:`machine_added` of the run's ``measurement`` against the reference (waiting for it), {"error":
        ...} if the reference failed, None without one."""
        if ref is None:
            return None
        ideal = ref.result()
        return machine_added(measurement, ideal) if ideal is not None else {"error": ref.error}


def _in_worker() -> bool:
    """Whether this process is a worker of a pool or a Dask cluster (a study's case runs there)."""
    if multiprocessing.current_process().daemon:
        return True
    try:
        from distributed import get_worker

        get_worker()
    except (ImportError, ValueError):
        return False
    return True


def machine_added(run: dict[str, Any], ideal: dict[str, Any]) -> dict[str, Any]:
    """The run's measurement minus the ideal cut's: per ISO 1328-1 parameter the left and right flanks' (or the
    gear's) difference [um], the size's (span W_k and dimension over balls M_dK) [um] and both classes."""
    ideal_rows = {key: (left, right) for key, left, right, _, _ in class_table(ideal)}
    deviations = {}
    for key, left, right, _, _ in class_table(run):
        i_left, i_right = ideal_rows[key]
        deviations[key] = {"left": left - i_left}
        if right is not None:
            deviations[key]["right"] = right - i_right
    size = {"M_dK_um": (run["thickness"]["over_balls"]["M_dK_mm"] - ideal["thickness"]["over_balls"]["M_dK_mm"]) * 1e3}
    if run["thickness"]["span"].get("k"):
        size["W_k_um"] = (run["thickness"]["span"]["W_k_mm"] - ideal["thickness"]["span"]["W_k_mm"]) * 1e3
    classes = {
        "run": (run["iso1328"].get("class") or {}).get("overall"),
        "ideal_cut": (ideal["iso1328"].get("class") or {}).get("overall"),
    }
    return {"deviations_um": deviations, "size": size, "class": classes}
