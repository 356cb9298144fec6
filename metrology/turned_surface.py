"""Measuring a turned surface (seed 004, "Вибрационное точение"): its crests, the roughness Rt over the spindle
angles, and what the surface and the chips show, from the workpiece the caller hands over.

What is measured: in the axial half plane at the spindle angle phi the turned profile r(z) (z axial, r radial),
its crests (the local maxima between the valleys two neighbouring tool paths leave; the height of each above the
lower of its two valleys is its peak to valley, Rt of that crest) in the window of the surface the turns left
finished (:meth:`cutting.turning.vibration.TurningSetup.window`); over ``n_phi`` angles the largest crest at each
(Rt) and the mean crest, against the seed's prediction from the path positions alone
(:func:`cutting.turning.vibration.predicted_crests`: h(Delta) = r_eps - sqrt(r_eps^2 - Delta^2 / 4) between
neighbouring paths Delta apart).

Two workpieces are measured: the exact surface, the lower envelope of the nose circles sampled every 0.1 um
(:class:`cutting.turning.vibration.SurfaceProfile`, which a :class:`cutting.turning.vibration.TurningSetup`, or the
:class:`cutting.turning.vibration.SampledTurning` of a path a machine made, answers at each angle with
:meth:`~cutting.turning.vibration.TurningSetup.surface`): its crests are cusps of two arcs, refined between the
samples; and the manifold3d solid (:class:`cutting.turning.vibration.TurnedSolid`), sliced in the axial half plane:
its crests are vertices of the section. They agree within the solid's chord and nose tolerances.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cutting.turning.vibration import (
    MIN_CREST,
    TWO_PI,
    Crests,
    SurfaceProfile,
    TurnedSolid,
    TurningSetup,
    checked_count,
    checked_revs,
    chip_breaks,
    crest_height,
)

__all__ = [
    "Roughness",
    "crest_heights",
    "profile_crests",
    "roughness",
    "solid_crests",
    "solid_section",
    "turned_surface_summary",
]


@dataclass(frozen=True)
class Roughness:
    """Crests over many spindle angles: the largest crest ``rt`` at each angle ``phi`` and the mean of all crests
    (``crest_mean``, [mm])."""

    phi: np.ndarray
    rt: np.ndarray
    crest_mean: float

    @property
    def rt_max(self) -> float:
        """The largest crest over all angles [mm]."""
        return float(self.rt.max())

    @property
    def rt_mean(self) -> float:
        """The mean over the angles of the largest crest at each [mm]."""
        return float(self.rt.mean())


def profile_crests(
    phi: float, z: np.ndarray, r: np.ndarray, window: tuple[float, float], min_height: float, refine: bool
) -> Crests:
    """Crests of a profile r(z) (z increasing): its local maxima in the window, each measured from the lower of
    the local minima on either side; ``refine`` puts each crest where the straight lines through the two samples
    on either side meet (a sampled envelope: the crest is a cusp of two arcs)."""
    s = np.sign(np.diff(r))
    last = np.maximum.accumulate(np.where(s != 0, np.arange(len(s)), 0))
    s = s[last]  # a flat run keeps the slope it came with
    peak = np.nonzero((s[:-1] > 0) & (s[1:] < 0))[0] + 1
    valley = np.nonzero((s[:-1] < 0) & (s[1:] > 0))[0] + 1
    zs, hs, gs = [], [], []
    for i in peak:
        left = valley[valley < i]
        right = valley[valley > i]
        if len(left) == 0 or len(right) == 0:
            continue
        vl, vr = left[-1], right[0]
        zc, rc = z[i], r[i]
        if refine and 2 <= i < len(z) - 2:
            zc, rc = _cusp(z, r, i)
        if not window[0] <= zc <= window[1]:
            continue
        h = rc - min(r[vl], r[vr])
        if h >= min_height:
            zs.append(zc)
            hs.append(h)
            gs.append(z[vr] - z[vl])
    return Crests(phi, np.array(zs), np.array(hs), np.array(gs))


def _cusp(z: np.ndarray, r: np.ndarray, i: int) -> tuple[float, float]:
    """The crossing of the lines through samples (i-2, i-1) and (i+1, i+2), if it lies between i-1 and i+1."""
    kl = (r[i - 1] - r[i - 2]) / (z[i - 1] - z[i - 2])
    kr = (r[i + 2] - r[i + 1]) / (z[i + 2] - z[i + 1])
    if not (kl > 0 > kr):
        return z[i], r[i]
    zc = (r[i + 1] - r[i - 1] + kl * z[i - 1] - kr * z[i + 1]) / (kl - kr)
    if not z[i - 1] <= zc <= z[i + 1]:
        return z[i], r[i]
    rc = r[i - 1] + kl * (zc - z[i - 1])
    return float(zc), float(min(max(rc, r[i]), r[i] + (z[i + 1] - z[i - 1]) * max(kl, -kr)))


def crest_heights(profile: SurfaceProfile, min_height: float = MIN_CREST) -> Crests:
    """The crests [mm] of a sampled envelope (:class:`cutting.turning.vibration.SurfaceProfile`) in its window."""
    return profile_crests(profile.phi, profile.z, profile.r, profile.window, min_height, refine=True)


def solid_section(solid: TurnedSolid, phi: float) -> tuple[np.ndarray, np.ndarray]:
    """The turned profile (z, r) [mm] of the manifold solid at the angle phi: the section polygon's vertices on the
    outer surface, sorted along z (the solid rotated so that the half plane at phi is the x > 0 half of z = 0, then
    sliced)."""
    c, s = math.cos(phi), math.sin(phi)
    m = np.array([[c, s, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [s, -c, 0.0, 0.0]])
    polys = solid.solid.transform(m).slice(0.0).to_polygons()
    v = np.vstack(polys)
    st = solid.setup
    keep = (v[:, 0] > st.tip_radius - 0.01) & (v[:, 1] > 0) & (v[:, 1] < st.feed * solid.n_revs)
    v = v[keep]
    order = np.argsort(v[:, 1], kind="stable")
    return v[order, 1], v[order, 0]


def solid_crests(solid: TurnedSolid, phi: float, min_height: float = MIN_CREST) -> Crests:
    """The crests [mm] of the manifold solid's section at phi, in the same window as the envelope's (vertices taken
    as they are: the crest is a vertex of the section, where it crosses the ridge of two passes)."""
    z, r = solid_section(solid, phi)
    return profile_crests(phi, z, r, solid.setup.window(solid.n_revs), min_height, refine=False)


def roughness(setup: TurningSetup, n_phi: int = 72, n_revs: int | None = None, predicted: bool = False) -> Roughness:
    """Crests at ``n_phi`` angles over a revolution (offset half a step from 0): the largest at each angle and the
    mean of them all, measured on the exact envelope ``setup`` answers (:meth:`TurningSetup.surface
    <cutting.turning.vibration.TurningSetup.surface>`) or, with ``predicted``, from the path positions
    (:meth:`TurningSetup.predicted_crests <cutting.turning.vibration.TurningSetup.predicted_crests>`)."""
    n_phi = checked_count("n_phi", n_phi, 1)
    phis = (np.arange(n_phi) + 0.5) * TWO_PI / n_phi
    if predicted:
        crests = [setup.predicted_crests(float(phi), n_revs) for phi in phis]
    else:
        crests = [crest_heights(setup.surface(float(phi), n_revs)) for phi in phis]
    rt = np.array([c.rt for c in crests])
    every = np.concatenate([c.height for c in crests])
    return Roughness(phis, rt, float(every.mean()) if len(every) else 0.0)


def turned_surface_summary(setup: TurningSetup, n_revs: int | None = None, n_phi: int = 72) -> dict:
    """What the turned surface and the chips show, in micrometres: the spacing range of successive paths, the
    crests measured on the exact envelope ``setup`` answers (the command's :class:`TurningSetup
    <cutting.turning.vibration.TurningSetup>` or the :class:`SampledTurning
    <cutting.turning.vibration.SampledTurning>` of a path a machine made; Rt_max, mean Rt, mean crest) and from the
    path positions alone (the geometric prediction), and the chip breaks per revolution."""
    n = checked_revs(setup, n_revs)
    measured = roughness(setup, n_phi, n)
    predicted = roughness(setup, n_phi, n, predicted=True)
    phis = np.linspace(0.0, TWO_PI, 721)[:-1]
    spacing = np.asarray(setup.spacing(phis + TWO_PI * (n // 2)))
    breaks = chip_breaks(setup, max(n, 4))
    um = 1e3
    return {
        "spacing_um": {"min": float(spacing.min() * um), "max": float(spacing.max() * um), "S0": setup.feed * um},
        "Rt_max_um": measured.rt_max * um,
        "Rt_mean_um": measured.rt_mean * um,
        "crest_mean_um": measured.crest_mean * um,
        "predicted_Rt_max_um": predicted.rt_max * um,
        "predicted_Rt_mean_um": predicted.rt_mean * um,
        "plain_turning_crest_um": float(crest_height(setup.feed, setup.nose_radius, setup.depth)) * um,
        "chip_breaks_per_rev": breaks.per_rev,
        "min_uncut_chip_um": breaks.min_thickness * um,
    }
