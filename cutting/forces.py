"""Cutting forces of one tooth engagement from the chip the removal really took (Kienzle's law).

The edge is the outline polygon without its hub chord. During the engagement [t0, t1] the part of the edge
inside the blank's envelope cuts: in skiving every pass takes a U-shaped layer along the whole engaged
profile (both flanks and the bottom), so that part is the chip's width b(t). Each edge element dl moving at
the relative speed v sweeps dl * v of chip area per second, so the chip volume is

    V = h * integral( integral(|v| dl) dt )

which gives the mean uncut chip thickness h of this engagement from the removed volume V. The force on the
workpiece at each instant is Kienzle's  Fc = kc(h) * b * h  distributed along the engaged edge, each element
pushing the material along its own velocity (the tool drags the chip with it); the cutter feels the opposite.
Its work over the engagement is exactly kc(h) * V: the chip's specific energy times its volume.

Only the main cutting force is modelled (no feed or passive components: their ratios to Fc are not in the
material table).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from cutting.materials import Material, rake_factor
from cutting.sweep import PoseFunction, place


@dataclass
class EngagementLoad:
    """The load on the workpiece over one engagement, in the blank frame: the resultant ``force`` (n, 3) [N] at
    ``point`` (n, 3) [mm] (the engaged edge's centroid) and the ``moment`` (n, 3) [N m] of the distributed
    forces about that point, at times ``t`` (n,) [s]. For rigid bodies the wrench does the same work as the
    forces along the edge. The cutter takes the opposite wrench."""

    t: np.ndarray
    force: np.ndarray
    point: np.ndarray
    moment: np.ndarray
    volume: float  # chip volume [mm^3]
    thickness: float  # mean uncut chip thickness h [mm]
    kc: float  # specific cutting force used [N/mm^2]

    @property
    def energy(self) -> float:
        """Cutting work of the engagement [J]: kc [N/mm^2] * V [mm^3] = N mm."""
        return self.kc * self.volume * 1e-3

    def peak(self) -> float:
        return float(np.linalg.norm(self.force, axis=1).max()) if len(self.t) else 0.0

    def mean(self, a: float, b: float) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """The load averaged over [a, b] [s] (a servo tick): the mean force, the force-weighted mean point and the
        mean moment about that point, so that the tick gets the engagement's impulse and angular impulse even when
        the engagement is shorter than the tick. None if they do not overlap. (Called every servo tick: the
        samples inside [a, b] are taken as they are, only its ends interpolated.)"""
        t = self.t
        if not len(t) or b <= t[0] or a >= t[-1] or b <= a:
            return None
        lo, hi = max(a, t[0]), min(b, t[-1])
        rows = self._rows
        i0, i1 = int(np.searchsorted(t, lo, "right")), int(np.searchsorted(t, hi, "left"))
        ts = np.concatenate([[lo], t[i0:i1], [hi]])
        y = np.concatenate([self._at(lo)[None], rows[i0:i1], self._at(hi)[None]])
        f, p, m = y[:, 0:3], y[:, 3:6], y[:, 6:9]
        w = np.diff(ts)

        def integral(v: np.ndarray) -> np.ndarray:  # trapezoid rule over ts
            return ((v[1:] + v[:-1]) / 2 * w[:, None]).sum(axis=0)

        mag = np.sqrt((f * f).sum(axis=1))[:, None]
        weight = float(integral(mag)[0])
        if weight <= 0:
            return None
        point = integral(mag * p) / weight
        moment = integral(m + np.cross(p - point, f) * 1e-3)
        return integral(f) / (b - a), point, moment / (b - a)

    @property
    def _rows(self) -> np.ndarray:
        rows = self.__dict__.get("_stacked")
        if rows is None:
            rows = self.__dict__["_stacked"] = np.concatenate([self.force, self.point, self.moment], axis=1)
        return rows

    def _at(self, x: float) -> np.ndarray:
        """The samples interpolated linearly at x (within the samples)."""
        t = self.t
        j = min(max(int(np.searchsorted(t, x, "right")) - 1, 0), len(t) - 2)
        f = (x - t[j]) / (t[j + 1] - t[j]) if t[j + 1] > t[j] else 0.0
        return self._rows[j] + f * (self._rows[j + 1] - self._rows[j])

    def shifted(self, dt: float) -> EngagementLoad:
        """The same load ``dt`` seconds later (the prediction for the next tooth: one cutter pitch on)."""
        return EngagementLoad(self.t + dt, self.force, self.point, self.moment, self.volume, self.thickness, self.kc)


def engaged_speed(
    pose: PoseFunction, edge: np.ndarray, times: np.ndarray, inside: Callable[[np.ndarray], np.ndarray]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per time and edge element: the element's length inside the blank [mm], its midpoint [mm] and its velocity
    relative to the workpiece [mm/s] (central difference over 1e-3 of the sampling interval)."""
    step = 1e-3 * (times[-1] - times[0]) / max(len(times) - 1, 1)
    w, w_before, w_after = (place(edge, *pose(times + d)) for d in (0.0, -step, step))
    a, b = w[:, :-1], w[:, 1:]
    mid = (a + b) / 2
    ins = inside(w).astype(float)
    share = (ins[:, :-1] + ins[:, 1:]) / 2  # an element half in the blank counts half
    length = np.linalg.norm(b - a, axis=2) * share
    vel = ((w_after[:, :-1] + w_after[:, 1:]) - (w_before[:, :-1] + w_before[:, 1:])) / (4 * step)
    return length, mid, vel


def engagement_load(
    pose: PoseFunction,
    edge: np.ndarray,
    t0: float,
    t1: float,
    volume: float,
    material: Material,
    inside: Callable[[np.ndarray], np.ndarray],
    rake_deg: float = 0.0,
    samples: int = 41,
    thickness: float | None = None,
) -> EngagementLoad:
    """The load of one engagement: ``pose`` of the cutting tooth over [t0, t1], ``edge`` its points (n, 3) in the
    cutter frame (the cutting edge, an open polyline), ``volume`` [mm^3] the chip the removal took, ``inside``
    the blank's envelope (points -> bool). ``rake_deg``: the cutter's rake angle (0: rake face on the end plane).
    ``thickness`` [mm]: the chip's mean uncut thickness where the removal measured it (the dexel chip's, normal
    to the cut surface over its footprint); it sets kc(h), while the force along the edge stays scaled so that the
    engagement's work is kc(h) V. Without it, h is the volume over the area the engaged edge sweeps.
    """
    times = np.linspace(t0, t1, samples)
    length, mid, vel = engaged_speed(pose, edge, times, inside)
    speed = np.linalg.norm(vel, axis=2)
    swept_rate = (length * speed).sum(axis=1)  # chip area swept per second [mm^2/s]
    swept = float(((swept_rate[1:] + swept_rate[:-1]) / 2 * np.diff(times)).sum())  # trapezoid rule [mm^2]
    if volume <= 0 or swept <= 0:
        zero = np.zeros((0, 3))
        return EngagementLoad(np.zeros(0), zero, zero, zero, max(volume, 0.0), 0.0, 0.0)
    h = volume / swept  # the layer the engaged edge would take if it cut all along
    h_chip = thickness if thickness is not None and thickness > 0 else h
    kc = material.kc(h_chip) * rake_factor(rake_deg)
    unit = vel / np.maximum(speed, 1e-12)[..., None]
    per_element = kc * h * length[..., None] * unit  # [N] on the workpiece, along each element's velocity
    force = per_element.sum(axis=1)
    weight = length.sum(axis=1)
    point = (length[..., None] * mid).sum(axis=1) / np.maximum(weight, 1e-12)[:, None]
    moment = np.cross(mid - point[:, None, :], per_element).sum(axis=1) * 1e-3  # N mm -> N m
    return EngagementLoad(times, force, point, moment, volume, h_chip, kc)
