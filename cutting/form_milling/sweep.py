"""The exact swept surface of form milling: the workpiece the measurement probes for micrometre truth.

A disc mill is a solid of revolution (its teeth, many and fine, make its envelope of revolution: the feed per
tooth leaves marks of f_z^2 / 8R, nanometres here). A point Q of the gear frame is removed by a pass if at some
instant of the pass Q lies inside the mill: with the mill's centre C(t) and axis a(t), u = (Q - C).a and
w = |Q - C - u a|, Q is inside when w < R(u) (:class:`cutting.form_milling.mill.DiscMill`; the finger mill of
:mod:`cutting.form_milling.finger` alike, C its tip centre and a its axis into it). Along a pass the margin
g(t) = w - R(u) is least where Q crosses the mill's axial plane (the seed's profiling plane), so each pass
contributes min_t g, found from the pose table (sorted along the feed) and refined at the vertex of the
parabola through the least sample and its neighbours (poses interpolated between samples): the margin is
exact to ~1e-9 mm, whatever the path (the planned Bezier path, or the poses the simulated machine made).

A point is material when it is in the blank (the tip cylinder between the end faces; an internal gear's ring from
the tip circle out to the root circle plus RIM mn) and every pass of its own and the nearer neighbouring tooth space
leaves it (margin > 0). A probe line is sampled, its first material sample from the air end found, and the surface
solved by regula falsi (Illinois) to 1e-8 mm.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from cutting.flank import twist_rate
from cutting.form_milling.mill import Mill
from cutting.form_milling.sweep_kernels import FAR, interp_guide, milled_margins
from cutting.gear import Gear

GOLDEN = (math.sqrt(5) - 1) / 2
#: golden-section steps on the bracket of 2 pose samples around the scan's least margin (0.1 mm * 0.618^24
#: ~ 1e-6 mm in z at 0.05 mm sample spacing: a margin error of (1e-6)^2 / 2R, nothing)
GOLDEN_STEPS = 24
#: the surface on a probe line is found to this [mm], in at most ROOT_STEPS Illinois steps
ROOT_TOLERANCE = 1e-8
ROOT_STEPS = 40
#: the scan for a pass's least margin: coarse samples about this far apart along the feed [mm], the path's slope
#: taken over this much feed [mm]
SCAN_STEP = 0.05
#: a space's passes are asked only for points within the mill's axial span of its symmetry line plus this [mm]
#: (the path's own tangential moves, clearance and corrections, stay far within it)
REACH_PAD = 1.0
SCAN_BASE = 0.5  # the margin of a point the mill's axial span does not reach [mm]
#: an internal gear's blank: a ring out to the root circle plus this many module (as cutting.skiving.solids.blank)
RIM = 3.0


@dataclass(frozen=True, eq=False)
class MillPassPoses:
    """The poses of one pass in the gear frame: instants ``t`` [s], mill centre (n, 3) [mm] and unit axis (n, 3);
    ``space`` the tooth space it cuts and ``side`` the flank it finishes."""

    space: int
    side: str
    t: np.ndarray
    centre: np.ndarray
    axis: np.ndarray

    def sorted_along_feed(self) -> MillPassPoses:
        """The poses in the order of the centre's face position, the axes made unit vectors."""
        order = np.argsort(self.centre[:, 2], kind="stable")
        axis = self.axis[order] / np.linalg.norm(self.axis[order], axis=1, keepdims=True)
        return MillPassPoses(self.space, self.side, self.t[order], self.centre[order], axis)


class MilledGear:
    """The gear the passes cut from the blank (an external gear's tip cylinder, an internal one's ring): a
    :class:`metrology.workpiece.Workpiece`."""

    kind = "exact swept surface"

    def __init__(self, gear: Gear, mill: Mill, passes: Sequence[MillPassPoses], name: str = "form-milled gear"):
        self.gear, self.mill, self.name = gear, mill, name
        self.passes = [p.sorted_along_feed() for p in passes]
        self._by_space: dict[int, list[int]] = {}
        for i, p in enumerate(self.passes):
            self._by_space.setdefault(p.space % gear.teeth, []).append(i)
        self._u, self._h = mill.profile
        self._scans: dict[int, tuple[int, int]] = {}
        self._pack: tuple | None = None
        lean = max((float(np.max(np.abs(p.axis[:, 2]))) for p in self.passes), default=0.0)
        self._cos_lean = math.sqrt(max(1.0 - lean**2, 0.25))

    # ---- the blank ---------------------------------------------------------------------------------------
    @property
    def outer_radius(self) -> float:
        """The blank's outside [mm]: the tip circle, or an internal gear's rim."""
        return self.gear.root_radius + RIM * self.gear.mn if self.gear.internal else self.gear.tip_radius

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        r, half = self.outer_radius, self.gear.face_width / 2
        return np.array([-r, -r, -half]), np.array([r, r, half])

    def in_blank(self, q: np.ndarray) -> np.ndarray:
        return self._blank(q) >= 0

    def _blank(self, q: np.ndarray) -> np.ndarray:
        """The blank's margin [mm]: > 0 inside, <= 0 outside."""
        r = np.hypot(q[..., 0], q[..., 1])
        out = np.minimum(self.outer_radius - r, self.gear.face_width / 2 - np.abs(q[..., 2]))
        return np.minimum(out, r - self.gear.tip_radius) if self.gear.internal else out

    # ---- the mill's margin ---------------------------------------------------------------------------------
    def _pose(self, p: MillPassPoses, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Centre and axis at the continuous sample index ``s`` (linear between samples)."""
        n = len(p.t)
        i = np.clip(np.floor(s).astype(int), 0, n - 2)
        f = np.clip(s - i, 0.0, 1.0)[:, None]
        return p.centre[i] * (1 - f) + p.centre[i + 1] * f, p.axis[i] * (1 - f) + p.axis[i + 1] * f

    def _g(self, p: MillPassPoses, q: np.ndarray, s: np.ndarray) -> np.ndarray:
        """The margin w - R(u) of points ``q`` at the continuous sample index ``s``."""
        c, a = self._pose(p, s)
        return self._margin_at(q, c, a / np.linalg.norm(a, axis=1, keepdims=True))

    def _margin_at(self, q: np.ndarray, c: np.ndarray, a: np.ndarray) -> np.ndarray:
        """w - R(u) of points ``q`` for the mill at centres ``c`` with unit axes ``a`` (FAR beyond its span)."""
        v = q - c
        u = np.einsum("ij,ij->i", v, a)
        r = v - u[:, None] * a
        w = np.sqrt(np.einsum("ij,ij->i", r, r))
        inside = (u >= self._u[0]) & (u <= self._u[-1])
        return np.where(inside, w - (self.mill.radius - np.interp(u, self._u, self._h)), FAR)

    def pass_margin(self, index: int, q: np.ndarray) -> np.ndarray:
        """min over the pass of w - R(u) [mm] for points ``q`` (n, 3): negative where the pass removes them. The
        pose samples around Q's face position are scanned, and the least one refined by the vertex of the parabola
        through it and its neighbours (the margin is quadratic in the feed there to ~(dz / 2R)^2 relative)."""
        p = self.passes[index]
        n = len(p.t)
        if n < 3 or len(q) == 0:
            return np.full(len(q), FAR)
        j = np.searchsorted(p.centre[:, 2], q[:, 2])
        k, stride = self._scan(index)
        best, arg = self._least(p, q, j, k, stride, n)  # coarse: every stride-th sample
        if stride > 1:  # fine: every sample between the coarse least one's neighbours
            best, arg = self._least(p, q, arg, stride, 1, n)
        mid = np.clip(arg, 1, n - 2)
        g0, g1, g2 = (self._margin_at(q, p.centre[i], p.axis[i]) for i in (mid - 1, mid, mid + 1))
        curv = g0 - 2 * g1 + g2
        ok = (curv > 1e-15) & (g0 < FAR / 2) & (g2 < FAR / 2)
        vertex = mid + np.where(ok, 0.5 * (g0 - g2) / np.where(ok, curv, 1.0), 0.0)
        refined = self._g(p, q, np.clip(vertex, mid - 1, mid + 1))
        return np.minimum(refined, np.minimum(best, g1))

    def _least(self, p: MillPassPoses, q: np.ndarray, j: np.ndarray, k: int, stride: int, n: int):
        """The least margin over the samples j + stride * (-k..k) and where it is."""
        best = np.full(len(q), np.inf)
        arg = np.clip(j, 1, n - 2)
        for off in range(-k, k + 1):
            s = np.clip(j + off * stride, 0, n - 1)
            g = self._margin_at(q, p.centre[s], p.axis[s])  # at a sample: no interpolation
            better = g < best
            best, arg = np.where(better, g, best), np.where(better, s, arg)
        return best, arg

    def _scan(self, index: int) -> tuple[int, int]:
        """(k, stride): scan k coarse samples each side of Q's face position, stride samples apart (~SCAN_STEP of
        feed). The profiling plane of a path sloped by psi crosses Q up to R tan(psi) away along the feed; the
        slope is taken over SCAN_BASE of feed so that a recorded path's vibration does not count as one."""
        if index not in self._scans:
            c = self.passes[index].centre
            dz = np.diff(c[:, 2])
            step = float(np.median(dz[dz > 0])) if np.any(dz > 0) else SCAN_STEP
            lean = float(np.max(np.abs(self.passes[index].axis[:, 2])))
            # a leaning mill's wide window is scanned coarser first (the margin is a parabola of curvature ~1 / 2R
            # along the feed: a step of 0.4 mm misplaces the least sample by little, the fine scan then finds it)
            stride = max(1, round(SCAN_STEP * (1 + 20 * lean) / step))
            base = max(1, round(SCAN_BASE / step))
            lateral = np.hypot(*(c[base:, :2] - c[:-base, :2]).T) if len(c) > base else np.zeros(1)
            slope = float(np.max(lateral)) / (base * step) if lateral.size else 0.0
            # a mill whose axis leans along the feed (set over at a helix angle) touches Q off its centre plane, up
            # to R sin(lean) away along the feed; a finger mill on a helix up to R times the path's slope
            coarse = step * stride
            reach = self.mill.radius * (min(slope, self.mill.scan_slope) + lean)
            k = int(min(400, math.ceil((reach + coarse) / coarse) + 1))
            self._scans[index] = (k, stride)
        return self._scans[index]

    def margin(self, q: np.ndarray, sign_only: bool = False) -> np.ndarray:
        """The least margin [mm] over the passes of the point's tooth space and of the nearer neighbouring one.
        ``sign_only``: a pass is asked only where the passes before it left the point (the sign is exact, a
        negative value may be above the least). Compiled (:mod:`cutting.form_milling.sweep_kernels`): as
        :meth:`_margin_numpy` to rounding."""
        q = np.asarray(q, dtype=float).reshape(-1, 3)
        return milled_margins(q, sign_only, self.gear.teeth, twist_rate(self.gear), self._reach(), self._packed())

    def _reach(self) -> tuple[float, float]:
        """The span across a space's symmetry line [mm] in which its passes are asked: the mill's axial span plus
        REACH_PAD (a leaning axis spans 1 / cos(lean) as much across it)."""
        lo, hi = self.mill.tangential_span
        return (lo - REACH_PAD) / self._cos_lean, (hi + REACH_PAD) / self._cos_lean

    def _packed(self) -> tuple:
        """The passes as the kernel reads them (made once): centres and unit axes of all poses (N, 3) with the
        offsets ``ptr`` of each pass's rows, the passes' scan parameters (k, stride), the passes of each space
        (``space_ptr``, ``space_pass``), the mill's profile table with its guide (interp_guide) and radius."""
        if self._pack is None:
            sizes = [len(p.t) for p in self.passes]
            ptr = np.zeros(len(self.passes) + 1, np.int64)
            ptr[1:] = np.cumsum(sizes)
            centre = np.zeros((int(ptr[-1]), 3))
            axis = np.zeros((int(ptr[-1]), 3))
            scan = np.zeros((len(self.passes), 2), np.int64)
            for i, p in enumerate(self.passes):
                centre[ptr[i] : ptr[i + 1]], axis[ptr[i] : ptr[i + 1]] = p.centre, p.axis
                scan[i] = self._scan(i) if sizes[i] >= 3 else (0, 1)  # a pass of < 3 poses is FAR
            z = self.gear.teeth
            space_ptr = np.zeros(z + 1, np.int64)
            space_ptr[1:] = np.cumsum([len(self._by_space.get(k, [])) for k in range(z)])
            space_pass = np.array([i for k in range(z) for i in self._by_space.get(k, [])], np.int64)
            u, h = (np.ascontiguousarray(a, dtype=np.float64) for a in (self._u, self._h))
            guide, scale = interp_guide(u)
            self._pack = (centre, axis, ptr, scan, space_ptr, space_pass, u, h, guide, scale, float(self.mill.radius))
        return self._pack

    def _margin_numpy(self, q: np.ndarray, sign_only: bool = False) -> np.ndarray:
        """The numpy reference of :meth:`margin`: the least margin [mm] over the passes of the point's tooth space
        and of the nearer neighbouring one. ``sign_only``: a pass is asked only where the passes before it left the
        point (the sign is exact, a negative value may be above the least)."""
        q = np.asarray(q, dtype=float).reshape(-1, 3)
        z = self.gear.teeth
        twist = twist_rate(self.gear) * q[:, 2]  # a helical space turns along the face
        pos = (np.arctan2(q[:, 1], q[:, 0]) - twist) / (2 * math.pi) * z  # in space units: space k spans [k, k+1)
        own = np.floor(pos).astype(int) % z
        near = np.where(pos - np.floor(pos) < 0.5, own - 1, own + 1) % z
        out = np.full(len(q), FAR)
        lo, hi = self.mill.tangential_span
        lo, hi = lo - REACH_PAD, hi + REACH_PAD
        for spaces in (own, near):
            for k in np.unique(spaces):
                a = 2 * math.pi * (k + 0.5) / z + twist  # the space's symmetry line: its passes' mill is across it
                x_s = -np.sin(a) * q[:, 0] + np.cos(a) * q[:, 1]
                # within the mill's axial span of this space (a leaning axis spans 1 / cos(lean) as much across it)
                reach = (spaces == k) & (x_s >= lo / self._cos_lean) & (x_s <= hi / self._cos_lean)
                for i in self._by_space.get(int(k), []):
                    sel = np.nonzero(reach & (out > 0 if sign_only else True))[0]
                    if sel.size:
                        out[sel] = np.minimum(out[sel], self.pass_margin(i, q[sel]))
        return out

    def removed(self, points: np.ndarray) -> np.ndarray:
        return self.margin(points) < 0

    def inside(self, points: np.ndarray) -> np.ndarray:
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        out = self.in_blank(p)
        if out.any():
            out[out] = self.margin(p[out], sign_only=True) >= 0
        return out

    def _material(self, q: np.ndarray) -> np.ndarray:
        """Signed material function: > 0 material, <= 0 air (blank margin and mill margin)."""
        blank = self._blank(q)
        out = blank.copy()
        inb = blank > 0
        if inb.any():
            out[inb] = np.minimum(blank[inb], self.margin(q[inb], sign_only=True))
        return out

    # ---- probing -------------------------------------------------------------------------------------------
    def probe(self, points: np.ndarray, directions: np.ndarray, reach: float) -> np.ndarray:
        """(n,) signed distance d [mm] along the unit ``directions`` (out of the material) at which a probe
        coming from ``points + reach * directions`` first touches material; NaN where that end is material or
        no material lies within |d| <= reach."""
        p = np.asarray(points, dtype=float).reshape(-1, 3)
        u = np.asarray(directions, dtype=float).reshape(-1, 3)
        u = u / np.linalg.norm(u, axis=1, keepdims=True)
        m = max(8, min(160, math.ceil(2 * reach / 0.0025)))
        ds = np.linspace(reach, -reach, m + 1)  # from the air end inwards
        f = self._material((p[:, None, :] + ds[None, :, None] * u[:, None, :]).reshape(-1, 3)).reshape(len(p), -1)
        solid = f > 0
        first = np.argmax(solid, axis=1)
        ok = solid.any(axis=1) & ~solid[:, 0]
        out = np.full(len(p), np.nan)
        idx = np.nonzero(ok)[0]
        if idx.size == 0:
            return out
        a = ds[first[idx] - 1]  # air end of the bracket
        b = ds[first[idx]]  # material end
        pp, uu = p[idx], u[idx]
        fa = f[idx, first[idx] - 1]
        fb = f[idx, first[idx]]
        side = np.zeros(len(idx))
        for _ in range(ROOT_STEPS):  # Illinois (regula falsi that halves a stale end's value)
            c = np.where(fb != fa, (a * fb - b * fa) / np.where(fb != fa, fb - fa, 1.0), (a + b) / 2)
            c = np.where((c - a) * (c - b) < 0, c, (a + b) / 2)
            fc = self._material(pp + c[:, None] * uu)
            mat = fc > 0
            fa = np.where(mat, np.where(side == 1, fa / 2, fa), fc)
            fb = np.where(mat, fc, np.where(side == -1, fb / 2, fb))
            side = np.where(mat, 1, -1)
            a, b = np.where(mat, a, c), np.where(mat, c, b)
            if np.max(np.abs(a - b)) < ROOT_TOLERANCE:
                break
        out[idx] = (a + b) / 2
        return out
