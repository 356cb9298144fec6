"""Vibration turning (seed 004, "Вибрационное точение"): the feed vibration, the crests it leaves and the chips
it breaks.

The seed: in plain turning the paths of neighbouring turns are Delta = S0 apart; a symmetric feed vibration varies
Delta from 0 to Delta_max > 2 S0 and the crests rise, an asymmetric one (xi = T_in / T_out != 1) lowers them, and
the vibration breaks the chip. :class:`TurningSetup` with its :class:`FeedVibration` is the tool path (its frame
there), :func:`surface_profile` the surface it leaves, :func:`predicted_crests` the crests from the path positions
alone, :func:`chip_breaks` where the chip breaks; :func:`cut_workpiece` cuts the same surface with manifold3d. Both
are measured by :mod:`metrology.turned_surface` (the envelope and the solid's axial section). What the geometry
gives, and where the seed's statement holds: docs/face-contours-and-turning.md, "Vibration turning: the geometry".
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import numbers
from dataclasses import dataclass

import manifold3d as mf
import numpy as np
from scipy.optimize import brentq

TWO_PI = 2 * math.pi
FORMS = ("soft", "hard")
#: z step of the sampled envelope [mm] (0.1 um): the crest, refined between its samples, is good to ~1e-8 mm
ENVELOPE_STEP = 1e-4
#: crests lower than this [mm] (0.01 um, two paths less than ~8 um apart) are not counted as crests
MIN_CREST = 1e-5
#: an uncut chip thinner than this [mm] is none (the rounding of z over tens of turns is ~1e-15 mm)
THICKNESS_ZERO = 1e-12
#: each swept piece runs this part of the next step on along the path, so that pieces overlap instead of
#: sharing a face (shared faces leave zero-volume slivers in manifold3d's result)
OVERLAP = 0.05


def _finite(name: str, value: float, *, low: float, strict: bool, unit: str) -> None:
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)
    ok = ok and (value > low if strict else value >= low)
    if not ok:
        raise ValueError(f"{name} must be a finite number {'>' if strict else '>='} {low:g} {unit}, got {value!r}")


@dataclass(frozen=True)
class FeedVibration:
    """The axial (feed-direction) vibration of the tool.

    Parameters
    ----------
    amplitude : float
        A [mm]: the tool moves between -A and +A about the nominal feed.
    cycles_per_rev : float
        f, vibration cycles per spindle revolution. Its fractional part shifts the vibration's phase from one
        turn to the next; an integer f shifts nothing and turns as plain turning does (Delta = S0 everywhere).
    xi : float
        Asymmetry xi = T_in / T_out: time moving with the feed (cutting in) over time moving back (retracting)
        within one cycle; 1 is symmetric. The rise takes the fraction p = xi / (1 + xi) of the cycle.
    form : str
        "soft": half cosines, -A cos(pi u / p) rising and A cos(pi (u - p) / (1 - p)) falling (u the cycle's
        phase); smooth, a pure cosine at xi = 1. "hard": straight rise and fall (a sawtooth; a triangle at
        xi = 1). Both have zero mean over a cycle. The seed's figure labels the asymmetric forms "soft" (a > b)
        and "hard" (a < b); here ``form`` is the waveform (smooth or straight strokes) and xi, either side of 1,
        is independent of it.
    """

    amplitude: float
    cycles_per_rev: float
    xi: float = 1.0
    form: str = "soft"

    def __post_init__(self) -> None:
        _finite("amplitude", self.amplitude, low=0.0, strict=False, unit="[mm]")
        _finite("cycles_per_rev", self.cycles_per_rev, low=0.0, strict=True, unit="[cycles/rev]")
        _finite("xi", self.xi, low=0.0, strict=True, unit="(xi = T_in / T_out)")
        if self.form not in FORMS:
            raise ValueError(f"form must be one of {FORMS}, got {self.form!r}")

    @property
    def rise_fraction(self) -> float:
        """p = T_in / (T_in + T_out) = xi / (1 + xi): the part of a cycle spent moving with the feed."""
        return self.xi / (1 + self.xi)

    def phase(self, theta: np.ndarray | float) -> np.ndarray:
        """u in [0, 1): the cycle's phase at the spindle angle theta [rad]; u = 0 at the back end (-A)."""
        return np.mod(self.cycles_per_rev * np.asarray(theta, dtype=float) / TWO_PI, 1.0)

    def axial(self, theta: np.ndarray | float) -> np.ndarray | float:
        """a(theta) [mm]: the tool's axial offset from the nominal feed at the spindle angle theta [rad]."""
        u = self.phase(theta)
        a, p = self.amplitude, self.rise_fraction
        rise = u < p
        if self.form == "hard":
            out = np.where(rise, -a + 2 * a * u / p, a - 2 * a * (u - p) / (1 - p))
        else:
            out = np.where(rise, -a * np.cos(math.pi * u / p), a * np.cos(math.pi * (u - p) / (1 - p)))
        return float(out) if out.ndim == 0 else out

    def curvature_bound(self) -> float:
        """Largest |d^2 a / d theta^2| [mm/rad^2] of the soft form (the hard form is straight between kinks)."""
        if self.form == "hard":
            return 0.0
        p = self.rise_fraction
        return self.amplitude * (self.cycles_per_rev / (2 * min(p, 1 - p))) ** 2

    def kinks(self, theta0: float, theta1: float) -> np.ndarray:
        """Spindle angles in [theta0, theta1] where the hard form turns (both ends of a stroke); none for soft."""
        if self.form != "hard" or self.amplitude == 0:
            return np.empty(0)
        period = TWO_PI / self.cycles_per_rev
        n = np.arange(math.floor(theta0 / period), math.ceil(theta1 / period) + 1)
        t = np.concatenate([n * period, (n + self.rise_fraction) * period])
        return np.sort(t[(t >= theta0) & (t <= theta1)])


@dataclass(frozen=True)
class Crests:
    """Crests of a turned profile at one spindle angle: positions ``z`` [mm], heights above the lower of their two
    valleys (peak to valley, Rt of each) [mm] and the distance ``gap`` [mm] of the two paths that leave them
    (predicted by :func:`predicted_crests`, measured by :mod:`metrology.turned_surface`)."""

    phi: float
    z: np.ndarray
    height: np.ndarray
    gap: np.ndarray

    @property
    def spacing(self) -> np.ndarray:
        """Distances between neighbouring crests along z [mm] (S0 in plain turning)."""
        return np.diff(self.z)

    @property
    def rt(self) -> float:
        """The largest crest [mm]."""
        return float(self.height.max()) if len(self.height) else 0.0


@dataclass(frozen=True)
class SurfaceProfile:
    """The turned surface in the axial half plane at ``phi``: radius ``r`` [mm] at the axial positions ``z``."""

    phi: float
    z: np.ndarray
    r: np.ndarray
    window: tuple[float, float]


@dataclass(frozen=True)
class ChipBreaks:
    """Where the chip breaks: the spindle angles ``angles`` [rad, cumulative] at which the uncut chip thickness
    falls to zero, counted over the revolutions ``revs`` = (first, end)."""

    angles: np.ndarray
    revs: tuple[int, int]
    min_thickness: float

    @property
    def per_rev(self) -> float:
        """Breaks, i.e. chip segments, per revolution over the counted revolutions."""
        first, end = self.revs
        counted = (self.angles >= first * TWO_PI) & (self.angles < end * TWO_PI)
        return int(counted.sum()) / (end - first)


def crest_height(delta: np.ndarray | float, nose_radius: float, depth: float) -> np.ndarray | float:
    """h = r_eps - sqrt(r_eps^2 - Delta^2 / 4) [mm], the crest between two nose circles Delta [mm] apart: the
    standard turning formula of the kinematic roughness (S0^2 / 8 r_eps for Delta = S0, to second order), not the
    seed's (seed 004 states only that the crests rise and fall with Delta); no more than the depth a_p."""
    d = np.asarray(delta, dtype=float)
    half = np.minimum(np.abs(d) / 2, nose_radius)
    h = np.minimum(nose_radius - np.sqrt(nose_radius**2 - half**2), depth)
    return float(h) if h.ndim == 0 else h


@dataclass(frozen=True)
class TurningSetup:
    """Turning with a round-nosed tool, plain or with a feed vibration.

    Workpiece frame: the tool stands at the spindle angle theta [rad, cumulative]; z is axial (the feed goes to
    +z), r radial. The round nose (radius r_eps) lies in the axial half plane at theta with its tip on the radius
    r0 - a_p, so its centre is on r_c = r0 - a_p + r_eps. The tool path is z(theta) = S0 theta / 2 pi + a(theta),
    S0 the feed per revolution, a(theta) the axial feed vibration (:class:`FeedVibration`).

    Parameters
    ----------
    radius : float
        r0, the workpiece's radius before the cut [mm].
    feed : float
        S0, the feed per revolution [mm/rev].
    nose_radius : float
        r_eps, the tool's nose radius [mm]; the nose takes the whole cut, so the depth must be less.
    depth : float
        a_p, the depth of cut [mm]: the tool tip runs on r0 - a_p.
    vibration : FeedVibration or None
        The feed vibration; None is plain turning.
    """

    radius: float
    feed: float
    nose_radius: float
    depth: float
    vibration: FeedVibration | None = None

    def __post_init__(self) -> None:
        _finite("radius", self.radius, low=0.0, strict=True, unit="[mm]")
        _finite("feed", self.feed, low=0.0, strict=True, unit="[mm/rev]")
        _finite("nose_radius", self.nose_radius, low=0.0, strict=True, unit="[mm]")
        _finite("depth", self.depth, low=0.0, strict=True, unit="[mm]")
        if self.depth >= self.nose_radius:
            raise ValueError(f"depth must be less than nose_radius ({self.nose_radius} mm), got {self.depth}")
        if self.depth >= self.radius:
            raise ValueError(f"depth must be less than radius ({self.radius} mm), got {self.depth}")
        width = 2 * math.sqrt(self.depth * (2 * self.nose_radius - self.depth))  # the nose's chord at the blank
        if self.feed >= width:  # the turns' grooves would not meet: ridges of the blank stay between them
            raise ValueError(
                f"feed must be less than the nose's width at the depth of cut, 2 sqrt(a_p (2 r_eps - a_p)) = "
                f"{width:.4g} mm (else ridges of the blank stay between the turns), got {self.feed}"
            )
        if self.vibration is not None and not isinstance(self.vibration, FeedVibration):
            raise ValueError(f"vibration must be a FeedVibration or None, got {type(self.vibration).__name__}")

    @property
    def amplitude(self) -> float:
        """A [mm], 0 in plain turning."""
        return self.vibration.amplitude if self.vibration is not None else 0.0

    @property
    def tip_radius(self) -> float:
        """r0 - a_p [mm]: the valleys' bottom."""
        return self.radius - self.depth

    @property
    def centre_radius(self) -> float:
        """r_c = r0 - a_p + r_eps [mm]: the nose centre's radius."""
        return self.radius - self.depth + self.nose_radius

    def path(self, theta: np.ndarray | float) -> np.ndarray | float:
        """z(theta) = S0 theta / 2 pi + a(theta) [mm]: the nose centre's axial position at the spindle angle."""
        z = self.feed * np.asarray(theta, dtype=float) / TWO_PI
        if self.vibration is not None:
            z = z + self.vibration.axial(theta)
        return float(z) if np.ndim(z) == 0 else z

    def passes(self, phi: float, n_revs: int) -> np.ndarray:
        """z_k [mm] of the passes through the angle phi, theta = phi + 2 pi k, k = 0 .. n_revs - 1."""
        return np.asarray(self.path(phi + TWO_PI * np.arange(n_revs)))

    def spacing(self, phi: np.ndarray | float) -> np.ndarray | float:
        """Delta = z(phi + 2 pi) - z(phi) [mm]: the axial distance between the paths of successive turns."""
        return np.asarray(self.path(np.asarray(phi) + TWO_PI)) - np.asarray(self.path(phi))

    def spacing_range(self, samples: int = 20000) -> tuple[float, float]:
        """(Delta_min, Delta_max) [mm] over a vibration cycle (Delta repeats with the vibration's period)."""
        if self.vibration is None:
            return self.feed, self.feed
        theta = np.linspace(0.0, TWO_PI / self.vibration.cycles_per_rev, samples, endpoint=False)
        d = self.spacing(theta)
        return float(d.min()), float(d.max())

    def window(self, n_revs: int) -> tuple[float, float]:
        """The axial range [mm] whose surface n_revs turns leave finished: every pass that could neighbour a point
        in it (nominal position within S0 + 3A) is among them."""
        a = self.amplitude
        lo, hi = 2 * self.feed + 3 * a, self.feed * (n_revs - 2) - 3 * a
        if hi - lo < self.feed:
            raise ValueError(f"n_revs must be at least {math.ceil(5 + 6 * a / self.feed)} here, got {n_revs}")
        return lo, hi

    def default_revs(self) -> int:
        """Turns enough for a window of about 12 feeds."""
        return math.ceil(6 * self.amplitude / self.feed) + 16

    def surface(self, phi: float, n_revs: int | None = None, dz: float = ENVELOPE_STEP) -> SurfaceProfile:
        """See :func:`surface_profile`."""
        return surface_profile(self, phi, n_revs, dz)

    def predicted_crests(self, phi: float, n_revs: int | None = None, min_height: float = MIN_CREST) -> Crests:
        """See :func:`predicted_crests`."""
        return predicted_crests(self, phi, n_revs, min_height)

    def uncut_thickness(self, theta: np.ndarray | float, previous_only: bool = False) -> np.ndarray | float:
        """See :func:`uncut_thickness`."""
        return uncut_thickness(self, theta, previous_only)

    def chip_breaks(self, n_revs: int = 24, samples_per_rev: int = 3600, previous_only: bool = False) -> ChipBreaks:
        """See :func:`chip_breaks`."""
        return chip_breaks(self, n_revs, samples_per_rev, previous_only)


def checked_count(name: str, value: int, least: int) -> int:
    """``value`` as an int, refused (naming ``name``) unless an integer >= ``least``."""
    if not isinstance(value, numbers.Integral) or isinstance(value, bool) or value < least:
        raise ValueError(f"{name} must be an integer >= {least}, got {value!r}")
    return int(value)


def checked_revs(setup: TurningSetup, n_revs: int | None) -> int:
    """The turns ``n_revs`` checked, :meth:`TurningSetup.default_revs` for None."""
    return checked_count("n_revs", setup.default_revs() if n_revs is None else n_revs, 1)


def surface_profile(
    setup: TurningSetup, phi: float, n_revs: int | None = None, dz: float = ENVELOPE_STEP
) -> SurfaceProfile:
    """The turned surface at the angle phi: the lower envelope of the nose circles of every pass through it,
    r(z) = min(r0, min_k (r_c - sqrt(r_eps^2 - (z - z_k)^2))), sampled every ``dz`` [mm] over the window and
    S0 + 2A beyond it on both sides (so that each crest in the window has both its valleys)."""
    _finite("dz", dz, low=0.0, strict=True, unit="[mm]")
    n = checked_revs(setup, n_revs)
    lo, hi = setup.window(n)
    ext = setup.feed + 2 * setup.amplitude + 10 * dz
    z = np.arange(lo - ext, hi + ext + dz, dz)
    r = np.full(len(z), setup.radius)
    re, rc = setup.nose_radius, setup.centre_radius
    for zk in setup.passes(phi, n):
        i0, i1 = np.searchsorted(z, [zk - re, zk + re])
        if i1 > i0:
            u = z[i0:i1] - zk
            np.minimum(r[i0:i1], rc - np.sqrt(np.maximum(re**2 - u * u, 0.0)), out=r[i0:i1])
    return SurfaceProfile(phi, z, r, (lo, hi))


def predicted_crests(
    setup: TurningSetup, phi: float, n_revs: int | None = None, min_height: float = MIN_CREST
) -> Crests:
    """The crests from the path positions alone: the passes z_k through phi sorted along z, each neighbouring
    pair Delta apart leaves h(Delta) (:func:`crest_height`) at its midpoint (equal circles meet there); no other
    circle reaches between two neighbours, so none is shadowed. The envelope of :func:`surface_profile` must
    reproduce them."""
    n = checked_revs(setup, n_revs)
    lo, hi = setup.window(n)
    zk = np.sort(setup.passes(phi, n))
    gap = np.diff(zk)
    mid = (zk[:-1] + zk[1:]) / 2
    h = np.asarray(crest_height(gap, setup.nose_radius, setup.depth))
    keep = (mid >= lo) & (mid <= hi) & (h >= min_height)
    return Crests(phi, mid[keep], h[keep], gap[keep])


def uncut_thickness(setup: TurningSetup, theta: np.ndarray | float, previous_only: bool = False) -> np.ndarray | float:
    """t(theta) = z(theta) - max_{j >= 1} z(theta - 2 pi j) [mm]: how far the path runs ahead of the surface the
    earlier turns left at the same angle (``previous_only``: of the previous turn alone); +inf on the first turn.
    t <= 0: the tool cuts nothing there, the chip is broken."""
    th = np.asarray(theta, dtype=float)
    k = np.floor(th / TWO_PI + 1e-12).astype(int)
    z = np.asarray(setup.path(th))
    behind = np.full(th.shape, -np.inf)
    for j in range(1, 2 if previous_only else max(int(k.max(initial=0)), 1) + 1):
        has = k >= j
        zj = np.asarray(setup.path(th - TWO_PI * j))
        behind = np.where(has, np.maximum(behind, zj), behind)
    t = z - behind
    return float(t) if t.ndim == 0 else t


def chip_breaks(
    setup: TurningSetup, n_revs: int = 24, samples_per_rev: int = 3600, previous_only: bool = False
) -> ChipBreaks:
    """The spindle angles where the uncut chip thickness (:func:`uncut_thickness`) falls to zero over ``n_revs``
    turns (sampled ``samples_per_rev`` a turn, each crossing solved to 1e-12 rad), counted per revolution from
    the third turn on (the first has no earlier surface). A dip shorter than a sample can be missed."""
    n_revs = checked_count("n_revs", n_revs, 4)
    samples_per_rev = checked_count("samples_per_rev", samples_per_rev, 16)
    n = samples_per_rev
    theta = TWO_PI * (np.arange(n_revs * n) / n)
    z = np.asarray(setup.path(theta)).reshape(n_revs, n)
    behind = z[:-1] if previous_only else np.maximum.accumulate(z, axis=0)[:-1]
    t = (z[1:] - behind).ravel()
    th = theta[n:]
    down = np.nonzero((t[:-1] > THICKNESS_ZERO) & (t[1:] <= THICKNESS_ZERO))[0]

    def f(x: float) -> float:
        return float(uncut_thickness(setup, x, previous_only))

    def root(i: int) -> float:
        if abs(t[i + 1]) <= THICKNESS_ZERO:  # the zero falls on the sample (within rounding)
            return float(th[i + 1])
        return float(brentq(f, th[i], th[i + 1], xtol=1e-12))

    angles = np.array([root(i) for i in down])
    return ChipBreaks(angles, (2, n_revs), float(t.min()))


# --- the same surface cut with manifold3d ------------------------------------------------------------------


@dataclass
class TurnedSolid:
    """The workpiece cut by manifold3d: a cylinder (r0, from z = 0 to S0 n_revs) less the nose's swept volume.

    ``chord_error`` [mm] is the largest measured distance of the sampled path's chords from the true path (for
    the nose's lowest and highest points), ``nose_error`` [mm] the sag of the nose polygon where it leaves
    crests; a crest of the solid is within about their sum of the exact envelope's. Measured (r0 = 3 mm, 1 um
    chord tolerance, 0.1 um nose tolerance, crests over 0.5 um at 24 angles): plain turning 0.05 um (the nose
    polygon; the placements fall at the same angles every turn, so their radial chord sag is common to crest and
    valley), symmetric vibration 0.10 um, hard xi = 3 0.32 um (its kinks move the placements from turn to turn,
    so neighbouring passes sag differently at one angle)."""

    setup: TurningSetup
    n_revs: int
    solid: mf.Manifold
    pieces: int
    chord_error: float
    nose_error: float
    method: str


def nose_polygon(setup: TurningSetup, nose_tolerance: float, top: float) -> tuple[np.ndarray, float]:
    """The nose section (axial offset u, radius rho) [mm] up to the radius ``top``: inscribed in the nose circle,
    its sag below ``nose_tolerance`` where crests form (within Delta_max / 2 + 0.02 mm of the tip), three steps
    beyond (the neighbouring passes cut there). Counter-clockwise; returns the polygon and its sag there."""
    re, rc = setup.nose_radius, setup.centre_radius
    a_top = math.acos((rc - top) / re)
    reach = setup.spacing_range()[1] / 2 + 0.02
    a_fine = min(math.asin(min(reach / re, 1.0)), a_top)
    step = 2 * math.acos(1 - nose_tolerance / re)
    k = math.ceil(2 * a_fine / step)
    a = np.linspace(-a_fine, a_fine, k + 1)
    if a_top > a_fine:
        side = np.linspace(a_fine, a_top, 4)[1:]
        a = np.concatenate([-side[::-1], a, side])
    sag = re * (1 - math.cos(a_fine / k))
    return np.column_stack([re * np.sin(a), rc - re * np.cos(a)]), sag


def path_samples(setup: TurningSetup, n_revs: int, tolerance: float, top: float) -> list[np.ndarray]:
    """Spindle angles of the nose placements, in runs no longer than half a turn that meet at the hard form's kinks:
    uniform steps within a run so that the chord sag of the radius ``top`` (and, if the path is curved between
    kinks, the axial sag of the vibration's curvature) stays within ``tolerance`` [mm], shared equally."""
    curvature = setup.vibration.curvature_bound() if setup.vibration is not None else 0.0
    share = tolerance / 2 if curvature > 0 else tolerance
    step = 2 * math.acos(1 - share / top)
    if curvature > 0:
        step = min(step, math.sqrt(8 * share / curvature))
    end = TWO_PI * n_revs
    kinks = setup.vibration.kinks(0.0, end) if setup.vibration is not None else np.empty(0)
    halves = np.arange(0.0, end + 1e-12, math.pi)
    if len(kinks):
        halves = halves[np.min(np.abs(halves[:, None] - kinks[None, :]), axis=1) > step / 2]
    marks = np.unique(np.concatenate([[0.0, end], halves, kinks]))
    return [
        np.linspace(a, b, max(1, math.ceil((b - a) / step)) + 1) for a, b in itertools.pairwise(marks) if b - a > 1e-9
    ]


def _chord_error(setup: TurningSetup, runs: list[np.ndarray], radii: tuple[float, float]) -> float:
    """Largest distance of the true path from its chords, at the quarter points of every step, for two radii."""
    worst = 0.0
    for t in runs:
        t0, t1 = t[:-1], t[1:]
        z0, z1 = np.asarray(setup.path(t0)), np.asarray(setup.path(t1))
        for f in (0.25, 0.5, 0.75):
            tm = t0 + f * (t1 - t0)
            zm = np.asarray(setup.path(tm))
            for rho in radii:
                true = np.column_stack([rho * np.cos(tm), rho * np.sin(tm), zm])
                chord = (1 - f) * np.column_stack([rho * np.cos(t0), rho * np.sin(t0), z0]) + f * np.column_stack(
                    [rho * np.cos(t1), rho * np.sin(t1), z1]
                )
                worst = max(worst, float(np.max(np.linalg.norm(true - chord, axis=1))))
    return worst


def _placement(setup: TurningSetup, nose: np.ndarray, theta: float) -> np.ndarray:
    """The nose polygon (u, rho) placed in the half plane at theta on the path: (n, 3) points [mm]."""
    rho, u = nose[:, 1], nose[:, 0]
    return np.column_stack([rho * math.cos(theta), rho * math.sin(theta), setup.path(theta) + u])


def cut_workpiece(
    setup: TurningSetup,
    n_revs: int = 20,
    tolerance: float = 1e-3,
    nose_tolerance: float = 1e-4,
    method: str = "loft",
) -> TurnedSolid:
    """The workpiece after ``n_revs`` turns, cut by manifold3d.

    The nose (:func:`nose_polygon`, up to 0.05 mm above r0) is placed at the path's samples
    (:func:`path_samples`, chord error within ``tolerance`` [mm]) in the axial half plane of each. ``method``:
    "hull", the convex hull of each two consecutive placements, a turn's hulls united (batch_boolean) and
    subtracted one turn after another (as cutting/form_milling/removal.py; ~0.35 s a turn here); "loft", each run of
    placements (at most half a turn) as one solid, the nose CrossSection extruded and warped onto the helix
    (straight between placements like the hulls' edges, ~0.1 s a turn), all united and subtracted at once.
    """
    if method not in ("hull", "loft"):
        raise ValueError(f"method must be 'hull' or 'loft', got {method!r}")
    n = checked_revs(setup, n_revs)
    _finite("tolerance", tolerance, low=0.0, strict=True, unit="[mm]")
    _finite("nose_tolerance", nose_tolerance, low=0.0, strict=True, unit="[mm]")
    top = setup.radius + 0.05
    nose, sag = nose_polygon(setup, nose_tolerance, top)
    runs = path_samples(setup, n, tolerance, top)
    chord = _chord_error(setup, runs, (setup.tip_radius, top))
    segments = max(64, math.ceil(math.pi / math.acos(1 - tolerance / setup.radius)))
    solid = mf.Manifold.cylinder(setup.feed * n, setup.radius, circular_segments=segments)
    pieces = 0
    if method == "hull":
        theta = np.unique(np.concatenate(runs))
        steps = np.diff(theta)
        per_turn: dict[int, list[mf.Manifold]] = {}
        for i in range(len(steps)):
            over = OVERLAP * steps[i + 1] if i + 1 < len(steps) else 0.0
            pts = np.vstack([_placement(setup, nose, theta[i]), _placement(setup, nose, theta[i + 1] + over)])
            per_turn.setdefault(int(theta[i] // TWO_PI), []).append(mf.Manifold.hull_points(pts))
            pieces += 1
        for _, hulls in sorted(per_turn.items()):
            solid = solid - mf.Manifold.batch_boolean(hulls, mf.OpType.Add)
    else:
        section = mf.CrossSection([nose])
        lofts = []
        for j, t in enumerate(runs):
            rings = t if j + 1 == len(runs) else np.append(t, t[-1] + OVERLAP * (runs[j + 1][1] - runs[j + 1][0]))
            index = np.arange(len(rings), dtype=float)

            def onto_path(p: np.ndarray, rings: np.ndarray = rings, index: np.ndarray = index) -> np.ndarray:
                p = np.asarray(p)
                th = np.interp(p[:, 2], index, rings)  # extruded height j is the j-th placement
                return np.column_stack([p[:, 1] * np.cos(th), p[:, 1] * np.sin(th), setup.path(th) + p[:, 0]])

            piece = mf.Manifold.extrude(section, float(len(rings) - 1), n_divisions=len(rings) - 2)
            lofts.append(piece.warp_batch(onto_path))
        pieces = len(lofts)
        solid = solid - mf.Manifold.batch_boolean(lofts, mf.OpType.Add)
    if solid.status() != mf.Error.NoError:
        raise RuntimeError(f"manifold3d could not cut the workpiece: {solid.status()}")
    return TurnedSolid(setup, n, solid, pieces, chord, sag, method)


# --- a path a machine made ------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class SampledTurning(TurningSetup):
    """Turning along a path given by samples: spindle angles ``theta`` [rad, increasing, from 0] and the tool's
    axial positions ``z`` [mm] there (what a simulated lathe made); linear between the samples. ``vibration``
    (the commanded one) only sizes the windows; ``theta0`` says where in its phase the samples begin."""

    theta: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(2))
    z: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(2))
    theta0: float = 0.0  # the spindle angle [rad] since the vibration started at which the samples begin

    def __post_init__(self) -> None:
        super().__post_init__()
        th = np.asarray(self.theta, dtype=float)
        if th.ndim != 1 or len(th) < 2 or np.any(np.diff(th) <= 0) or len(self.z) != len(th):
            raise ValueError("theta must be increasing samples [rad] with one z [mm] each")

    @property
    def revolutions(self) -> int:
        """Whole revolutions the samples cover."""
        return int((self.theta[-1] - self.theta[0]) / TWO_PI)

    def path(self, theta: np.ndarray | float) -> np.ndarray | float:
        z = np.interp(np.asarray(theta, dtype=float), self.theta, self.z)
        return float(z) if np.ndim(z) == 0 else z
