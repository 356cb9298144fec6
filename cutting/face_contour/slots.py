"""Face tooth contours by continuous indexing (seed 004): the radial slots of a face coupling, cut by a tool head
whose cutting elements and the workpiece turn in a fixed ratio (eq. 11: omega_t = m omega_w).

The coupling and its setup, with the seed's kinematic controls (fixed, eccentric eq. 14, cyclic speed ratio, the
work's setting changed during the cut), are :class:`FaceCoupling`; the element's path is :func:`element_path`
(eq. 5, its frames there), its setting sheet :func:`setting_sheet` (setting angle eq. 1, |V| eq. 4, the flat-bottom
eccentricity, the straight-slot amplitudes). The exact slot (:func:`exact_bottom`, :func:`exact_sides`,
:class:`ExactSlots`) and the manifold cut (:func:`cut_slots`) are measured alike by :mod:`metrology.face_slots`.
Measured slots: docs/face-contours-and-turning.md, "Face tooth contours".
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Literal

import manifold3d as mf
import numpy as np
from scipy.optimize import brentq

__all__ = [
    "SWEEP_TOLERANCE",
    "ExactSlots",
    "FaceCoupling",
    "FaceCut",
    "cut_slots",
    "cutting_speed",
    "eccentric_speed",
    "eccentric_tool_speed",
    "element_path",
    "exact_bottom",
    "exact_sides",
    "face_blank",
    "flat_bottom_eccentricity",
    "held_speed_factor",
    "path_velocity",
    "phi_at_radius",
    "plate_corners",
    "setting_angle",
    "setting_sheet",
    "slot_hulls",
    "speed_direction",
    "straight_slot_amplitude",
    "straight_slot_offset",
    "work_offset",
    "workpiece_angle",
]

Control = Literal[
    "fixed", "eccentric", "cyclic_ratio", "eccentric+cyclic_ratio", "work_setting", "eccentric+work_setting"
]
#: the controls; the combined ones add their terms (all geared to the head angle): "eccentric+cyclic_ratio" the
#: tool's setting and the ratio, "eccentric+work_setting" the tool's setting and the work's together
CONTROLS = (
    "fixed",
    "eccentric",
    "cyclic_ratio",
    "eccentric+cyclic_ratio",
    "work_setting",
    "eccentric+work_setting",
)
#: the manifold sweep's chord error [mm] (hull chords of the element's path, the blank's circles)
SWEEP_TOLERANCE = 1e-3
#: samples of a pass that bracket a root before bisection; bisection steps (1e-4 rad / 2^50: exact in double)
SCAN_SAMPLES = 2001
BISECTION_STEPS = 50
#: neighbouring hulls of a pass overlap by this fraction of a step
OVERLAP = 0.02


@dataclass(frozen=True)
class FaceCoupling:
    """A face coupling's slots and the continuous-indexing setup that cuts them (lengths [mm], angles [rad]).

    m slots; L the radius of M (where V is radial); R the tool radius to the tips; S the feed per tool revolution;
    ``depth`` the slot depth at M; ``inner_radius``..``outer_radius`` the slotted face; the tool's ``elements``
    (count, phase pitch ``element_pitch``, tip edge ``edge_width``, ``flank_angle``, ``element_height``); the
    ``control`` and its settings: eccentricity ``e`` and ``eccentric_ratio`` N, ``ratio_cycles`` q and
    ``ratio_amplitude`` A, ``setting_cycles`` q_s and ``setting_offset`` T (the work's setting changed during the cut).

    The controls (``control``; the work setting: :func:`work_offset`):

    * ``"fixed"``: eq. 5 as it stands. The bottom of a slot is the tool circle, so it is concave (deeper at M), and
      the slot's centre line bows sideways by about s^2 / (R m cos lambda) at a distance s from M (V turns along
      the slot).
    * ``"eccentric"``: eq. 14. The head's centre is carried by an eccentric (radius e, axis O) turning N =
      ``eccentric_ratio`` times per tool revolution (N m cycles per workpiece revolution, a multiple of m); at
      phi = 0 the eccentric is at 180 deg (eq. 14's start), so in the tool plane (down, along) the tip is
      (R cos psi - e cos N phi, R sin psi - e sin N phi) from O: z gains - e (1 - cos N phi), the position along the
      slot - e sin N phi. Eq. 14 prints m for N (eq. 15/16 write N); N is a field because the eccentric's
      flattening holds only while N times the slot's half angle on the tool circle stays well below 1 (N = m
      leaves a W-shaped bottom). At M the tip's horizontal speed is omega_t (R - N e) (eq. 15 at phi = 0:
      V1 - V2), so the setting angle keeps V radial there with eq. 1 on R - N e.
    * ``"cyclic_ratio"``: the speed ratio varied cyclically, q = ``ratio_cycles`` cycles per tool revolution (q m
      per workpiece revolution): a = phi / m - A (1 - cos q phi), A = ``ratio_amplitude`` [rad]; the ratio at M
      stays 1 / m. :func:`straight_slot_amplitude` is the A that cancels the centre line's bow to second order.

    The controls are geared to the head angle phi, so an element at beta_j != 0 meets them at the phase N beta_j
    (q beta_j): only the element at beta = 0 gets the flat / straight setting exactly.
    """

    m: int = 24
    L: float = 52.5
    R: float = 125.0
    S: float = 0.05
    depth: float = 3.0
    inner_radius: float = 45.0
    outer_radius: float = 60.0
    elements: int = 1
    element_pitch: float = 0.0
    edge_width: float = 2.0
    flank_angle: float = math.radians(20.0)
    element_height: float = 5.0
    control: Control = "fixed"
    e: float = 0.0
    eccentric_ratio: int = 4
    ratio_cycles: int = 6
    ratio_amplitude: float = 0.0
    setting_cycles: int = 6
    setting_offset: float = 0.0

    def __post_init__(self) -> None:
        _check(self)

    @property
    def eccentric_on(self) -> bool:
        """The eccentric carries the head (control "eccentric", alone or combined)."""
        return self.control in ("eccentric", "eccentric+cyclic_ratio", "eccentric+work_setting")

    @property
    def cyclic_on(self) -> bool:
        """The speed ratio changes cyclically (control "cyclic_ratio", alone or combined)."""
        return self.control in ("cyclic_ratio", "eccentric+cyclic_ratio")

    @property
    def work_setting_on(self) -> bool:
        """The work's setting changes during the cut (control "work_setting", alone or with the eccentric)."""
        return self.control in ("work_setting", "eccentric+work_setting")

    @property
    def phases(self) -> np.ndarray:
        """The elements' phases beta_j [rad], centred on the head angle."""
        return (np.arange(self.elements) - (self.elements - 1) / 2) * self.element_pitch

    @property
    def middle_radius(self) -> float:
        return 0.5 * (self.inner_radius + self.outer_radius)

    def setting_angle(self) -> float:
        return setting_angle(self)

    def cutting_speed(self, radius: np.ndarray | float, tool_speed: float = 1.0) -> np.ndarray:
        return cutting_speed(self, radius, tool_speed)

    def flat_bottom_eccentricity(self) -> float:
        return flat_bottom_eccentricity(self)

    def straight_slot_amplitude(self) -> float:
        return straight_slot_amplitude(self)

    def straight_slot_offset(self) -> float:
        return straight_slot_offset(self)


def _fail(name: str, why: str) -> None:
    raise ValueError(f"{name}: {why}")


def _check(c: FaceCoupling) -> None:
    """Inputs first: each ValueError names its field."""
    if not isinstance(c.m, int) or c.m < 2:
        _fail("m", f"the number of slots must be an integer >= 2, got {c.m!r}")
    for name in ("R", "S", "depth", "inner_radius", "edge_width", "element_height"):
        v = getattr(c, name)
        if not (isinstance(v, int | float) and math.isfinite(v) and v > 0):
            _fail(name, f"must be a positive finite number, got {v!r}")
    if not c.outer_radius > c.inner_radius:
        _fail("outer_radius", f"must exceed inner_radius {c.inner_radius}, got {c.outer_radius}")
    if not c.inner_radius <= c.L <= c.outer_radius:
        _fail("L", f"M (radius L = {c.L}) must lie on the slotted face {c.inner_radius}..{c.outer_radius}")
    if c.control not in CONTROLS:
        _fail("control", f"must be one of {CONTROLS}, got {c.control!r}")
    if not isinstance(c.elements, int) or c.elements < 1:
        _fail("elements", f"must be an integer >= 1, got {c.elements!r}")
    if not (math.isfinite(c.element_pitch) and c.element_pitch >= 0):
        _fail("element_pitch", f"must be >= 0, got {c.element_pitch!r}")
    if not 0 <= c.flank_angle < math.radians(45):
        _fail("flank_angle", f"must be in [0, 45 deg), got {math.degrees(c.flank_angle):.3g} deg")
    if not c.element_height > c.depth:
        _fail("element_height", f"{c.element_height} must exceed depth {c.depth} (the element clears the face)")
    if not c.depth < 0.5 * c.R:
        _fail("depth", f"{c.depth} must be below R / 2 = {c.R / 2}")
    if not isinstance(c.eccentric_ratio, int) or c.eccentric_ratio < 2:
        _fail("eccentric_ratio", f"N must be an integer >= 2, got {c.eccentric_ratio!r}")
    if not isinstance(c.ratio_cycles, int) or c.ratio_cycles < 1:
        _fail("ratio_cycles", f"q must be an integer >= 1, got {c.ratio_cycles!r}")
    if not (math.isfinite(c.e) and c.e >= 0):
        _fail("e", f"must be >= 0, got {c.e!r}")
    if c.e > 0 and not c.eccentric_on:
        _fail("e", f"an eccentricity needs control = 'eccentric' (control is {c.control!r})")
    if not (math.isfinite(c.ratio_amplitude) and c.ratio_amplitude >= 0):
        _fail("ratio_amplitude", f"must be >= 0, got {c.ratio_amplitude!r}")
    if c.ratio_amplitude > 0 and not c.cyclic_on:
        _fail("ratio_amplitude", f"needs control = 'cyclic_ratio' (control is {c.control!r})")
    if not isinstance(c.setting_cycles, int) or c.setting_cycles < 1:
        _fail("setting_cycles", f"q_s must be an integer >= 1, got {c.setting_cycles!r}")
    if not (math.isfinite(c.setting_offset) and c.setting_offset >= 0):
        _fail("setting_offset", f"must be >= 0, got {c.setting_offset!r}")
    if c.setting_offset > 0 and not c.work_setting_on:
        _fail("setting_offset", f"needs control = 'work_setting' (control is {c.control!r})")
    if c.setting_offset >= 0.1 * c.L:
        _fail(
            "setting_offset", f"T = {c.setting_offset} mm moves the work by {2 * c.setting_offset} mm: keep T < L / 10"
        )
    if c.ratio_amplitude * c.ratio_cycles >= 1 / c.m:
        _fail("ratio_amplitude", f"A q = {c.ratio_amplitude * c.ratio_cycles:.4g} >= 1/m: the workpiece would reverse")
    radius = c.R - c.eccentric_ratio * c.e
    if radius <= 0:
        _fail("e", f"N e = {c.eccentric_ratio * c.e:.4g} >= R: the tip would run backwards at M")
    if c.L >= radius * c.m:
        name = "e" if c.e > 0 else "L"
        _fail(name, f"L = {c.L} >= (R - N e) m = {radius * c.m:.4g}: lambda = arcsin(L / (R m)) does not exist")
    width = c.edge_width + 2 * c.depth * math.tan(c.flank_angle)
    spread = (c.elements - 1) * c.element_pitch / c.m
    if width / c.inner_radius + spread >= 2 * math.pi / c.m:
        name = "element_pitch" if spread > 0 else "edge_width"
        _fail(
            name,
            f"the slot ({width:.3g} mm at the face, sector {spread:.3g} rad) is wider than the pitch at the "
            f"inner radius",
        )
    # the final pass must run through the face (the tip below z = 0 from the inner to the outer radius), the tip
    # moving on along the slot while it cuts
    for beta in c.phases:
        phi = _pass_phis(c, beta, samples=4001)[1:-1]
        r = np.linalg.norm(tip_position(c, phi, beta, final=True)[0], axis=-1)
        if r.min() > c.inner_radius or r.max() < c.outer_radius:
            _fail(
                "depth",
                f"the final pass is below the face only from r = {r.min():.4g} to {r.max():.4g}: deepen "
                f"the slot or enlarge R to cut it through {c.inner_radius}..{c.outer_radius}",
            )
        if np.any(np.diff(_along(c, phi, beta)) <= 0):
            _fail("e", "the tip runs backwards along the slot while it cuts (N e too large for the pass)")


# ---------------------------------------------------------------------------------------------------- kinematics


def setting_angle(c: FaceCoupling) -> float:
    """lambda = arcsin(L / ((R - N e) m)) [rad] (eq. 1; R - N e is the radius of the tip's horizontal speed at M,
    = R without the eccentric): the tool plane's angle to the radial line OM that makes V radial at M."""
    e = c.e if c.eccentric_on else 0.0
    return math.asin(c.L / ((c.R - c.eccentric_ratio * e) * c.m))


def workpiece_angle(c: FaceCoupling, phi: np.ndarray | float) -> np.ndarray:
    """The workpiece angle a [rad] at the head angle phi: phi / m (eq. 11), minus A (1 - cos q phi) under the
    cyclic ratio control."""
    phi = np.asarray(phi, dtype=float)
    a = phi / c.m
    if c.cyclic_on:
        a = a - c.ratio_amplitude * (1 - np.cos(c.ratio_cycles * phi))
    return a


def work_offset(c: FaceCoupling, phi: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """The work's setting during the cut (control "work_setting"): how far the work's axis has moved along the tool
    axis n at head angle phi, T (1 - cos q_s phi) [mm], and its rate in phi [mm/rad]; zero at M and without it.

    The seed's setting parameters are the work axis's place relative to the tool plane: L along OM and the setting
    angle lambda, i.e. L cos lambda along the tool plane and L sin lambda across it. Moving the work across the
    plane, cyclically with q_s cycles per tool revolution (q_s m per workpiece revolution: "the number of cycles a
    multiple of the number of slots"), changes L sin lambda during the cut, and so the tip's path eq. 5 by
    - T (1 - cos q_s phi) n."""
    phi = np.asarray(phi, dtype=float)
    if not c.work_setting_on:
        return np.zeros_like(phi), np.zeros_like(phi)
    T, q = c.setting_offset, c.setting_cycles
    return T * (1 - np.cos(q * phi)), T * q * np.sin(q * phi)


def tool_frame(
    c: FaceCoupling, phi: np.ndarray, final: bool = True, beta: float = 0.0
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """At head angle phi: the tool plane's horizontal direction u, the tool axis n (both (..., 2)), the head
    centre's horizontal position (..., 2) and height, the workpiece angle."""
    a = workpiece_angle(c, phi)
    tu = a - setting_angle(c)
    u = np.stack([np.cos(tu), np.sin(tu)], axis=-1)
    n = np.stack([-np.sin(tu), np.cos(tu)], axis=-1)
    e = c.e if c.eccentric_on else 0.0
    N = c.eccentric_ratio
    feed = c.depth if final else c.S * (phi + beta) / (2 * math.pi)
    centre = c.L * np.stack([np.cos(a), np.sin(a)], axis=-1) - (e * np.sin(N * phi))[..., None] * u
    if c.work_setting_on:  # the work moved along the tool axis: the head centre moves back relative to it
        centre = centre - work_offset(c, phi)[0][..., None] * n
    height = c.R - e + e * np.cos(N * phi) - feed
    return u, n, centre, height, a


def _along(c: FaceCoupling, phi: np.ndarray, beta: float) -> np.ndarray:
    """The tip's position along the tool plane from the eccentric's axis: R sin psi - e sin N phi [mm]."""
    e = c.e if c.eccentric_on else 0.0
    return c.R * np.sin(phi + beta) - e * np.sin(c.eccentric_ratio * phi)


def tip_position(c: FaceCoupling, phi: np.ndarray, beta: float, final: bool) -> tuple[np.ndarray, np.ndarray]:
    """The tip of the element at phase ``beta`` at head angle phi: its horizontal position (..., 2) and height [mm]."""
    u, _, centre, height, _ = tool_frame(c, phi, final, beta)
    psi = phi + beta
    return centre + (c.R * np.sin(psi))[..., None] * u, height - c.R * np.cos(psi)


def element_path(c: FaceCoupling, phi: np.ndarray | float, element: int = 0, final: bool = False) -> np.ndarray:
    """The tip of element ``element`` in the workpiece frame, (..., 3) [mm], at head angles phi [rad]
    (phi = omega_t t; the seed's a m for the fixed setting): eq. 5 with the control's terms. ``final`` replaces the
    seed's feed term S psi / (2 pi) by the full depth (the spark-out pass).

    Frames and the seed's quantities. The workpiece frame turns with the workpiece (axis z, the slotted face at
    z = 0, material below). The tool head (radius R to the element tips) turns in a vertical plane about a
    horizontal axis; its angle phi is the time parameter. The workpiece angle is a = phi / m (eq. 11), so each tool
    revolution passes one slot and slot k's centre line is the radial line at 2 pi k / m. Element j sits at the
    phase beta_j on the head (a sector of ``elements`` elements ``element_pitch`` apart, centred on phi); its own
    angle is psi = phi + beta_j. The head's centre is above the point M at radius L (seed: L, the distance of the
    line through M perpendicular to the tool axis, i.e. the vertical through M, from the workpiece axis), the tool
    plane is turned by the setting angle lambda from the radial line OM (eq. 1, lambda = arcsin(L / (R m))). The
    tip of element j is (eq. 5)

        x = L cos a + R sin psi cos(a - lambda),   y = L sin a + R sin psi sin(a - lambda),
        z = R (1 - cos psi) - S psi / (2 pi).

    The seed prints cos(a + lambda): with a counted as in its x = L cos a the element's velocity at M is radial (the
    condition eq. 1 is derived from) only for the tool plane at a - lambda (the tangential speed at M is
    omega_w (L - R m sin lambda) = 0), so the path uses a - lambda; lambda itself is eq. 1's positive angle.
    """
    if not 0 <= element < c.elements:
        raise ValueError(f"element: must be in 0..{c.elements - 1}, got {element}")
    phi = np.asarray(phi, dtype=float)
    xy, z = tip_position(c, phi, float(c.phases[element]), final)
    return np.concatenate([xy, z[..., None]], axis=-1)


def path_velocity(
    c: FaceCoupling, phi: np.ndarray | float, element: int = 0, tool_speed: float = 1.0, final: bool = True
) -> np.ndarray:
    """d/dt of :func:`element_path` [mm/s] at the tool speed omega_t [rad/s] (central differences, 1e-10 relative):
    the relative velocity V of the seed's eq. 7."""
    phi = np.asarray(phi, dtype=float)
    h = 1e-6
    d = (element_path(c, phi + h, element, final) - element_path(c, phi - h, element, final)) / (2 * h)
    return tool_speed * d


def cutting_speed(c: FaceCoupling, radius: np.ndarray | float, tool_speed: float = 1.0) -> np.ndarray:
    """|V| [mm/s] at workpiece radius R_w along the slot, the seed's eq. 4:
    |V|^2 = (R_w omega_w)^2 + V_t^2 + 2 V_t R_w omega_w cos(pi/2 + lambda), omega_w = omega_t / m,
    with the angle between the tool's and the workpiece's velocities pi/2 + lambda (the seed's figure 1; its
    printed cos is of that angle) and V_t the tip's speed at M: R omega_t, with the eccentric eq. 15 at phi = 0,
    (R - N e) omega_t. Exact at M (R_w = L: V radial, |V| = V_t cos lambda); along the slot the path's own speed is
    :func:`path_velocity`."""
    r = np.asarray(radius, dtype=float)
    lam = setting_angle(c)
    e = c.e if c.eccentric_on else 0.0
    vt = (c.R - c.eccentric_ratio * e) * tool_speed
    vw = r * tool_speed / c.m
    return np.sqrt(vw**2 + vt**2 + 2 * vt * vw * math.cos(math.pi / 2 + lam))


def eccentric_speed(c: FaceCoupling, phi: np.ndarray | float, tool_speed: float = 1.0) -> np.ndarray:
    """The tip's speed in the tool plane [mm/s] under the eccentric, eq. 15:
    |V|^2 = V1^2 + V2^2 - 2 V1 V2 cos(N phi - phi), V1 = R omega_t, V2 = e N omega_t."""
    phi = np.asarray(phi, dtype=float)
    v1, v2 = c.R * tool_speed, c.e * c.eccentric_ratio * tool_speed
    return np.sqrt(v1**2 + v2**2 - 2 * v1 * v2 * np.cos((c.eccentric_ratio - 1) * phi))


def eccentric_tool_speed(c: FaceCoupling, v: float, phi: np.ndarray | float) -> np.ndarray:
    """The tool's speed n [rev/s] that holds the cutting speed v [mm/s] at head angle phi under the eccentric,
    eq. 16: n = v / (2 pi sqrt(N^2 e^2 + R^2 - 2 e N R cos(N phi - phi)))."""
    phi = np.asarray(phi, dtype=float)
    N, e, R = c.eccentric_ratio, c.e, c.R
    return v / (2 * math.pi * np.sqrt(N**2 * e**2 + R**2 - 2 * e * N * R * np.cos((N - 1) * phi)))


def held_speed_factor(c: FaceCoupling, phi: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 16 as a factor on the head's speed: k(phi) = n(phi) / n(0) = (R - N e) / sqrt(N^2 e^2 + R^2 - 2 e N R
    cos(N phi - phi)) and dk/dphi. The head turning at k(phi) times its speed at M keeps the tip's speed in the tool
    plane (eq. 15) at its value at M, omega_t (R - N e), all round; k = 1 without the eccentric."""
    phi = np.asarray(phi, dtype=float)
    if not c.eccentric_on or c.e == 0.0:
        return np.ones_like(phi), np.zeros_like(phi)
    N, e, R = c.eccentric_ratio, c.e, c.R
    q = N**2 * e**2 + R**2 - 2 * e * N * R * np.cos((N - 1) * phi)
    k = (R - N * e) / np.sqrt(q)
    dk = -k * e * N * R * (N - 1) * np.sin((N - 1) * phi) / q  # k = (R - N e) q^(-1/2)
    return k, dk


def straight_slot_amplitude(c: FaceCoupling) -> float:
    """The cyclic ratio's amplitude A [rad] that cancels the bow of the slot's centre line to second order:
    the tip's polar angle is phi^2 (R cos lambda / (m L) - A q^2 / 2) near M, so A = 2 R cos lambda / (m L q^2)."""
    lam = math.asin(c.L / (c.R * c.m))
    return 2 * c.R * math.cos(lam) / (c.m * c.L * c.ratio_cycles**2)


def straight_slot_offset(c: FaceCoupling) -> float:
    """The work setting's amplitude T [mm] that cancels the bow of the slot's centre line to second order. Near M
    the tip's path eq. 5 leaves the radial line by (R - N e) phi^2 cos lambda / m towards larger polar angles (the
    tool plane at a - lambda turns with the work while the tip runs along it; R - N e the tip's radius of speed at M),
    and the work's move T (1 - cos q_s phi) along n (n at cos lambda to the tangential direction) takes
    T q_s^2 phi^2 cos lambda / 2 off it: T = 2 (R - N e) / (m q_s^2)."""
    e = c.e if c.eccentric_on else 0.0
    return 2 * (c.R - c.eccentric_ratio * e) / (c.m * c.setting_cycles**2)


def phi_at_radius(c: FaceCoupling, radius: np.ndarray | float, element: int | None = None) -> np.ndarray:
    """Head angles [rad] at which the tip of ``element`` (default: the one nearest beta = 0) is at ``radius`` on the
    final pass through slot 0."""
    r = np.atleast_1d(np.asarray(radius, dtype=float))
    beta = float(c.phases[c.elements // 2 if element is None else element])
    phi = _pass_phis(c, beta, margin=1.0)

    def gap(x: np.ndarray) -> np.ndarray:
        return np.linalg.norm(tip_position(c, x, beta, final=True)[0], axis=-1) - r

    g = np.linalg.norm(tip_position(c, phi, beta, final=True)[0], axis=-1)[None, :] - r[:, None]
    k, ok = first_sign_change(g)
    x = bisect_roots(gap, phi[k], phi[k + 1], g[np.arange(len(r)), k])
    return np.where(ok, x, np.nan)


def speed_direction(c: FaceCoupling, radius: np.ndarray | float, tool_speed: float = 1.0) -> np.ndarray:
    """The angle [rad] of the relative velocity V's horizontal part to the radial direction where the tip is at
    ``radius`` (+ towards larger polar angles): 0 at M by the setting, growing towards the slot's ends (the seed's
    figure 2: V turns along the slot, so the slot leaves the radial line)."""
    phi = phi_at_radius(c, radius)
    element = c.elements // 2
    p = element_path(c, phi, element, final=True)[..., :2]
    v = path_velocity(c, phi, element, tool_speed)[..., :2]
    radial = p / np.linalg.norm(p, axis=-1, keepdims=True)
    return np.arctan2(radial[..., 0] * v[..., 1] - radial[..., 1] * v[..., 0], np.einsum("ij,ij->i", radial, v))


def setting_sheet(c: FaceCoupling, tool_speed: float = 1.0) -> dict[str, float]:
    """The setting sheet's figures (tool speed omega_t [rad/s]): the setting angle [deg], the tip's radius of speed at
    M, the cutting speed |V| (eq. 4) at the slot's inner end, M and outer end [mm/s], V's direction at the ends
    [deg], the flat-bottom eccentricity [mm] (N = ``eccentric_ratio``), the straight-slot ratio amplitude [rad] (q =
    ``ratio_cycles``), the straight-slot work setting T [mm] (q_s = ``setting_cycles``), the control's cycles per
    workpiece revolution and the cycle's tool revolutions (plunge at S,
    one workpiece revolution of spark-out)."""
    e = c.e if c.eccentric_on else 0.0
    ends = np.array([c.inner_radius, c.L, c.outer_radius])
    v = cutting_speed(c, ends, tool_speed)
    direction = np.degrees(speed_direction(c, ends[[0, 2]], tool_speed))
    # per workpiece revolution: N m of the eccentric, q m of the ratio; combined, the pattern repeats gcd(N, q) m times
    turns = [c.eccentric_ratio] * c.eccentric_on + [c.ratio_cycles] * c.cyclic_on
    turns += [c.setting_cycles] * c.work_setting_on
    cycles = math.gcd(*turns) * c.m if turns else 0
    return {
        "setting_angle_deg": math.degrees(setting_angle(c)),
        "tip_speed_radius_mm": c.R - c.eccentric_ratio * e,
        "V_inner_mm_s": float(v[0]),
        "V_M_mm_s": float(v[1]),
        "V_outer_mm_s": float(v[2]),
        "V_direction_inner_deg": float(direction[0]),
        "V_direction_outer_deg": float(direction[1]),
        "flat_bottom_e_mm": flat_bottom_eccentricity(c),
        "straight_slot_amplitude_rad": straight_slot_amplitude(c),
        "straight_slot_offset_mm": straight_slot_offset(c),
        "control_cycles_per_workpiece_rev": float(cycles),
        "tool_revolutions": c.depth / c.S + c.m,
    }


# ---------------------------------------------------------------------------------------------------- exact slot


def _pass_phis(c: FaceCoupling, beta: float, margin: float = 0.0, samples: int = SCAN_SAMPLES) -> np.ndarray:
    """Head angles of element beta's final pass through slot 0 while its tip is below z = margin [mm]."""
    psi = np.linspace(-1.2, 1.2, 4801)
    _, z = tip_position(c, psi - beta, beta, final=True)
    below = np.flatnonzero(z < margin)
    if below.size == 0:
        raise ValueError(f"height: the tip never goes below z = {margin:.4g} (the slot is {c.depth} deep)")
    i0 = below[np.argmin(np.abs(psi[below]))]  # the run around the bottom
    lo = hi = i0
    while lo > 0 and z[lo - 1] < margin:
        lo -= 1
    while hi < len(psi) - 1 and z[hi + 1] < margin:
        hi += 1
    lo, hi = max(lo - 1, 0), min(hi + 1, len(psi) - 1)
    return np.linspace(psi[lo], psi[hi], samples) - beta


def bisect_roots(
    f: Callable[[np.ndarray], np.ndarray],
    lo: np.ndarray,
    hi: np.ndarray,
    flo: np.ndarray,
    steps: int = BISECTION_STEPS,
) -> np.ndarray:
    """Vectorised bisection of f on brackets [lo, hi] (f(lo) = flo), ``steps`` halvings."""
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        fm = f(mid)
        left = np.sign(fm) == np.sign(flo)
        lo = np.where(left, mid, lo)
        flo = np.where(left, fm, flo)
        hi = np.where(left, hi, mid)
    return 0.5 * (lo + hi)


def first_sign_change(g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per row of g (points x samples), the index of the first sign change and whether there is one."""
    change = np.signbit(g[:, :-1]) != np.signbit(g[:, 1:])
    return np.argmax(change, axis=1), change.any(axis=1)


def exact_bottom(c: FaceCoupling, radii: np.ndarray) -> np.ndarray:
    """The slot bottom z [mm] at ``radii`` on a slot's radial centre line: the lowest height of any element's
    tip edge passing over the point (the edge lies along the tool axis, horizontal, so its height there is the tip's
    when (P - tip) . u = 0). Bracketed on the pass's samples, bisected to 1e-12 rad. All slots are slot 0 turned by
    2 pi k / m (the controls repeat every tool revolution), so this is every slot's bottom."""
    r = np.asarray(radii, dtype=float)
    p = np.stack([r, np.zeros_like(r)], axis=-1)
    best = np.full(r.shape, np.nan)
    for beta in c.phases:
        phi = _pass_phis(c, beta)
        tip, _ = tip_position(c, phi, beta, final=True)
        u = tool_frame(c, phi)[0]
        g = np.einsum("ijk,jk->ij", p[:, None, :] - tip[None], u)
        k, ok = first_sign_change(g)

        def gap(x: np.ndarray, p: np.ndarray = p, beta: float = beta) -> np.ndarray:
            t, _ = tip_position(c, x, beta, final=True)
            return np.einsum("ij,ij->i", p - t, tool_frame(c, x)[0])

        x = bisect_roots(gap, phi[k], phi[k + 1], g[np.arange(len(r)), k])
        t, z = tip_position(c, x, beta, final=True)
        across = np.abs(np.einsum("ij,ij->i", p - t, tool_frame(c, x)[1]))
        z = np.where(ok & (across <= 0.5 * c.edge_width), z, np.nan)
        best = np.fmin(best, z)
    return best


def _side_point(
    c: FaceCoupling, phi: np.ndarray, beta: float, height: float, sign: int
) -> tuple[np.ndarray, np.ndarray]:
    """The ``sign`` flank's end of element beta's section at z = ``height`` (..., 2), and whether the plate
    reaches that height there."""
    u, n, centre, zc, _ = tool_frame(c, phi)
    psi = phi + beta
    t = (zc - height) / np.cos(psi)  # distance from the head's centre along the element's radius
    half = 0.5 * c.edge_width + (c.R - t) * math.tan(c.flank_angle)
    pt = centre + (t * np.sin(psi))[..., None] * u + sign * half[..., None] * n
    return pt, (t <= c.R) & (t >= c.R - c.element_height)


def exact_sides(c: FaceCoupling, radii: np.ndarray, height: float, slot: int = 0) -> np.ndarray:
    """Polar angles [rad] of the slot's sides at ``radii`` and z = ``height``, (2, n): the - side (towards smaller
    angles) and the + side. The section of an element's plate at that height is a segment along the tool axis; the
    slot's section is the union of these segments, bounded by their ends (roots of |end| = r, bisected)."""
    r = np.asarray(radii, dtype=float)
    out = np.stack([np.full(r.shape, np.inf), np.full(r.shape, -np.inf)])
    for beta in c.phases:
        phi = _pass_phis(c, beta, margin=height)
        for row, sign in ((0, -1), (1, 1)):
            pt, valid = _side_point(c, phi, beta, height, sign)
            g = np.where(valid, np.linalg.norm(pt, axis=-1), np.nan)[None, :] - r[:, None]
            k, ok = first_sign_change(np.nan_to_num(g, nan=-1.0))

            def gap(x: np.ndarray, beta: float = beta, sign: int = sign) -> np.ndarray:
                return np.linalg.norm(_side_point(c, x, beta, height, sign)[0], axis=-1) - r

            x = bisect_roots(gap, phi[k], phi[k + 1], g[np.arange(len(r)), k])
            q, reach = _side_point(c, x, beta, height, sign)
            ang = np.where(ok & reach, np.arctan2(q[:, 1], q[:, 0]), np.nan)
            out[row] = np.fmin(out[row], ang) if sign < 0 else np.fmax(out[row], ang)
    return out + 2 * math.pi * slot / c.m


@dataclass(frozen=True, eq=False)
class ExactSlots:
    """The exact slots of ``coupling`` as the measurement probes them (:class:`metrology.face_slots.SlottedFace`):
    :func:`exact_bottom` (every slot's: the lowest z the tip edge reaches over each point of the slot's radial
    centre line) and :func:`exact_sides` (the slot's sides at a height), roots on the elements' motion (to 1e-9 mm).
    The measurement (bottom form, side lines, slot spacing) measures the manifold solid of :func:`cut_slots` the
    same way."""

    coupling: FaceCoupling

    def bottom(self, radii: np.ndarray, slot: int) -> np.ndarray:
        return exact_bottom(self.coupling, radii)

    def sides(self, radii: np.ndarray, height: float, slot: int) -> np.ndarray:
        return exact_sides(self.coupling, radii, height, slot)


def flat_bottom_eccentricity(c: FaceCoupling) -> float:
    """The eccentricity e [mm] that makes the slot bottom flat: the exact bottom at the middle radius on the straight
    line through the bottom at the inner and the outer radius (a depth gauge at the ends and the middle reads one
    line; what is left is a W of the order R (N^2 - 1) delta^4 / 24, delta the slot's half angle on the tool circle,
    see :mod:`metrology.face_slots`). Solved (brentq, 1e-9 mm) on the exact bottom of the eccentric control with N =
    ``eccentric_ratio``; near R (1 - cos delta) / (1 - cos N delta), and R / N^2 for a short slot."""
    ends = np.array([c.inner_radius, c.middle_radius, c.outer_radius])

    # with the cyclic ratio or the work setting combined, its own amplitude stays: the bottom is flat under both
    both = "eccentric+cyclic_ratio" if c.cyclic_on else "eccentric+work_setting" if c.work_setting_on else None

    def middle(e: float) -> float:
        trial = replace(c, control=both, e=e) if both else replace(c, control="eccentric", e=e, ratio_amplitude=0.0)
        z = exact_bottom(trial, ends)
        return float(z[1] - 0.5 * (z[0] + z[2]))

    N = c.eccentric_ratio
    delta = 0.5 * (c.outer_radius - c.inner_radius) / c.R
    guess = c.R * (1 - math.cos(delta)) / (1 - math.cos(N * delta))
    limit = 0.999 * (c.R - c.L / c.m) / N
    hi = min(1.25 * guess, limit)
    while middle(hi) < 0:
        if hi >= limit:
            raise ValueError(f"eccentric_ratio: no eccentricity flattens this slot with N = {N}")
        hi = min(1.5 * hi, limit)
    return brentq(middle, 0.0, hi, xtol=1e-9)


# ---------------------------------------------------------------------------------------------------- manifold cut


def _segments(radius: float, tol: float) -> int:
    return max(16, math.ceil(math.pi / math.acos(1 - tol / radius)))


def face_blank(c: FaceCoupling, tol: float = SWEEP_TOLERANCE, base: float = 2.0) -> mf.Manifold:
    """The annular face blank, z from -(depth + base) to 0: the outer circle circumscribed and the inner one
    inscribed by polygons of chord error ``tol`` (the blank covers the whole true annulus)."""
    n_out, n_in = _segments(c.outer_radius, tol), _segments(c.inner_radius, tol)
    outer = mf.CrossSection.circle(c.outer_radius / math.cos(math.pi / n_out), n_out)
    inner = mf.CrossSection.circle(c.inner_radius, n_in)
    h = c.depth + base
    return mf.Manifold.extrude(outer - inner, h).translate((0.0, 0.0, -h))


def plate_corners(c: FaceCoupling, phi: np.ndarray, beta: float) -> np.ndarray:
    """The element plate's four corners (..., 4, 3) on the final pass: the tip edge's ends and the top's.

    Each element is a thin plate in the plane of the tool axis and its radius: a straight tip edge of width
    ``edge_width`` along the tool axis, flanks opening by ``flank_angle``, ``element_height`` high."""
    u, n, centre, zc, _ = tool_frame(c, phi)
    psi = phi + beta
    u3 = np.concatenate([u, np.zeros((*u.shape[:-1], 1))], axis=-1)
    n3 = np.concatenate([n, np.zeros((*n.shape[:-1], 1))], axis=-1)
    c3 = np.concatenate([centre, zc[..., None]], axis=-1)
    rho = np.sin(psi)[..., None] * u3 - np.cos(psi)[..., None] * np.array([0.0, 0.0, 1.0])
    top = c.R - c.element_height
    w_tip = 0.5 * c.edge_width
    w_top = w_tip + c.element_height * math.tan(c.flank_angle)
    corners = [
        c3 + c.R * rho - w_tip * n3,
        c3 + c.R * rho + w_tip * n3,
        c3 + top * rho + w_top * n3,
        c3 + top * rho - w_top * n3,
    ]
    return np.stack(corners, axis=-2)


def hull_steps(phi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each hull's start and end angle: consecutive samples, widened by OVERLAP of the step at both ends so that
    neighbouring hulls overlap (hulls that only share a plate leave zero-volume slivers in the boolean)."""
    d = OVERLAP * np.diff(phi)
    return phi[:-1] - d, phi[1:] + d


def _chord_error(c: FaceCoupling, phi: np.ndarray, beta: float) -> float:
    """The largest distance of the plate's corners at the quarter points of each hull from its straight move."""
    lo, hi = hull_steps(phi)
    p0, p1 = plate_corners(c, lo, beta), plate_corners(c, hi, beta)
    worst = 0.0
    for f in (0.25, 0.5, 0.75):
        q = plate_corners(c, lo + f * (hi - lo), beta)
        worst = max(worst, float(np.max(np.linalg.norm(q - ((1 - f) * p0 + f * p1), axis=-1))))
    return worst


def pass_samples(c: FaceCoupling, beta: float, tol: float) -> tuple[np.ndarray, float]:
    """Head angles of element beta's final pass (tip below the face, one step beyond) with the plate's chord error
    within ``tol`` [mm] (the path's curvature radius is about R + e N^2, the first guess), and that error."""
    curvature = c.R + (c.e * c.eccentric_ratio**2 if c.eccentric_on else 0.0) + c.L / c.m**2
    span = _pass_phis(c, beta, samples=2)
    steps = max(2, math.ceil((span[1] - span[0]) / math.sqrt(8 * tol / curvature)))
    while True:
        phi = np.linspace(span[0], span[1], steps + 1)
        err = _chord_error(c, phi, beta)
        if err <= tol:
            return phi, err
        steps = math.ceil(steps * 1.3)


@dataclass(frozen=True, eq=False)
class FaceCut:
    """The manifold cut: the ``solid``, the ``slots`` cut, the number of hulls, the sweep's chord error [mm] (the
    largest over the passes, <= ``tol``) and the time it took [s]."""

    solid: mf.Manifold
    slots: tuple[int, ...]
    hulls: int
    chord_error: float
    tol: float
    seconds: float = field(default=0.0)


def slot_hulls(c: FaceCoupling, slot: int, tol: float = SWEEP_TOLERANCE) -> tuple[list[mf.Manifold], float]:
    """The convex pieces of slot ``slot``'s swept volume (every element's final pass): hulls of consecutive plate
    placements, within ``tol`` [mm] of the true sweep; and their chord error."""
    turn = 2 * math.pi * slot / c.m
    rot = np.array([[math.cos(turn), -math.sin(turn), 0.0], [math.sin(turn), math.cos(turn), 0.0], [0.0, 0.0, 1.0]])
    hulls, worst = [], 0.0
    for beta in c.phases:
        phi, err = pass_samples(c, beta, tol)
        worst = max(worst, err)
        lo, hi = (plate_corners(c, x, beta) @ rot.T for x in hull_steps(phi))
        hulls += [mf.Manifold.hull_points(np.vstack([a, b])) for a, b in zip(lo, hi, strict=True)]
    return hulls, worst


def cut_slots(c: FaceCoupling, slots: tuple[int, ...] = (0, 1), tol: float = SWEEP_TOLERANCE) -> FaceCut:
    """The face blank with the slots' swept volumes removed (one batched boolean); ``tol`` [mm] the chord error.

    The cut: the head plunges with feed S per revolution (the seed's z, per element angle) until the depth is
    reached, then turns one more workpiece revolution at full depth (spark-out). The xy motion does not depend on the
    feed, so every plunge pass is the final pass lifted by depth - feed >= 0: the slot is the final passes' swept
    volume. :mod:`metrology.face_slots` measures the solid as it measures :class:`ExactSlots`."""
    t0 = time.perf_counter()
    pieces, worst = [], 0.0
    for k in slots:
        h, err = slot_hulls(c, k, tol)
        pieces += h
        worst = max(worst, err)
    solid = subtract_pieces(c, pieces, tol)
    return FaceCut(solid, tuple(slots), len(pieces), worst, tol, time.perf_counter() - t0)


def subtract_pieces(c: FaceCoupling, pieces: list[mf.Manifold], tol: float) -> mf.Manifold:
    """The face blank less the swept pieces (one batched boolean), evaluated now (manifold is lazy) so that a
    caller's timing is the cut's; a failed boolean raises RuntimeError with manifold's status."""
    solid = mf.Manifold.batch_boolean([face_blank(c, tol), *pieces], mf.OpType.Subtract)
    if solid.status() != mf.Error.NoError or solid.is_empty():
        raise RuntimeError(f"the face cut failed: {solid.status()}")
    solid.num_tri()
    return solid
