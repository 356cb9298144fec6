"""The tooth passages of a skiving pass and what each removes: a passage is the interval in which one cutter tooth
crosses the mesh zone (:func:`passage_range`, :func:`tooth_pose`, the blank's envelope it can meet); a :class:`Chip`
is what one passage took, and a :class:`CutResult` the cut gear with its chips. Both removals share them: the dexel
workpiece (:mod:`cutting.skiving.dexel_cut`) and the manifold reference (:mod:`cutting.skiving.removal`)."""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import manifold3d as mf
import numpy as np

from cutting.gear import Gear
from cutting.skiving.edge import CuttingEdge
from cutting.skiving.exact_solve import pose_table
from cutting.skiving.sweep import outline_points, place, place_few
from cutting.skiving.tooling import in_blank_frame
from cutting.skiving.trajectory import PassMotion


@dataclass
class Chip:
    """One tooth engagement: pass, cutter tooth, time at the mesh [s], removed volume [mm^3], and the window
    [start, end] [s] in which the tooth was in the blank's envelope (times of the pass's motion); the dexel removal
    adds the chip's thickness, contact length and centroid."""

    pass_index: int
    cutter_tooth: int
    time: float
    volume: float
    sweeps: int
    start: float = 0.0
    end: float = 0.0
    #: from the dexel removal (cutting.skiving.dexel.DexelChip): uncut chip thickness normal to the nominal
    #: boundary, largest
    #: and mean over the chip [mm], the profile length it covers [mm], and its centroid [mm]; None from manifold
    thickness_max: float | None = None
    thickness_mean: float | None = None
    contact_length: float | None = None
    centroid: tuple[float, float, float] | None = None


@dataclass
class CutResult:
    gear: mf.Manifold
    chips: list[Chip] = field(default_factory=list)
    sweep_error: float = 0.0  # largest deviation of the swept tubes from the exact sweep of the edge [mm]
    pass_sweep_error: dict[int, float] = field(default_factory=dict)  # the same, per pass index [mm]
    subtractions: int = 0
    sweeps: int = 0
    loose_pieces: int = 0  # pieces the cut separated from the gear without sweeping them away (they fall off)
    loose_volume: float = 0.0  # their volume [mm^3]

    def finish(self, solid: mf.Manifold) -> None:
        """Set the gear to ``solid`` without loose pieces: two cuts can meet around a sliver no sweep passes
        through; it falls off a real blank and must not reach the measurement (a gear measuring machine never
        sees it). The largest body is the gear."""
        self.finish_columns([solid])

    def finish_columns(self, columns: Sequence[mf.Manifold]) -> None:
        """The gear from the stock's sector columns (:meth:`Stock.columns`), each without its loose pieces, then
        united. A loose piece lies in a tooth space, never on the tooth centre lines where the columns meet, so
        dropping it per column is dropping it from the gear, at the cost of a column instead of the whole gear."""
        kept = []
        for column in columns:
            body, pieces, volume = drop_loose(column)
            self.loose_pieces += pieces
            self.loose_volume += volume
            kept.append(body)
        self.gear = kept[0] if len(kept) == 1 else mf.Manifold.batch_boolean(kept, mf.OpType.Add)
        self.gear.status()  # evaluate the union here, not lazily in whoever reads the gear first


def drop_loose(solid: mf.Manifold) -> tuple[mf.Manifold, int, float]:
    """The largest body of ``solid``, the number of the other pieces and their volume [mm^3]."""
    parts = solid.decompose()
    if len(parts) <= 1:
        return solid, 0, 0.0
    volumes = [p.volume() for p in parts]
    keep = int(np.argmax(volumes))
    return parts[keep], len(parts) - 1, float(sum(volumes) - volumes[keep])


def expected_genus(gear: Gear) -> int:
    """A cut gear is one solid without voids or tunnels: genus 0 (external), 1 (a ring gear)."""
    return 1 if gear.internal else 0


def engagement_half_angle(motion: PassMotion, edge: CuttingEdge) -> float:
    """Cutter rotation from the mesh [rad] beyond which no point of a tooth reaches the blank's radius range."""
    outline = np.ascontiguousarray(edge.outline, dtype=float)
    return _engagement_half_angle(motion.setup, motion.centre_distance, motion.index, outline.shape, outline.tobytes())


@functools.lru_cache(maxsize=64)
def _engagement_half_angle(setup, centre_distance: float | None, index: int, shape: tuple, data: bytes) -> float:
    """:func:`engagement_half_angle`, kept per setup, centre distance and edge (a pass asks for it often)."""
    g = setup.gear
    phi = np.linspace(-math.pi, math.pi, 3601)
    rot, trans = setup.rake_pose(phi, 0.0, centre_distance)  # tooth 0's edge in its rake face
    w = place(outline_points(np.frombuffer(data, dtype=float).reshape(shape)), rot, trans)
    r = np.hypot(w[..., 0], w[..., 1])
    inside = (r > g.tip_radius).any(axis=1) if g.internal else (r < g.tip_radius).any(axis=1)
    if not inside.any():
        raise ValueError(
            f"pass {index + 1}: the cutter never reaches the blank at a = "
            f"{centre_distance:.4f} mm; check process.passes and the cutter tip diameter"
        )
    return float(np.abs(phi[inside]).max()) + 0.02


def passage_range(motion: PassMotion, edge: CuttingEdge) -> tuple[float, int, int]:
    """Engagement half angle [rad] and the first and last cutter tooth pitch m whose passage (the cutter at the
    angle m * pitch) can meet the blank during the pass."""
    half = engagement_half_angle(motion, edge)
    pitch = 2 * math.pi / motion.setup.cutter.teeth
    phi0 = motion.phi_start
    phi1 = phi0 + motion.omega0 * motion.duration if not hasattr(motion, "phi") else float(motion.phi[-1])
    return half, math.ceil((phi0 - half) / pitch), math.floor((phi1 + half) / pitch)


def passage_count(motion: PassMotion, edge: CuttingEdge) -> int:
    _, first, last = passage_range(motion, edge)
    return last - first + 1


def tooth_pose(motion: PassMotion, m: int):
    """pose(t) of the rake frame of the cutter tooth that is at the mesh at the m-th cutter tooth pitch, tooth
    (-m) mod z0, in the blank's frame (its pitch deviation, the rake face, the cutter's runout and the blank's
    clamping: :mod:`cutting.skiving.tooling`)."""
    st = motion.setup
    tooth = st.passage_frames(np.array([m]))[0]

    def pose(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        rot, trans = pose_table(motion, t) or motion.pose(t)  # compiled where the motion has it: the same values
        return in_blank_frame(rot, trans, tooth, st.blank_frame)

    return pose


def blank_window(gear: Gear, pose, points: np.ndarray, t0: float, t1: float, probes: int = 65):
    """The part of a passage's window [t0, t1] [s] in which the tooth's ``points`` (cutter frame, moved by
    ``pose``) can meet the blank (its envelope: radius and face), one probe wider: (t0, t1, the points at the probes
    in it), or None when the tooth stays clear of the blank."""
    probe = np.linspace(t0, t1, probes)
    return blank_window_of(gear, points, probe, *pose(probe))


def blank_window_of(gear: Gear, points: np.ndarray, probe: np.ndarray, rot: np.ndarray, trans: np.ndarray):
    """:func:`blank_window` from the tooth's poses (rot, trans) at the probe times ``probe`` (a pass table's rows
    have them already)."""
    w = place_few(points, rot, trans)
    hit = np.nonzero(in_blank_envelope(gear, w).any(axis=1))[0]
    if hit.size == 0:
        return None
    lo, hi = max(hit[0] - 1, 0), min(hit[-1] + 1, len(probe) - 1)
    return float(probe[lo]), float(probe[hi]), w[lo : hi + 1]


def in_blank_envelope(gear: Gear, w: np.ndarray, margin: float = 0.0) -> np.ndarray:
    """Points (..., 3) [mm] inside the blank's envelope (tip cylinder, or the bore of a ring gear, over the face
    width), grown by ``margin`` [mm]."""
    r = np.hypot(w[..., 0], w[..., 1])
    radial = (r > gear.tip_radius - margin) if gear.internal else (r < gear.tip_radius + margin)
    return radial & (np.abs(w[..., 2]) <= gear.face_width / 2 + margin)
