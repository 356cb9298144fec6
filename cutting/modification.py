"""Flank modifications: the designed topography of each flank as its deviation from the involute helicoid.

A gear is usually made with its flanks modified (crowned, relieved, twisted), and the cut and the measurement need
the design as a deviation e(L, z) [mm] over roll length and face position (excess material positive, as every
measured deviation). :class:`Modification` holds both flanks' :class:`FlankDesign` (the shortcuts and an optional
bicubic :class:`BezierPatch`, as seed 003 describes the flank; the deviation's terms in
:meth:`FlankDesign.deviation`); :func:`design_problems` and :func:`check_design` refuse what cannot be made. The
keys and the measured figures: docs/modifications.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from cutting.errors import InputError, Problem
from cutting.flank import SIDES
from cutting.gear import MIN_TIP_THICKNESS, Gear, form_roll_length


def roll(gear: Gear, diameter: float) -> float:
    return math.sqrt(max((diameter / 2) ** 2 - gear.base_radius**2, 0.0))


@dataclass(frozen=True)
class FlankDesign:
    """One flank's design: the shortcut amounts [mm] and an optional patch of 4 x 4 [L, z, e] control points.

    Amounts are in mm like every length of a job (``lead_crowning = 0.010`` is 10 um)."""

    lead_crowning: float = 0.0
    end_relief: float = 0.0
    end_relief_length: float = 0.0
    profile_crowning: float = 0.0
    tip_relief: float = 0.0
    tip_relief_diameter: float | None = None
    helix_angle_modification: float = 0.0
    twist: float = 0.0
    patch: tuple[tuple[tuple[float, float, float], ...], ...] | None = None

    def deviation(self, gear: Gear, L, z) -> np.ndarray:
        """e [mm] at roll lengths ``L`` and face positions ``z`` (broadcast).

        e(L, z) is the deviation along the base tangent in the transverse plane (excess material positive, as every
        measured deviation; a modification that removes material is negative) over the roll length L and the face
        position z (0 at mid face): the sum of the shortcuts and, optionally, the patch:

        - ``lead_crowning`` C_beta: a parabola over the face width, e = -C_beta (2 z / b)^2 (the face ends C_beta
          low);
        - ``end_relief`` C_I over ``end_relief_length`` l from each end face: e = -C_I (|z| - (b/2 - l)) / l there;
        - ``profile_crowning`` C_alpha: a parabola over the active profile (root form to tip, L_F..L_a):
          e = -C_alpha (2 (L - L_m) / (L_a - L_F))^2, L_m its middle;
        - ``tip_relief`` C_a from ``tip_relief_diameter`` d_Ca to the tip: e = -C_a (L - L_Ca) / (L_a - L_Ca) there;
        - ``helix_angle_modification`` f_Hbeta: e = f_Hbeta z / b (more material towards +z when positive);
        - ``twist`` S_beta: the helix slope changes across the profile, e = S_beta (z / b) (L - L_m) / (L_a - L_F)
          (the helix slope at the tip minus that at the root is S_beta);
        - ``patch``: 4 x 4 control points [L, z, e] (mm) of a bicubic Bezier patch whose (L, z) must cover the flank
          without folding; e at a flank point is found by inverting the patch's (u, v) -> (L, z) map.
        """
        L, z = np.broadcast_arrays(np.asarray(L, dtype=float), np.asarray(z, dtype=float))
        b = gear.face_width
        lf, la = form_roll_length(gear), roll(gear, gear.tip_diameter_value)
        lm, span = (lf + la) / 2, la - lf
        e = np.zeros(L.shape)
        e -= self.lead_crowning * (2 * z / b) ** 2
        if self.end_relief and self.end_relief_length > 0:
            e -= self.end_relief * np.clip(
                (np.abs(z) - (b / 2 - self.end_relief_length)) / self.end_relief_length, 0, 1
            )
        e -= self.profile_crowning * (2 * (L - lm) / span) ** 2
        if self.tip_relief and self.tip_relief_diameter:
            lca = roll(gear, self.tip_relief_diameter)
            e -= self.tip_relief * np.clip((L - lca) / max(la - lca, 1e-12), 0, 1)
        e += self.helix_angle_modification * z / b
        e += self.twist * (z / b) * (L - lm) / span
        if self.patch is not None:
            e += BezierPatch(np.asarray(self.patch, dtype=float)).height(L, z)
        return e


@dataclass(frozen=True)
class Modification:
    """The design of both flanks (``left``, ``right``: :data:`cutting.flank.SIDES`)."""

    left: FlankDesign = field(default_factory=FlankDesign)
    right: FlankDesign = field(default_factory=FlankDesign)

    def flank(self, side: str) -> FlankDesign:
        return self.left if side == "left" else self.right

    def deviation(self, gear: Gear, side: str, L, z) -> np.ndarray:
        return self.flank(side).deviation(gear, L, z)


def bernstein(t: np.ndarray) -> np.ndarray:
    """The four cubic Bernstein polynomials at ``t`` (..., 4)."""
    t = np.asarray(t, dtype=float)[..., None]
    k = np.arange(4)
    return np.array([1, 3, 3, 1]) * t**k * (1 - t) ** (3 - k)


def bernstein_derivative(t: np.ndarray) -> np.ndarray:
    t = np.asarray(t, dtype=float)
    return np.stack([-3 * (1 - t) ** 2, 3 * (1 - t) ** 2 - 6 * t * (1 - t), 6 * t * (1 - t) - 3 * t**2, 3 * t**2], -1)


class BezierPatch:
    """A bicubic Bezier patch of control points P (4, 4, 3) = [L, z, e]; u runs along the first index, v the
    second. :meth:`height` inverts (u, v) -> (L, z) by Newton's method from a table's nearest point."""

    def __init__(self, control: np.ndarray):
        self.p = np.asarray(control, dtype=float)
        if self.p.shape != (4, 4, 3):
            raise ValueError(f"a patch has 4 x 4 control points [L, z, e], got shape {self.p.shape}")
        g = np.linspace(0.0, 1.0, 41)
        self.table_uv = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
        self.table_xy = self.point(self.table_uv[:, 0], self.table_uv[:, 1])[:, :2]

    def point(self, u, v) -> np.ndarray:
        return np.einsum("...i,...j,ijk->...k", bernstein(u), bernstein(v), self.p)

    def jacobian(self, u, v) -> np.ndarray:
        """d(L, z)/d(u, v) (..., 2, 2)."""
        du = np.einsum("...i,...j,ijk->...k", bernstein_derivative(u), bernstein(v), self.p[..., :2])
        dv = np.einsum("...i,...j,ijk->...k", bernstein(u), bernstein_derivative(v), self.p[..., :2])
        return np.stack([du, dv], -1)

    def fold(self) -> tuple[float, float] | None:
        """(u, v) where the (L, z) map's Jacobian changes sign or vanishes (the patch folds), else None."""
        g = np.linspace(0.0, 1.0, 33)
        u, v = np.meshgrid(g, g, indexing="ij")
        det = np.linalg.det(self.jacobian(u, v))
        sign = np.sign(np.median(det))
        bad = (det * sign) <= 1e-9 * np.abs(det).max()
        if sign == 0 or bad.any():
            i = np.argwhere(bad)[0] if bad.any() else (0, 0)
            return float(u[tuple(i)]), float(v[tuple(i)])
        return None

    def height(self, L, z) -> np.ndarray:
        """e at the flank points (L, z); NaN where the patch does not reach."""
        L, z = np.broadcast_arrays(np.asarray(L, dtype=float), np.asarray(z, dtype=float))
        target = np.stack([L.ravel(), z.ravel()], -1)
        d2 = ((target[:, None, :] - self.table_xy[None, :, :]) ** 2).sum(-1)
        uv = self.table_uv[np.argmin(d2, axis=1)].copy()
        for _ in range(30):
            p = self.point(uv[:, 0], uv[:, 1])[:, :2]
            r = p - target
            if np.abs(r).max() < 1e-12:
                break
            step = np.linalg.solve(self.jacobian(uv[:, 0], uv[:, 1]), r[..., None])[..., 0]
            uv = uv - step
        inside = (uv >= -1e-9).all(axis=1) & (uv <= 1 + 1e-9).all(axis=1)
        uvc = np.clip(uv, 0.0, 1.0)
        e = self.point(uvc[:, 0], uvc[:, 1])[:, 2]
        return np.where(inside, e, np.nan).reshape(L.shape)


def design_problems(mod: Modification, gear: Gear, prefix: str = "modification") -> list[Problem]:
    """Every reason the design cannot be made: a patch that folds or leaves part of the flank uncovered, a tip
    relief that starts off the flank, negative lengths, and more taken from the tooth than it can carry (the tip land
    left by both flanks below 0.2 mn), each reported with its key and the fix."""
    out: list[Problem] = []
    b = gear.face_width
    lf, la = form_roll_length(gear), roll(gear, gear.tip_diameter_value)
    for side in SIDES:
        d, key = mod.flank(side), f"{prefix}.{side}"
        if d.end_relief_length < 0 or d.end_relief_length > b / 2:
            out.append(
                Problem(
                    f"{key}.end_relief_length",
                    d.end_relief_length,
                    f"must lie in 0..b/2 = {b / 2:g} mm",
                    "give the relief's length from each end face",
                )
            )
        if d.end_relief and not d.end_relief_length:
            out.append(
                Problem(
                    f"{key}.end_relief_length", 0.0, "an end relief needs its length", "add end_relief_length = <mm>"
                )
            )
        if d.tip_relief:
            lo, hi = 2 * math.hypot(gear.base_radius, lf), gear.tip_diameter_value
            if d.tip_relief_diameter is None or not lo <= d.tip_relief_diameter < hi:
                out.append(
                    Problem(
                        f"{key}.tip_relief_diameter",
                        d.tip_relief_diameter,
                        f"a tip relief starts on the active profile: {lo:.3f} <= d_Ca < {hi:.3f} mm",
                        "give tip_relief_diameter between the root form and the tip diameter",
                    )
                )
        if d.patch is not None:
            try:
                patch = BezierPatch(np.asarray(d.patch, dtype=float))
            except ValueError as exc:
                out.append(Problem(f"{key}.patch", "...", str(exc), "give [[[L, z, e] x 4] x 4] in mm"))
                continue
            folded = patch.fold()
            if folded is not None:
                out.append(
                    Problem(
                        f"{key}.patch",
                        "...",
                        f"the patch folds near (u, v) = ({folded[0]:.2f}, "
                        f"{folded[1]:.2f}): its (L, z) map turns back on itself",
                        "order the control points so that L grows along the rows and z along the "
                        "columns, without crossing",
                    )
                )
                continue
            corners = np.array([[lf, -b / 2], [la, -b / 2], [lf, b / 2], [la, b / 2]])
            if np.isnan(patch.height(corners[:, 0], corners[:, 1])).any():
                out.append(
                    Problem(
                        f"{key}.patch",
                        "...",
                        f"the patch does not cover the flank (L {lf:.3f}..{la:.3f} mm, z {-b / 2:g}..{b / 2:g} mm)",
                        "extend the outer control points",
                    )
                )
    if out:
        return out
    # what both flanks take at the tip must leave a land: s_an - (|e_l| + |e_r|) / cos(alpha_a) >= 0.2 mn
    z = np.linspace(-b / 2, b / 2, 41)
    cut = sum(np.maximum(-mod.deviation(gear, side, la, z), 0.0) for side in SIDES)
    alpha_a = math.acos(gear.base_radius / gear.tip_radius)
    land = gear.tip_normal_thickness - float(cut.max()) / math.cos(alpha_a)
    if land < MIN_TIP_THICKNESS * gear.mn:
        out.append(
            Problem(
                prefix,
                f"{cut.max() * 1e3:.1f} um at the tip",
                f"the modification takes more than the "
                f"tooth can carry: it leaves a tip land of {land:.4f} mm < {MIN_TIP_THICKNESS} mn",
                "take less at the tip (tip_relief, profile_crowning, the patch) or make the teeth thicker",
            )
        )
    return out


def check_design(mod: Modification, gear: Gear, source: str = "") -> Modification:
    problems = design_problems(mod, gear)
    if problems:
        raise InputError(problems, source)
    return mod
