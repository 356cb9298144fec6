"""Pose trajectories of the cutter in the work frame, and the ideal one of a job.

A trajectory gives, for any time t, the rotation R (3x3) and translation p (3) that carry cutter-frame
points into the rotating work frame (:meth:`SkivingSetup.cutter_pose` convention), plus the cutter
angle phi0(t), from which the cutting engine knows when each cutter tooth passes the mesh. The ideal
trajectory is the exact kinematics of the job; the simulated machine will provide sampled ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from cutting.errors import InputError, Problem
from cutting.skiving.kinematics import SkivingSetup


@dataclass(frozen=True)
class PassMotion:
    """The ideal motion of one pass: phi0 = omega0 t, s = s_start + v_s t, centre distance fixed; the poses those
    axes give on the machine as built (:meth:`SkivingSetup.machine_pose`: the nominal ones on an exact machine).

    t runs from 0 to ``duration`` [s]; phi2 follows from the kinematics in :class:`SkivingSetup`.
    """

    setup: SkivingSetup
    index: int
    centre_distance: float
    omega0: float  # rad/s, the cutter angular speed
    s_start: float  # mm
    v_s: float  # mm/s, carriage speed (negative for a downward feed)
    duration: float  # s

    def pose(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return self.setup.machine_pose(self.omega0 * t, self.s_start + self.v_s * t, self.centre_distance)

    def cutter_angle(self, t: np.ndarray) -> np.ndarray:
        return self.omega0 * np.asarray(t, dtype=float)

    phi_start = 0.0  # cutter angle at t = 0 [rad]

    def time_at_angle(self, phi: np.ndarray | float) -> np.ndarray | float:
        """When the cutter is at angle ``phi`` [rad]."""
        return phi / self.omega0

    def carriage(self, t: np.ndarray) -> np.ndarray:
        return self.s_start + self.v_s * np.asarray(t, dtype=float)


def ideal_passes(setup: SkivingSetup, reverse_feed: bool | None = None) -> list[PassMotion]:
    """Every pass of the job: approach and overrun beyond the engagement zone, then the feed over the face.

    The cutter turns at n0 (sign from the speed ratio convention: phi0 grows), the carriage travels
    face width + 2 x engagement half-length + 2 x clearance at s per work revolution, downwards from
    above the face for a "down" feed, upwards from below for "up".
    """
    down = setup.feed_direction == "down" if reverse_feed is None else not reverse_feed
    omega0 = setup.tool_speed * 2 * math.pi / 60
    v = setup.axial_feed * setup.work_speed / 60
    out = []
    spans = zip(setup.pass_centre_distances, setup.pass_travel, setup.pass_middles, strict=True)
    for i, (a, travel, mid) in enumerate(spans):
        half = travel / 2
        start, v_s = mid + (half if down else -half), -v if down else v
        own = setup
        if setup.thermal is not None:  # the pass's share of the drift as its own geometry (thermal_drift.py)
            g = setup.thermal.pass_geometry(setup.geometry, i, start, v_s, travel / v)
            own = replace(setup, geometry=g, thermal=None)
        out.append(PassMotion(own, i, a, omega0, start, v_s, travel / v))
    return out


def check_poses(t: np.ndarray, rot: np.ndarray, trans: np.ndarray, source: str = "trajectory") -> None:
    """A trajectory must be finite, made of rigid rotations, and increasing in time."""
    problems = []
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(rot)) and np.all(np.isfinite(trans))):
        bad = int(np.argmax(~np.isfinite(t) | ~np.isfinite(rot).all(axis=(1, 2)) | ~np.isfinite(trans).all(axis=1)))
        problems.append(
            Problem(
                f"{source}[{bad}]",
                "nan/inf",
                "holds non-finite values",
                "check the source of the poses (a diverged simulation?)",
            )
        )
    else:
        err = np.abs(np.einsum("nji,njk->nik", rot, rot) - np.eye(3)).max(axis=(1, 2))
        det = np.linalg.det(rot)
        worst = int(np.argmax(err + np.abs(det - 1)))
        if err[worst] > 1e-9 or abs(det[worst] - 1) > 1e-9:
            problems.append(
                Problem(
                    f"{source}[{worst}]",
                    f"|R^T R - I| = {err[worst]:.2e}, det = {det[worst]:.6f}",
                    "is not a rigid rotation",
                    "give orthonormal rotation matrices with det = +1",
                )
            )
        if np.any(np.diff(t) <= 0):
            k = int(np.argmax(np.diff(t) <= 0))
            problems.append(
                Problem(
                    f"{source}.t[{k + 1}]",
                    float(t[k + 1]),
                    f"does not increase (previous {t[k]})",
                    "give strictly increasing times",
                )
            )
    if problems:
        raise InputError(problems, source)
