"""The chip of the moment: the load of the teeth in the cut at one servo tick, from where the machine has really
put the cutter at that tick and where the teeth were when they last passed the same place (regeneration).

Every space of the gear is passed once per work revolution, so an edge element cutting at x_e now takes the layer
between the surface it cuts and the surfaces left before it, measured along the cut surface's normal n_e (towards
the tool's body, the side the layer lies on): the linear chip model of milling's stability theory (Martellotti,
Trans. ASME 63 (1941) 677; Altintas and Budak, CIRP Annals 44/1 (1995) 357) per element, with three surfaces that
can bound the layer::

    h_e = min( n_e . (x_prev - x_e),     the same element one work revolution earlier (the previous tooth in
                                          this space: cutter pitches z2 before, its own frame and errors), where
                                          the ideal kinematics had it one revolution back plus the machine's
                                          deviation recorded then
               n_e . (x_pass - x_e),      the same element at the previous pass's centre distance (that pass's
                                          surface, taken as ideal)
               distance along n_e to the blank's envelope (tip cylinder and faces) )

The first term counts once the stroke has run a work revolution, the second from the second pass on. With the
deviation of the machine from the ideal kinematics as a small rigid displacement delta(x, t) = w(t) x x + s(t) of
the cutter in the blank frame (the axes' following errors, the synchronisation error, the carriage's error along
its feed, the loop's modes), the first term is the nominal layer of the feed minus
n_e . (delta(x_e, t) - delta(x_e, t - T)): the loop's motion changes the chip that makes its force. A chip that runs
out (h_e <= 0: the element passes through air, or the tool has left the cut) takes no force; this is what bounds
chatter. Each element then takes the oblique model's three components (:mod:`cutting.oblique`) at its own chip,
working rake and inclination, computed at this tick's pose.

The removal stays the exact geometry (the dexel lines and the manifold solid); this is only the force. Its chip,
integrated over an engagement, is compared with the removal's (the run reports both).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from cutting.flank import twist_rate
from cutting.forces import element_force, oblique_sums
from cutting.gear import Gear

#: columns of :func:`tick_load`'s output per engaged tooth
FORCE, POINT, MOMENT, COMPONENTS = slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12)
POWER, VOLUME_RATE, WIDTH, CHIP, FACTOR = 12, 13, 14, 15, 16
COLUMNS = 17
#: the central difference's half step for the elements' velocities [s] (the tick is 2.5e-4 s)
VELOCITY_STEP = 1e-6


def opened_space(gear: Gear, stock: float, phase: float = 0.0, samples: int = 200) -> np.ndarray:
    """``envelope[3:]`` for :func:`_in_air`: the tooth space the passes so far opened, the nominal space of the gear
    with the profile shift x + ``stock`` / mn (the cutter ``stock`` [mm] short of its finishing position; its root
    r_f + stock, a ring gear's r_f - stock), as :func:`virtual_machine.reach.skiving_load.space_area` takes it, turned
    by ``phase`` [rad] about the work axis (the machine's cut gear against the ideal kinematics' one:
    :func:`cut_phase`). The generated flanks are the shifted gear's involutes; the fillet the cutter's tip leaves is
    taken as the root circle (a few hundredths of mn of material the chip model then counts as open)."""
    import dataclasses

    shifted = dataclasses.replace(
        gear, profile_shift=gear.x + stock / gear.mn, tip_diameter=gear.tip_diameter_value, root_diameter=None
    )
    root = gear.root_radius - stock if gear.internal else gear.root_radius + stock
    lo, hi = sorted((root, gear.tip_radius))
    r = np.linspace(lo, hi, samples)
    psi = np.asarray(shifted.half_thickness_angle(np.maximum(r, gear.base_radius * (1 + 1e-9))), dtype=float)
    return np.concatenate([[1.0, float(gear.teeth), twist_rate(gear), phase, lo, hi], psi])


def cut_phase(ratio: float, diff: float, home: tuple[float, float, float]) -> float:
    """The turn [rad] of the gear the machine cuts against the ideal kinematics' gear (the one :func:`opened_space`
    lays out, phi2 = ratio phi0 + diff s): the machine's work angle is B2 = B2_0 + ratio (B1 - B1_0) + diff
    (P3 - P3_0) from its home (B1_0, B2_0, P3_0 [mm]), so its cutter sits turned by -(B2_0 - ratio B1_0 - diff
    P3_0) in the blank frame, and so do the spaces it cuts. A helical gear's differential makes this a fraction of a
    pitch (half a pitch on a small helical job: the passes after the first would see their opened space on a tooth)."""
    b1_0, b2_0, p3_0 = home
    return -(b2_0 - ratio * b1_0 - diff * p3_0)


@njit(cache=True)
def rigid_pose(b1, b2, p3, x, tilt, cutter_phase, work_phase, rot, trans):
    """The cutter frame in the blank frame from the axes alone (as
    :func:`virtual_machine.runtime.machine_run.relative_pose`): Rz(-(B2 + wp)) Rx(tilt) Rz(B1 + cp) and the centre
    Rz(-(B2 + wp)) (X, 0, P3) [mm], into ``rot`` (3, 3) and ``trans`` (3,)."""
    cb, sb = math.cos(b2 + work_phase), math.sin(b2 + work_phase)
    ct, st = math.cos(tilt), math.sin(tilt)
    cc, sc = math.cos(b1 + cutter_phase), math.sin(b1 + cutter_phase)
    # Rx(tilt) Rz(B1 + cp)
    m = np.array([[cc, -sc, 0.0], [ct * sc, ct * cc, -st], [st * sc, st * cc, ct]])
    for j in range(3):
        rot[0, j] = cb * m[0, j] + sb * m[1, j]
        rot[1, j] = -sb * m[0, j] + cb * m[1, j]
        rot[2, j] = m[2, j]
    trans[0], trans[1], trans[2] = cb * x, -sb * x, p3


@njit(cache=True)
def turn_of(w):
    """The rotation matrix of the rotation vector ``w`` (3,) (Rodrigues)."""
    angle = math.sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2])
    out = np.eye(3)
    if angle <= 0.0:
        return out
    k0, k1, k2 = w[0] / angle, w[1] / angle, w[2] / angle
    kx = np.array([[0.0, -k2, k1], [k2, 0.0, -k0], [-k1, k0, 0.0]])
    return out + math.sin(angle) * kx + (1.0 - math.cos(angle)) * (kx @ kx)


@njit(cache=True)
def _place(axes, turn, shift, geometry, teeth, blank, edge, placed, row0, frames):
    """The edges of ``teeth`` (n, 3, 4) at the axes ``axes`` (B1, B2 [rad], P3, X [mm]) with the small displacement
    (``turn``, ``shift``) on top, in the blank frame, into ``placed[row0 + i]``; their rake frames' rotations into
    ``frames`` (n, 3, 3) if it has rows."""
    rot, trans = np.empty((3, 3)), np.empty(3)
    rigid_pose(axes[0], axes[1], axes[2], axes[3], geometry[0], geometry[1], geometry[2], rot, trans)
    r = turn @ rot
    c = turn @ trans + shift
    lb = np.ascontiguousarray(blank[:, :3])
    for i in range(len(teeth)):
        rt = lb @ (r @ np.ascontiguousarray(teeth[i, :, :3]))
        ot = lb @ (r @ np.ascontiguousarray(teeth[i, :, 3]) + c) + blank[:, 3]
        if len(frames):
            frames[i] = rt
        for j in range(len(edge)):
            e0, e1, e2 = edge[j, 0], edge[j, 1], edge[j, 2]
            for a in range(3):
                placed[row0 + i, j, a] = rt[a, 0] * e0 + rt[a, 1] * e1 + rt[a, 2] * e2 + ot[a]


@njit(cache=True)
def _inside(p, envelope) -> bool:
    """A point (3,) inside the blank's envelope: tip radius, 1.0 for a ring gear, half the face width."""
    r = math.sqrt(p[0] * p[0] + p[1] * p[1])
    radial = r > envelope[0] if envelope[1] > 0.5 else r < envelope[0]
    return radial and abs(p[2]) <= envelope[2]


@njit(cache=True)
def _in_air(p, envelope) -> bool:
    """A point (3,) in the tooth space the previous passes opened (their nominal space: the gear with the profile
    shift of the stock they left), where no chip can be: ``envelope[3:]`` = on (1.0), z2, the helix's twist [rad/mm],
    the space's turn [rad], the open space's radial range r_lo, r_hi [mm], then its half tooth angle psi(r) [rad]
    sampled evenly over it."""
    if len(envelope) <= 10 or envelope[3] < 0.5:
        return False
    lo, hi = envelope[7], envelope[8]
    r = math.sqrt(p[0] * p[0] + p[1] * p[1])
    if r <= lo or r >= hi:
        return False
    m = len(envelope) - 9
    f = (r - lo) / (hi - lo) * (m - 1)
    i = min(int(f), m - 2)
    w = f - i
    psi = envelope[9 + i] * (1.0 - w) + envelope[10 + i] * w
    pitch = 2 * math.pi / envelope[4]
    u = (math.atan2(p[1], p[0]) - envelope[5] * p[2] - envelope[6]) % pitch
    return abs(u - pitch / 2) < pitch / 2 - psi


@njit(cache=True)
def _to_envelope(p, n, envelope) -> float:
    """The distance from ``p`` inside the envelope along the unit ``n`` to its boundary [mm]."""
    best = math.inf
    if n[2] > 1e-12:
        best = (envelope[2] - p[2]) / n[2]
    elif n[2] < -1e-12:
        best = (-envelope[2] - p[2]) / n[2]
    # |p + t n|^2 = r^2 in the transverse plane
    a = n[0] * n[0] + n[1] * n[1]
    if a > 1e-18:
        b = p[0] * n[0] + p[1] * n[1]
        c = p[0] * p[0] + p[1] * p[1] - envelope[0] * envelope[0]
        disc = b * b - a * c
        if disc >= 0.0:
            root = math.sqrt(disc)
            for t in ((-b - root) / a, (-b + root) / a):
                if t > 0.0 and t < best:
                    best = t
    return best


@njit(cache=True, error_model="numpy")
def element_chips(
    axes, rates, deflection, geometry, teeth, blank, edge, rake, body, envelope,
    previous, before, deviation_before, visited, last_pass, deviation_pass, passed, friction, floor,
):  # fmt: skip
    """The engaged teeth's edge elements at one instant and the chip each takes (module docstring): per (tooth,
    element) the chip width b = dl cos(lambda_s) inside the blank [mm] (0 outside), the midpoint [mm], the directions
    (cutting v, cut-surface normal n towards the body, passive p) and the oblique factors K / tau_s
    (cutting.forces.oblique_sums), the speed [mm/s] and the chip h [mm] (<= 0: no chip).

    ``axes`` (4,): B1, B2 [rad], P3, X [mm] at the instant and ``rates`` (4,) their speeds (the elements'
    velocities); ``deflection`` (6,): the loop's rotation vector [rad] and translation [mm] on top of the axes (as
    MotionRecord.deflection); ``geometry``: tilt, cutter phase, work phase [rad]; ``teeth`` (n, 3, 4): the engaged
    teeth's rake frames in the cutter frame; ``blank`` (3, 4): the blank frame in the work spindle's; ``edge`` (k, 3)
    the edge in the rake frame, ``rake`` (3,) and ``body`` (k - 1, 3) its faces (cutting.forces.EdgeFaces);
    ``envelope``: tip radius [mm], 1.0 for a ring gear, half the face width [mm], and from a second pass on the
    space the previous passes opened (:func:`_in_air`, :func:`opened_space`). The surfaces left before:
    ``previous`` (n, 3, 4) the teeth that passed one work revolution earlier, at the ideal axes ``before`` (4,) plus
    the deviation recorded then ``deviation_before`` (6,: w [rad], s [mm]), if ``visited``; the previous pass's ideal
    axes ``last_pass`` (4,) plus the deviation it had at this height ``deviation_pass`` (6,), if ``passed``: that pass
    left its surface, and opened its space, where the machine really had the cutter, so both move with it.
    ``friction``, ``floor``: the friction angle and the rake floor [rad].

    Also returns per element which surface bounds its chip (``bound``): 0 the blank, 1 the previous revolution's (the
    regenerative one), 2 the previous pass's."""
    n, k = len(teeth), len(edge)
    turn = turn_of(deflection[:3])
    placed = np.empty((3 * n, k, 3))
    frames = np.empty((n, 3, 3))
    for s in range(3):
        dt = (0.0, -VELOCITY_STEP, VELOCITY_STEP)[s]
        rows = frames[: n if s == 0 else 0]
        _place(axes + rates * dt, turn, deflection[3:], geometry, teeth, blank, edge, placed, s * n, rows)
    ins = np.zeros((n, k))
    for i in range(n):
        for j in range(k):
            if _inside(placed[i, j], envelope):
                ins[i, j] = 1.0
    _, width, mid, dirs, factors, speeds = oblique_sums(
        placed, ins, frames, np.zeros(n), VELOCITY_STEP, rake, body, friction, floor
    )
    none = np.empty((0, 3, 3))
    earlier = np.empty((n, k, 3))
    if visited:
        turned = turn_of(deviation_before[:3])
        _place(before, turned, deviation_before[3:], geometry, previous, blank, edge, earlier, 0, none)
    lower = np.empty((n, k, 3))
    opened = np.eye(3)
    if passed:
        opened = turn_of(deviation_pass[:3])
        _place(last_pass, opened, deviation_pass[3:], geometry, teeth, blank, edge, lower, 0, none)
    chips = np.zeros((n, k - 1))
    bound = np.zeros((n, k - 1), dtype=np.int64)
    normal = np.empty(3)
    unmoved = np.empty(3)
    for i in range(n):
        for j in range(k - 1):
            if width[i, j] <= 0:  # outside the blank
                continue
            # in what the passes before cut: their nominal space where the previous pass really had the cutter
            for a in range(3):
                unmoved[a] = mid[i, j, a] - deviation_pass[3 + a]
            if _in_air(opened.T @ unmoved, envelope):
                continue
            for a in range(3):
                normal[a] = dirs[i, j, 1, a]
            h = _to_envelope(mid[i, j], normal, envelope)
            for source, on, before in ((1, visited, earlier), (2, passed, lower)):
                if on:  # the layer to that surface: n . (the element there - the element here)
                    layer = _layer(normal, before[i, j], before[i, j + 1], mid[i, j])
                    if layer < h:
                        h, bound[i, j] = layer, source
            chips[i, j] = h
    return width, mid, dirs, factors, speeds, chips, bound


@njit(cache=True, error_model="numpy")
def tick_load(
    axes, rates, deflection, geometry, teeth, blank, edge, rake, body, envelope,
    previous, before, deviation_before, visited, last_pass, deviation_pass, passed, chip, out,
):  # fmt: skip
    """The load of each engaged tooth at one instant into ``out`` (n, COLUMNS): the force on the workpiece [N], its
    point [mm] and the moment about it [N m] in the blank frame, the sums of the cutting, thrust and passive
    components [N], the cutting power [W], the chip volume rate [mm^3/s], the chip width [mm], the width-weighted
    mean chip [mm] and the chip-weighted cutting factor K_c / tau_s (the working rake's effect); returns the number
    of teeth with a chip. The arguments as :func:`element_chips`'; ``chip``: kc1.1 [N/mm^2], mc, the floor of h in
    kc(h) [mm], K_c / tau_s of the table's tool, h_min [mm], K_ce, K_te [N/mm], the friction angle and the rake floor
    [rad] (cutting.oblique.ObliqueForces: tau_s(h) = kc1.1 h^-mc / (K_c / tau_s of the table's tool))."""
    n = len(teeth)
    kc11, mc, h_floor, reference, h_min = chip[0], chip[1], chip[2], chip[3], chip[4]
    ce, te = chip[5], chip[6]
    width, mid, dirs, factors, speeds, chips, _ = element_chips(
        axes, rates, deflection, geometry, teeth, blank, edge, rake, body, envelope,
        previous, before, deviation_before, visited, last_pass, deviation_pass, passed, chip[7], chip[8],
    )  # fmt: skip
    e = width.shape[1]
    out[:n] = 0.0
    cut = 0
    for i in range(n):
        weight = 0.0
        fe = np.zeros((e, 3))
        active = np.zeros(e, dtype=np.bool_)
        for j in range(e):
            b, h = width[i, j], chips[i, j]
            if b <= 0 or h <= 0.0:  # outside the blank; passing through air, or the tool has left the cut
                continue
            tau = kc11 * max(h, h_floor) ** (-mc) / reference
            sheared = tau * max(h - h_min, 0.0)
            fc = (sheared * factors[i, j, 0] + ce) * b
            ft = (sheared * factors[i, j, 1] + te) * b
            fp = sheared * factors[i, j, 2] * b
            out[i, 9] += fc
            out[i, 10] += ft
            out[i, 11] += fp
            out[i, POWER] += fc * speeds[i, j] * 1e-3
            out[i, VOLUME_RATE] += b * h * speeds[i, j]
            out[i, WIDTH] += b
            out[i, CHIP] += b * h
            out[i, FACTOR] += b * h * factors[i, j, 0]
            mag = element_force(fc, ft, fp, dirs[i, j], fe[j])
            for a in range(3):
                out[i, a] += fe[j, a]
            weight += mag
            active[j] = True
            for a in range(3):
                out[i, 3 + a] += mag * mid[i, j, a]
        if weight <= 0.0:
            continue
        cut += 1
        out[i, FACTOR] /= out[i, CHIP]
        out[i, CHIP] /= out[i, WIDTH]
        for a in range(3):
            out[i, 3 + a] /= weight
        for j in range(e):
            if not active[j]:
                continue
            r0, r1, r2 = mid[i, j, 0] - out[i, 3], mid[i, j, 1] - out[i, 4], mid[i, j, 2] - out[i, 5]
            out[i, 6] += (r1 * fe[j, 2] - r2 * fe[j, 1]) * 1e-3
            out[i, 7] += (r2 * fe[j, 0] - r0 * fe[j, 2]) * 1e-3
            out[i, 8] += (r0 * fe[j, 1] - r1 * fe[j, 0]) * 1e-3
    return cut


@njit(cache=True)
def _layer(n, a, b, here) -> float:
    """n . ((a + b) / 2 - here): the distance along n from an element's midpoint ``here`` to the midpoint of the
    same element (ends ``a``, ``b``) on an earlier surface."""
    out = 0.0
    for c in range(3):
        out += n[c] * ((a[c] + b[c]) / 2 - here[c])
    return out


@njit(cache=True)
def deviation(axes, deflection, reference, geometry):
    """The machine's deviation from the ideal kinematics at one instant as a small rigid displacement of the cutter in
    the blank frame, x_real = turn(w) x_ideal + s: (w [rad], s [mm]) (6,). ``axes`` (4,): B1, B2 [rad], P3, X [mm]
    as the machine holds them, ``deflection`` (6,) the loop's on top of them, ``reference`` (4,) the ideal kinematics'
    axes at the same cutter angle; ``geometry``: tilt, cutter phase, work phase."""
    rot_a, c_a = np.empty((3, 3)), np.empty(3)
    rot_i, c_i = np.empty((3, 3)), np.empty(3)
    rigid_pose(axes[0], axes[1], axes[2], axes[3], geometry[0], geometry[1], geometry[2], rot_a, c_a)
    rigid_pose(
        reference[0], reference[1], reference[2], reference[3], geometry[0], geometry[1], geometry[2], rot_i, c_i
    )
    loop = turn_of(deflection[:3])
    turn = loop @ rot_a @ rot_i.T
    shift = loop @ c_a + deflection[3:] - turn @ c_i
    out = np.empty(6)
    out[0] = 0.5 * (turn[2, 1] - turn[1, 2])
    out[1] = 0.5 * (turn[0, 2] - turn[2, 0])
    out[2] = 0.5 * (turn[1, 0] - turn[0, 1])
    out[3], out[4], out[5] = shift[0], shift[1], shift[2]
    return out


@njit(cache=True, error_model="numpy")
def machine_tick(
    qpos, qvel, qadr, vadr, loop, state, history, count, last_history, last_count, frames, blank, edge, rake, body,
    envelope, chip, out, passages,
):  # fmt: skip
    """One servo tick of the co-simulation's load hook in one compiled call (the hook's Python per tick cost as
    much as the chips themselves): the machine's state from MuJoCo's ``qpos``, ``qvel`` at the axes' addresses
    ``qadr``, ``vadr`` (B1, B2, P3, X; slides in m), the loop's deflection ``loop`` (6,); its deviation from the ideal
    kinematics appended to the stroke's ``history`` ((n, 8): the cutter angle B1, the ideal carriage P3 [mm], the
    deviation) at row ``count``; the previous pass's ``last_history`` (its first ``last_count`` rows) gives the
    deviation that pass had at this height; then the engaged teeth's loads into ``out`` and their passage numbers
    into ``passages``. Returns the number of engaged teeth (rows of ``out``; a tooth with no chip has WIDTH 0).

    ``state`` (17,): B1, P3 [mm] at the stroke's start; B1, B2, P3 [mm] at home; the speed ratio, the differential
    rotation [rad/mm], the carriage per cutter radian [mm/rad], the pass's centre distance, the previous pass's (nan:
    none) [mm], the engagement's half angle, the cutter pitch, the cutter's turn over a work revolution [rad] (a
    whole number of its pitches: the pose then is the present one moved back along the helix by the feed), the
    passages that turn spans; the tilt, the cutter phase and the work phase [rad]. ``frames`` (z0, 3, 4): every
    cutter tooth's rake frame (tooth 0 first)."""
    b1, b2 = qpos[qadr[0]], qpos[qadr[1]]
    p3, x = qpos[qadr[2]] * 1e3, qpos[qadr[3]] * 1e3
    axes = np.array([b1, b2, p3, x])
    rates = np.array([qvel[vadr[0]], qvel[vadr[1]], qvel[vadr[2]] * 1e3, qvel[vadr[3]] * 1e3])
    b1_s, p3_s, b1_0, b2_0, p3_0 = state[0], state[1], state[2], state[3], state[4]
    ratio, diff, zeta, centre, before_centre = state[5], state[6], state[7], state[8], state[9]
    half, pitch, revolution, back = state[10], state[11], state[12], state[13]
    geometry = state[14:17]

    def ideal(b, a):
        z = p3_s + zeta * (b - b1_s)
        return np.array([b, b2_0 + ratio * (b - b1_0) + diff * (z - p3_0), z, a])

    here = ideal(b1, centre)
    dev = deviation(axes, loop, here, geometry)
    history[count, 0], history[count, 1] = b1, here[2]
    history[count, 2:] = dev
    # the deviation one work revolution earlier (linear between ticks)
    target = b1 - revolution
    visited = count > 0 and target >= history[0, 0]
    earlier = _between(history[: count + 1, 0], history[: count + 1, 2:], target) if visited else np.zeros(6)
    # the previous pass's at this height (its carriage ran one way: the keys made to grow; held at its ends)
    passed = not math.isnan(before_centre)
    before_pass = np.zeros(6)
    if passed and last_count > 1:
        way = 1.0 if last_history[last_count - 1, 1] >= last_history[0, 1] else -1.0
        before_pass = _between(way * last_history[:last_count, 1], last_history[:last_count, 2:], way * here[2])
    lo, hi = math.ceil((b1 - half) / pitch), math.floor((b1 + half) / pitch)
    n = hi - lo + 1
    if n <= 0 or half <= 0:
        return 0
    z0 = len(frames)
    teeth = np.empty((n, 3, 4))
    previous = np.empty((n, 3, 4))
    for j in range(n):
        m = lo + j
        passages[j] = m
        teeth[j] = frames[(-m) % z0]
        previous[j] = frames[(-(m - int(back))) % z0]
    last = ideal(b1, before_centre if passed else 0.0)
    tick_load(
        axes, rates, loop, geometry, teeth, blank, edge, rake, body, envelope, previous, ideal(b1 - revolution, centre),
        earlier, visited, last, before_pass, passed, chip, out[:n],
    )  # fmt: skip
    return n


@njit(cache=True)
def _between(keys, rows, target):
    """``rows`` (n, m) linear between the rows whose growing ``keys`` (n,) hold ``target``; the end rows beyond."""
    n = len(keys)
    if target <= keys[0]:
        return rows[0].copy()
    if target >= keys[n - 1]:
        return rows[n - 1].copy()
    i = min(max(np.searchsorted(keys, target), 1), n - 1)
    a0, a1 = keys[i - 1], keys[i]
    f = (target - a0) / (a1 - a0) if a1 > a0 else 1.0
    return rows[i - 1] + f * (rows[i] - rows[i - 1])
