"""Cutting forces of vibration turning (seed 004) with a round-nosed tool: the uncut chip at each spindle angle and
the oblique model's cutting force and thrust on it (:mod:`cutting.oblique`, the skiving machine's model).

The lathe's carriage and spindle feel the cut through these forces, and a vibration that breaks the chip drops them
to zero at every break. :func:`chip_section` (and its scalar :func:`chip_arc`) is the uncut chip in closed form
(its derivation there), :class:`TurningForces` the forces on it and the spindle torque. The measured forces and what
they do to the crests: docs/face-contours-and-turning.md, "Cutting forces on the lathe"; how the nose maps onto the
model: docs/forces.md, "The other machines".
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from cutting.materials import Material
from cutting.oblique import DEFAULT_EDGE_RADIUS, ObliqueForces, material_forces
from cutting.turning.vibration import TWO_PI, TurningSetup

#: the normal rake [rad] of the lathe's tool along its nose: the turning job gives none, so the tool is taken
#: flat-faced, its face normal to the cutting speed on centre height, as the lathe's threading tool is (0 deg; a
#: guess: a positive-rake insert cuts with less force, the model's -1.95 % per degree of rake about +6 deg)
NOSE_RAKE = 0.0
#: [mm] a chip thinner than this is the closed form's rounding (~1e-15 mm where the vibration breaks the chip and
#: the nose runs on an earlier pass's circle), not a chip: no force, the edge only touches that surface
CHIP_ZERO = 1e-9


@dataclass(frozen=True)
class ChipSection:
    """The uncut chip in the axial half plane: ``area`` A [mm^2], engaged edge length ``edge`` b [mm],
    equivalent thickness ``thickness`` h = A / b [mm] and the engaged nose arc's ends ``start`` and ``end``, their
    axial offsets u from the nose's centre along the feed [mm] (the arc angle from the tip is asin(u / r_eps));
    0 where there is no chip."""

    area: np.ndarray
    edge: np.ndarray
    thickness: np.ndarray
    start: np.ndarray
    end: np.ndarray


@dataclass(frozen=True)
class NoseGeometry:
    """The round nose in the cut: r0 the workpiece radius, r_eps the nose radius, a_p the depth [mm]; the depth
    must be less than the nose radius (the nose takes the whole cut)."""

    radius: float
    nose_radius: float
    depth: float

    def __post_init__(self) -> None:
        for name in ("radius", "nose_radius", "depth"):
            v = getattr(self, name)
            if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be a finite number > 0 [mm], got {v!r}")
        if self.depth >= self.nose_radius:
            raise ValueError(
                f"depth a_p = {self.depth} mm reaches beyond the nose (r_eps = {self.nose_radius} mm): the force model "
                "needs the nose to take the whole cut; take a_p < r_eps (turning.depth) or a larger turning.nose_radius"
            )
        if self.depth >= self.radius:
            raise ValueError(f"depth a_p = {self.depth} mm must be less than the radius r0 = {self.radius} mm")

    @classmethod
    def of(cls, setup: TurningSetup) -> NoseGeometry:
        return cls(setup.radius, setup.nose_radius, setup.depth)

    @cached_property
    def reach(self) -> float:
        """u0 = sqrt(r_eps^2 - (r_eps - a_p)^2) [mm]: the axial offset where the nose meets r0."""
        return math.sqrt(self.nose_radius**2 - (self.nose_radius - self.depth) ** 2)

    @property
    def mean_radius(self) -> float:
        """r0 - a_p / 2 [mm]: where the main force acts on the workpiece (the spindle torque's arm)."""
        return self.radius - self.depth / 2


def _sqrt_integral(u: np.ndarray, re: float) -> np.ndarray:
    """F(u) = int_0^u sqrt(r_eps^2 - s^2) ds = (u sqrt(r_eps^2 - u^2) + r_eps^2 asin(u / r_eps)) / 2."""
    u = np.clip(u, -re, re)
    return 0.5 * (u * np.sqrt(re * re - u * u) + re * re * np.arcsin(u / re))


def chip_section(nose: NoseGeometry, z: np.ndarray, previous: np.ndarray) -> ChipSection:
    """The uncut chip of the nose at axial positions ``z`` [mm] (n,), the earlier passes through the same angles at
    ``previous`` [mm] (n, K; NaN where there is none). Vectorised over n.

    The workpiece frame is that of :mod:`cutting.turning.vibration` (z axial along the feed, r radial). At the
    spindle angle theta the nose (radius r_eps, centre on r_c = r0 - a_p + r_eps) stands at z = z(theta) on the tool
    path; the surface the earlier turns left at that angle is the lower envelope of their nose circles, centres
    z_k = z(theta - 2 pi k), no higher than r0. Equal circles with centres on one radius: the envelope at z is the
    circle of the nearest centre, so the new nose cuts only in its own cell between the midpoints to its nearest
    earlier passes behind (L) and ahead (R), and only where it lies below r0
    (|z - z(theta)| < u0 = sqrt(r_eps^2 - (r_eps - a_p)^2)). The uncut chip section there,

        A = int_lo^hi [min(r0, C(z - z_nb)) - C(z - z(theta))] dz,   C(u) = r_c - sqrt(r_eps^2 - u^2),

    (z_nb the nearest earlier centre), is closed form with F(u) = int sqrt(r_eps^2 - u^2) du. The engaged edge is
    the nose arc over (lo, hi), of length b; the equivalent chip thickness h = A / b (R. Woxen's equivalent chip
    thickness, 1932, used for round-nosed tools in place of f sin(kappa_r)). Plain turning (L = z - S0, no R):
    A = S0 a_p - int_{-S0/2}^{S0/2} (r_eps - sqrt(r_eps^2 - u^2)) du (S0 a_p less the crest's scallop). Where the
    vibration breaks the chip (:func:`cutting.turning.vibration.chip_breaks`: the path meets the foremost earlier
    pass, z(theta) = z_L) the cell is empty and A = 0; while the tool runs behind the foremost pass it only shaves
    the crest between the two earlier passes it lies between (A at most h(Delta) Delta, Delta their distance).
    """
    z = np.atleast_1d(np.asarray(z, dtype=float))
    prev = np.asarray(previous, dtype=float).reshape(len(z), -1)
    re, ap, r0 = nose.nose_radius, nose.depth, nose.radius
    u0, far = nose.reach, 4 * re  # a missing neighbour sits 4 r_eps away: beyond any overlap (> 2 u0)
    with np.errstate(invalid="ignore"):
        behind = np.where(prev <= z[:, None], prev, -np.inf).max(axis=1, initial=-np.inf)
        ahead = np.where(prev > z[:, None], prev, np.inf).min(axis=1, initial=np.inf)
    left = np.maximum(behind, z - far)
    right = np.minimum(ahead, z + far)
    lo = np.maximum(z - u0, 0.5 * (z + left))
    hi = np.minimum(z + u0, 0.5 * (z + right))
    mid = 0.5 * (left + right)

    def g(c: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """int_a^b (r0 - C(z - c)) dz, 0 for b <= a."""
        b = np.maximum(a, b)
        return (r0 - (r0 - ap + re)) * (b - a) + _sqrt_integral(b - c, re) - _sqrt_integral(a - c, re)

    cut = hi > lo
    area = g(z, lo, hi) - g(left, lo, np.minimum.reduce([hi, mid, left + u0]))
    area = area - g(right, np.maximum.reduce([lo, mid, right - u0]), hi)
    area = np.where(cut, np.maximum(area, 0.0), 0.0)
    edge = np.where(
        cut, re * (np.arcsin(np.clip((hi - z) / re, -1, 1)) - np.arcsin(np.clip((lo - z) / re, -1, 1))), 0.0
    )
    thickness = np.divide(area, edge, out=np.zeros_like(area), where=edge > 0)
    return ChipSection(area, edge, thickness, np.where(cut, lo - z, 0.0), np.where(cut, hi - z, 0.0))


def _f(u: float, re: float, _sqrt=math.sqrt, _asin=math.asin) -> float:
    """Scalar :func:`_sqrt_integral` for |u| <= r_eps."""
    return 0.5 * (u * _sqrt(re * re - u * u) + re * re * _asin(u / re))


def chip_area(nose: NoseGeometry, z: float, behind: float, ahead: float) -> tuple[float, float]:
    """(A [mm^2], b [mm]) of :func:`chip_arc`: the chip's area and the engaged nose arc's length."""
    area, start, end = chip_arc(nose, z, behind, ahead)
    re = nose.nose_radius
    return area, (re * (math.asin(end / re) - math.asin(start / re)) if end > start else 0.0)


def chip_arc(nose: NoseGeometry, z: float, behind: float, ahead: float) -> tuple[float, float, float]:
    """Scalar :func:`chip_section` for the simulation's loop (math, no arrays): the nose at ``z``, its nearest
    earlier passes ``behind`` (<= z) and ``ahead`` (> z) [mm] (+-inf for none); returns (A [mm^2], the engaged
    arc's ends u_1, u_2 [mm] from the nose's centre along the feed), (0, 0, 0) for no chip."""
    re, u0 = nose.nose_radius, nose.reach
    far = 4 * re
    left = behind if behind > z - far else z - far
    right = ahead if ahead < z + far else z + far
    lo, hi = max(z - u0, 0.5 * (z + left)), min(z + u0, 0.5 * (z + right))
    if hi <= lo:
        return 0.0, 0.0, 0.0
    mid = 0.5 * (left + right)
    area = (nose.depth - re) * (hi - lo) + _f(hi - z, re) - _f(lo - z, re)  # G(z; lo, hi): all within u0 of z
    b = min(hi, mid, left + u0)  # the part whose nearest earlier pass is ``left`` and lies below r0
    if b > lo:
        area -= (nose.depth - re) * (b - lo) + _f(b - left, re) - _f(lo - left, re)
    a = max(lo, mid, right - u0)
    if hi > a:
        area -= (nose.depth - re) * (hi - a) + _f(hi - right, re) - _f(a - right, re)
    return max(area, 0.0), lo - z, hi - z


@dataclass(frozen=True)
class TurningForces:
    """The oblique model (:mod:`cutting.oblique`) on the round nose's chip.

    Every element of the engaged nose arc has the tool's normal rake ``rake`` and no inclination (the nose lies in
    the plane normal to the cutting speed), and takes Woxen's equivalent thickness h = A / b, b the engaged arc
    (:func:`chip_section`): the chip spread evenly along the arc. With the model's factors f at (rake, 0), the edge
    forces K_ce, K_te and the minimum chip h_min of the edge radius ``edge_radius`` (the turning job gives none:
    the model's default), on the tool (reversed on the workpiece):

    * the cutting force F_c = (tau_s(h) f_c (h - h_min)+ + K_ce) b along the cutting speed (tangential);
    * the thrust q = tau_s(h) f_t (h - h_min)+ + K_te per unit arc, normal to the arc towards the nose's centre (off
      the work); summed over the arc from u_1 to u_2 (:class:`ChipSection`'s ``start``, ``end``) it is the feed
      force F_f = q (sqrt(r_eps^2 - u_1^2) - sqrt(r_eps^2 - u_2^2)) (axial, against the feed) and the passive force
      F_p = q (u_2 - u_1) (radial, off the work: turning's name for the thrust's radial part). The resultant of an
      even load on an arc is normal to its chord, the direction Colwell's chip-flow rule (1954) gives a round nose;
    * the model's own passive component (along the edge) is zero without inclination; a chip thinner than
      :data:`CHIP_ZERO` takes no force;
    * the spindle torque M_c = F_c (r0 - a_p / 2) (the chip's mean radius).
    """

    nose: NoseGeometry
    material: Material
    rake: float = NOSE_RAKE
    edge_radius: float = DEFAULT_EDGE_RADIUS

    def __post_init__(self) -> None:
        if not (math.isfinite(self.rake) and abs(self.rake) < math.pi / 2):
            raise ValueError(f"rake must be a normal rake angle in (-90, 90) deg [rad], got {self.rake!r}")
        if not (math.isfinite(self.edge_radius) and self.edge_radius >= 0):
            raise ValueError(f"edge_radius must be a finite number >= 0 [mm], got {self.edge_radius!r}")

    @cached_property
    def model(self) -> ObliqueForces:
        """The material's oblique model for the tool's edge radius."""
        return material_forces(self.material, self.edge_radius)

    @cached_property
    def factors(self) -> tuple[float, float]:
        """(f_c, f_t): K_c / tau_s and K_t / tau_s of the nose's elements (rake ``rake``, no inclination)."""
        fc, ft, _ = self.model.factors(self.rake, 0.0)
        return float(fc), float(ft)

    def forces(self, section: ChipSection) -> np.ndarray:
        """(n, 3) [N]: F_c (tangential), F_f (axial, against the feed), F_p (radial, off the work)."""
        b, re = np.asarray(section.edge, dtype=float), self.nose.nose_radius
        engaged = np.asarray(section.thickness) > CHIP_ZERO
        tau = self.model.shear_stress(np.where(engaged, section.thickness, 1.0))
        sheared = np.maximum(np.asarray(section.thickness) - self.model.min_chip, 0.0)
        (fc, ft), (ce, te) = self.factors, self.model.edge_coefficients
        cutting = np.where(engaged, (tau * fc * sheared + ce) * b, 0.0)
        q = np.where(engaged, tau * ft * sheared + te, 0.0)
        u1, u2 = np.asarray(section.start, dtype=float), np.asarray(section.end, dtype=float)
        feed = q * (np.sqrt(re * re - u1 * u1) - np.sqrt(re * re - u2 * u2))
        return np.column_stack([cutting, feed, q * (u2 - u1)])

    def scalar(self, area: float, start: float, end: float) -> tuple[float, float, float]:
        """(F_c, F_f, F_p) [N] of one chip (A [mm^2], the arc's ends u_1, u_2 [mm]: :func:`chip_arc`), as
        :meth:`forces`."""
        if end <= start:
            return 0.0, 0.0, 0.0
        re = self.nose.nose_radius
        b = re * (math.asin(end / re) - math.asin(start / re))
        h = area / b
        if h <= CHIP_ZERO:
            return 0.0, 0.0, 0.0
        model = self.model
        tau = model.shear_stress(h)
        sheared = h - model.min_chip if h > model.min_chip else 0.0
        (fc, ft), (ce, te) = self.factors, model.edge_coefficients
        q = tau * ft * sheared + te
        feed = q * (math.sqrt(re * re - start * start) - math.sqrt(re * re - end * end))
        return (tau * fc * sheared + ce) * b, feed, q * (end - start)

    def spindle_torque(self, fc: np.ndarray | float) -> np.ndarray | float:
        """M_c = F_c (r0 - a_p / 2) [N m] (F_c [N])."""
        return fc * self.nose.mean_radius * 1e-3


#: [mm] how far a machine's path may stray from its command (the lathe's corner errors are ~0.07 mm), for
#: :func:`reach_turns`
PATH_SLACK = 0.1


def reach_turns(setup: TurningSetup, slack: float = PATH_SLACK) -> int:
    """K: the earlier turns that can hold the nose's nearest passes behind and ahead (the only ones that bound
    its chip). Pass k lies z(theta) - k S0 + a(theta) - a(theta - 2 pi k) from the nose: ahead only while k S0 <
    2 A, and the pass k > 2 A / S0 is behind; with the machine's ``slack`` [mm] on 2 A, K = ceil((2 A + slack) /
    S0) + 1."""
    return math.ceil((2 * setup.amplitude + slack) / setup.feed) + 1


def path_forces(
    setup: TurningSetup, forces: TurningForces, theta: np.ndarray, turns: int | None = None
) -> tuple[ChipSection, np.ndarray]:
    """The chip and the forces (n, 3) [N] along the path ``setup`` describes at the spindle angles ``theta`` [rad]:
    the earlier passes are the path at theta - 2 pi k, k = 1..K (:func:`reach_turns`), all of them (the cut is in
    its steady state: as if the path had been followed for K turns before)."""
    theta = np.asarray(theta, dtype=float)
    k = np.arange(1, (turns or reach_turns(setup)) + 1)
    z = np.asarray(setup.path(theta))
    prev = np.asarray(setup.path(theta[:, None] - TWO_PI * k[None, :]))
    section = chip_section(forces.nose, z, prev)
    return section, forces.forces(section)


class ChipTracker:
    """The cut as the simulated lathe makes it: called at every physics step with the time t [s], the spindle
    angle theta [rad, from the start] and the tool's axial position z [mm along the feed] it has now, it keeps the
    path made so far and returns the forces (F_c, F_f, F_p) [N] of the chip between the nose there and the surface
    the earlier turns of that path left (K = ``turns`` turns back). Before the simulation started (theta < 0) the
    path is ``before(theta)`` (the lathe was cutting as commanded); no force before the time ``engage`` [s] (the
    tool meets the work at speed, after the run-up) nor where the spindle does not advance. ``capacity``: the
    physics steps expected (the history grows beyond it if needed)."""

    def __init__(
        self,
        forces: TurningForces,
        turns: int,
        before: Callable[[np.ndarray], np.ndarray],
        engage: float,
        capacity: int,
        samples_per_rev: int = 3600,
    ):
        self.forces, self.turns, self.engage = forces, int(turns), float(engage)
        pre = np.linspace(-TWO_PI * (self.turns + 1), 0.0, samples_per_rev * (self.turns + 1), endpoint=False)
        self._n0 = len(pre)
        self._theta = np.empty(self._n0 + capacity)
        self._z = np.empty(self._n0 + capacity)
        self._theta[: self._n0], self._z[: self._n0] = pre, np.asarray(before(pre), dtype=float)
        self._n = self._n0
        self._back = TWO_PI * np.arange(1, self.turns + 1)

    def _push(self, theta: float, z: float) -> bool:
        n = self._n
        if theta <= self._theta[n - 1]:
            return False
        if n == len(self._theta):
            self._theta = np.concatenate([self._theta, np.empty(n)])
            self._z = np.concatenate([self._z, np.empty(n)])
        self._theta[n], self._z[n] = theta, z
        self._n = n + 1
        return True

    def __call__(self, t: float, theta: float, z: float) -> tuple[float, float, float]:
        advanced = self._push(theta, z)
        if not advanced or t < self.engage:
            return 0.0, 0.0, 0.0
        n = self._n
        behind, ahead = -math.inf, math.inf
        for p in np.interp(theta - self._back, self._theta[:n], self._z[:n]).tolist():
            if p <= z:
                behind = p if p > behind else behind
            elif p < ahead:
                ahead = p
        return self.forces.scalar(*chip_arc(self.forces.nose, z, behind, ahead))
