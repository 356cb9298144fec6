"""The tool-work loop's structural compliance as modes: each a mass on a spring and damper along one direction at
the tool (between the swivel head and the tool spindle) or at the workpiece (between the bed and the work spindle),
as MuJoCo bodies and joints, so the cut's force bends the loop and MuJoCo integrates the vibration.

A mode (:class:`LoopMode`) is what an impact test at the cutting point gives: its place (``at`` "tool" or "work"),
its ``direction`` (a unit vector in the machine frame: a translation, or the axis of a tilt), its natural
``frequency`` [Hz], damping ratio ``damping`` and modal ``stiffness`` [N/m, or N m/rad for a tilt]. Its modal mass is
m = k / (2 pi f)^2 (a tilt's modal inertia k / (2 pi f)^2 about its pivot, ``lever`` [m] behind the cutting point).

Realisation: the modes of one side are a chain of bodies, each with one slide (or hinge) joint of stiffness k and
damping c = 2 zeta sqrt(k m); the body's own mass is its modal mass less what the chain carries beyond it, so that
each joint moves the mass its mode has. The spindle and the blank beyond the chain keep their rotational inertia
about their own axis but carry no translational mass of their own: an impact test measures the whole structure's
modal mass, which includes them. Modes along orthogonal directions are uncoupled and exact; oblique ones couple
through the shared masses (the frequencies then shift: a user's modes should be the principal directions).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

SIDES = ("tool", "work")
KINDS = ("translation", "tilt")
#: the chain's own parts beyond a mode (spindle, blank) weigh nothing translationally; this keeps MuJoCo's bodies
#: regular [kg]
MIN_MASS = 1e-3


@dataclass(frozen=True)
class LoopMode:
    """One mode of the loop (see the module docstring). ``lever`` [m]: a tilt's pivot behind the cutting point (the
    tool: up the spindle axis; the work: down the table's axis)."""

    at: str
    direction: tuple[float, float, float]
    frequency: float
    damping: float
    stiffness: float
    kind: str = "translation"
    lever: float = 0.25

    @property
    def omega(self) -> float:
        return 2 * math.pi * self.frequency

    @property
    def mass(self) -> float:
        """Modal mass [kg] (translation) or modal inertia about the pivot [kg m^2] (tilt)."""
        return self.stiffness / self.omega**2

    @property
    def damping_coefficient(self) -> float:
        """c = 2 zeta sqrt(k m) [N s/m or N m s/rad]."""
        return 2 * self.damping * math.sqrt(self.stiffness * self.mass)

    def unit(self) -> np.ndarray:
        d = np.asarray(self.direction, dtype=float)
        return d / np.linalg.norm(d)

    def problems(self, name: str) -> list[str]:
        out = []
        if self.at not in SIDES:
            out.append(f"{name}.at = {self.at!r}: use 'tool' or 'work'")
        if self.kind not in KINDS:
            out.append(f"{name}.kind = {self.kind!r}: use 'translation' or 'tilt'")
        d = np.asarray(self.direction, dtype=float)
        if d.shape != (3,) or not np.all(np.isfinite(d)) or np.linalg.norm(d) < 1e-9:
            out.append(f"{name}.direction = {list(self.direction)}: a vector of three numbers, not zero")
        elif abs(np.linalg.norm(d) - 1.0) > 1e-3:
            length = float(np.linalg.norm(d))
            out.append(f"{name}.direction = {list(self.direction)}: must be a unit vector (length {length:.4f})")
        if not (math.isfinite(self.frequency) and 1.0 <= self.frequency <= 5000.0):
            out.append(f"{name}.frequency = {self.frequency}: a natural frequency from 1 to 5000 Hz")
        if not (math.isfinite(self.damping) and 0.0 < self.damping < 1.0):
            out.append(f"{name}.damping = {self.damping}: a damping ratio in (0, 1), machine structures 0.02-0.05")
        if not (math.isfinite(self.stiffness) and self.stiffness > 0):
            out.append(f"{name}.stiffness = {self.stiffness}: a modal stiffness > 0 (N/m; a tilt N m/rad)")
        if not (math.isfinite(self.lever) and self.lever >= 0):
            out.append(f"{name}.lever = {self.lever}: the tilt's pivot distance >= 0 m")
        return out


MODE_KEYS = {"at", "direction", "frequency", "damping", "stiffness", "kind", "lever"}


def parse_loop(value: Any, key: str = "loop") -> tuple[LoopMode, ...]:
    """[machine.model] ``loop``: a list of modes (tables with at, direction, frequency, damping, stiffness; kind
    and lever optional), or an empty list for a rigid loop. TypeError naming what is wrong."""
    if not isinstance(value, list | tuple):
        raise TypeError(
            f"{key!r} must be a list of modes ([[machine.model.loop]] tables with at, direction, frequency, damping, "
            f"stiffness), not {value!r}"
        )
    modes, problems = [], []
    for i, row in enumerate(value):
        name = f"{key}[{i}]"
        if isinstance(row, LoopMode):
            modes.append(row)
            continue
        if not isinstance(row, dict):
            raise TypeError(f"{name} must be a table of at, direction, frequency, damping, stiffness, not {row!r}")
        unknown = set(row) - MODE_KEYS
        missing = {"at", "direction", "frequency", "damping", "stiffness"} - set(row)
        if unknown or missing:
            raise TypeError(
                f"{name}: " + "; ".join(
                    ([f"unknown keys {sorted(unknown)}"] if unknown else [])
                    + ([f"missing {sorted(missing)}"] if missing else [])
                ) + " (a mode has at, direction, frequency, damping, stiffness; kind and lever optional)"
            )  # fmt: skip
        try:
            mode = LoopMode(
                str(row["at"]),
                tuple(float(x) for x in row["direction"]),
                float(row["frequency"]),
                float(row["damping"]),
                float(row["stiffness"]),
                str(row.get("kind", "translation")),
                float(row.get("lever", 0.25)),
            )
        except (TypeError, ValueError) as exc:
            raise TypeError(f"{name}: {exc}") from None
        problems += mode.problems(name)
        modes.append(mode)
    if problems:
        raise TypeError("; ".join(problems))
    return tuple(modes)


def mode_shape(mode: LoopMode, arm: np.ndarray, offset: np.ndarray | None = None) -> np.ndarray:
    """How far a point moves per unit modal coordinate (m/m or m/rad), machine frame: a translation moves every
    point along its direction; a tilt about its axis d through its pivot moves a point r from the pivot by d x r.
    ``arm``: the unit vector from the pivot towards the side's centre (the cutter's, the blank's), the pivot
    ``lever`` behind it; ``offset``: the point from that centre [m] (default the centre)."""
    d = mode.unit()
    if mode.kind == "translation":
        return d
    r = np.asarray(arm, dtype=float) * mode.lever + (0.0 if offset is None else np.asarray(offset, dtype=float))
    return np.cross(d, r)


def compliance(modes: tuple[LoopMode, ...], at: str, arm: np.ndarray, offset: np.ndarray | None = None) -> np.ndarray:
    """The static compliance matrix [m/N] (3 x 3) of the ``at`` side at a point (the side's centre + ``offset`` [m]):
    the sum over its modes of u u^T / k, u the mode's shape there (:func:`mode_shape`; a tilt: a force f gives the
    moment (r x f) . d = f . (d x r) and the point moves by (d x r) theta). What a static force there deflects it by."""
    c = np.zeros((3, 3))
    for m in modes:
        if m.at == at:
            u = mode_shape(m, arm, offset)
            c += np.outer(u, u) / m.stiffness
    return c


def frequency_response(
    modes: tuple[LoopMode, ...], at: str, omega: np.ndarray, arm: np.ndarray, offset: np.ndarray | None = None
) -> np.ndarray:
    """G(i omega) [m/N] (n, 3, 3) of the ``at`` side at a point (as :func:`compliance`): the sum of the modes'
    u u^T / (k (1 - r^2 + 2 i zeta r)), r = omega / omega_n."""
    omega = np.atleast_1d(np.asarray(omega, dtype=float))
    g = np.zeros((len(omega), 3, 3), dtype=complex)
    for m in modes:
        if m.at != at:
            continue
        u = mode_shape(m, arm, offset)
        r = omega / m.omega
        g += np.outer(u, u)[None] / (m.stiffness * (1 - r**2 + 2j * m.damping * r))[:, None, None]
    return g


def add_modes(parent, modes: tuple[LoopMode, ...], at: str, to_local: np.ndarray, arm: np.ndarray, beyond: float):
    """Add the ``at`` side's modes as a chain of bodies under ``parent`` (an MjSpec body) and return the innermost
    body (the spindle's parent). ``to_local`` (3, 3) turns machine-frame vectors into the parent's frame; ``arm``:
    the unit vector from a tilt's pivot to the side's centre, machine frame; ``beyond`` [kg m^2]: the transverse
    inertia of the spindle that the chain carries (its tilts turn it). Joints are named ``<at>_loop_<k>``.

    The bodies are token masses; each mode's modal mass (or inertia about its pivot) is its joint's armature, less
    what the joint moves anyway (the token masses beyond it; for a tilt, the spindle's transverse inertia): the
    joint-space mass matrix is the modes' diagonal, so modes of any directions stay uncoupled, and the armature
    carries no weight (the structure's static sag is the machine's set-up). ValueError if a tilt's modal inertia is
    less than the spindle's it turns."""
    import mujoco

    side = [m for m in modes if m.at == at]
    body = parent
    for k, mode in enumerate(side):
        carried = (len(side) - k) * MIN_MASS  # the token bodies from this one in, and the spindle's
        if mode.kind == "tilt":
            carried = beyond + (len(side) - k) * MIN_MASS * mode.lever**2
        armature = mode.mass - carried
        if armature <= 0:
            raise ValueError(
                f"loop mode at the {at} (tilt {list(mode.direction)}, {mode.frequency:g} Hz, "
                f"{mode.stiffness:g} N m/rad) has a modal inertia of {mode.mass:.4g} kg m^2, less than the "
                f"spindle's {beyond:.4g} kg m^2 it turns: give it a lower frequency or a higher stiffness"
            )
        axis = to_local @ mode.unit()
        body = body.add_body(name=f"{at}_loop_{k}")
        body.mass = MIN_MASS
        body.inertia = [1e-7, 1e-7, 1e-7]
        body.ipos = [0.0, 0.0, 0.0]
        body.explicitinertial = True
        body.gravcomp = 1.0
        if mode.kind == "translation":
            kind, pos = mujoco.mjtJoint.mjJNT_SLIDE, [0.0, 0.0, 0.0]
        else:  # about the pivot, lever behind the centre
            kind, pos = mujoco.mjtJoint.mjJNT_HINGE, (-(to_local @ np.asarray(arm, dtype=float)) * mode.lever).tolist()
        body.add_joint(
            name=f"{at}_loop_{k}",
            type=kind,
            axis=axis.tolist(),
            pos=pos,
            stiffness=mode.stiffness,
            damping=mode.damping_coefficient,
            armature=armature,
        )
    return body
