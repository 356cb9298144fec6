"""Files of a simulated run: the motion record, the pose trajectory (the cutting engine's input) and a summary.

``trajectory.npz`` holds, per feed stroke i, ``pass{i}_t`` [s from the stroke's start], ``pass{i}_rot``
(n, 3, 3) and ``pass{i}_trans`` (n, 3) [mm]: the cutter frame in the blank frame (cutting/skiving/kinematics.py
conventions), plus the axis values that produced them (``pass{i}_cutter_angle`` [rad], ``pass{i}_carriage``,
``pass{i}_centre_distance`` [mm]). ``motion.npz`` holds the per-tick record (see :class:`MotionRecord`).
"""

from __future__ import annotations

import zipfile
from pathlib import Path
from typing import Any

import numpy as np

from cutting.errors import InputError, Problem
from virtual_machine.output.json_file import write_json
from virtual_machine.runtime.machine_run import SEGMENTS, MotionRecord, PassTrajectory, error_stats
from virtual_machine.runtime.physics import AXES

TRAJECTORY_FORMAT = "skive pose trajectory 1"


def summary(rec: MotionRecord, teeth: int | None = None) -> dict[str, Any]:
    """Per pass and overall: synchronisation error while cutting, peak motor torques, machine time."""
    passes = []
    for p in rec.passes:
        sel = rec.cutting & (rec.pass_index == p.index)
        e = rec.sync_um[sel]
        stroke = (rec.segment == SEGMENTS.index("feed")) & (rec.pass_index == p.index)
        passes.append(
            {
                "pass": p.index,
                "stroke_seconds": float(p.t[-1]),
                "sync_error_in_cut": error_stats(e),
                "peak_torque_Nm": dict(
                    zip(rec.actuators, np.abs(rec.torque[stroke]).max(axis=0).round(3).tolist(), strict=True)
                ),
            }
        )
    return {
        "machine_seconds": float(rec.t[-1]),
        "sync_error_in_cut": error_stats(rec.sync_um[rec.cutting]),
        "periodic_part": rec.periodic_part(teeth),
        "passes": passes,
    }


def save(rec: MotionRecord, out: Path, meta: dict[str, Any], teeth: int | None = None) -> dict[str, Any]:
    """Write motion.npz, trajectory.npz, simulation.json (and sync_error.png) to ``out``; returns the summary."""
    out.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(
        out / "motion.npz",
        t=rec.t,
        q=rec.q,
        axes=np.array(AXES),
        torque=rec.torque,
        actuators=np.array(rec.actuators),
        sync_um=rec.sync_um,
        segment=rec.segment,
        segments=np.array(SEGMENTS),
        pass_index=rec.pass_index,
        cutting=rec.cutting,
    )
    arrays: dict[str, np.ndarray] = {
        "format": np.array(TRAJECTORY_FORMAT),
        "passes": np.array([p.index for p in rec.passes]),
    }
    for p in rec.passes:
        for name in ("t", "rot", "trans", "cutter_angle", "carriage", "centre_distance"):
            arrays[f"pass{p.index}_{name}"] = getattr(p, name)
    np.savez_compressed(out / "trajectory.npz", **arrays)
    if rec.model_xml:
        write_model(rec.model_xml, out)
    doc = {**meta, **summary(rec, teeth)}
    write_json(out / "simulation.json", doc)
    _chart(rec, out / "sync_error.png")
    return doc


SCENE = """<mujoco model="skive scene">
  <!-- open with: python -m mujoco.viewer --mjcf=scene.xml -->
  <include file="{machine}"/>
  <visual><headlight ambient="0.4 0.4 0.4"/></visual>
  <worldbody>
    <light pos="0.5 -1 2" dir="-0.3 0.5 -1"/>
    <geom name="floor" type="plane" size="2 2 0.1" pos="0 0 -0.4" rgba="0.85 0.85 0.85 1" contype="0" conaffinity="0"/>
  </worldbody>
</mujoco>
"""


def write_model(xml: str, out: Path, name: str = "machine.xml") -> Path:
    """The run's MJCF and a scene that includes it (floor and light), loadable in the plain MuJoCo viewer."""
    out.mkdir(parents=True, exist_ok=True)
    (out / name).write_text(xml)
    scene = out / "scene.xml"
    scene.write_text(SCENE.format(machine=name))
    return scene


def load_trajectory(path: Path) -> list[PassTrajectory]:
    """The pass trajectories of a trajectory.npz; InputError (key ``--trajectory``) when the file is not one."""

    def not_one(why: str) -> InputError:
        return InputError(
            Problem(
                "--trajectory",
                str(path),
                f"not a skive pose trajectory: {why}",
                "give the trajectory.npz that `skive simulate JOB --out DIR` writes (DIR/trajectory.npz)",
            )
        )

    if not zipfile.is_zipfile(path):
        raise not_one("the file is not an npz archive (a zip of numpy arrays)")
    try:
        with np.load(path, allow_pickle=False) as z:
            if "format" not in z or str(z["format"]) != TRAJECTORY_FORMAT:
                raise not_one("the archive has no skive trajectory format mark")
            names = ("t", "rot", "trans", "cutter_angle", "carriage", "centre_distance")
            return [PassTrajectory(int(i), *(z[f"pass{int(i)}_{n}"] for n in names)) for i in z["passes"]]
    except InputError:
        raise
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile) as exc:
        raise not_one(f"{type(exc).__name__}: {exc}") from exc


def _chart(rec: MotionRecord, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    ax[0].plot(rec.t, rec.sync_um, lw=0.5, color="tab:blue")
    cut = np.where(rec.cutting, rec.sync_um, np.nan)
    ax[0].plot(rec.t, cut, lw=0.7, color="tab:red", label="cutter in the blank")
    ax[0].set_ylabel("sync error [um]\n(arc on d)")
    ax[0].legend(loc="upper right")
    for k, name in enumerate(rec.actuators):
        ax[1].plot(rec.t, rec.torque[:, k], lw=0.5, label=name)
    ax[1].set_ylabel("motor torque [N m]")
    ax[1].set_xlabel("machine time [s]")
    ax[1].legend(loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
