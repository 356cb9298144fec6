"""Nominal tooth-thickness measures: span (base tangent length) and dimension over/between balls.

These are the values a gear measuring step compares its measured span and ball dimensions against.
Every function takes a :class:`cutting.gear.Gear` (lengths in mm, angles in radians; the notation of
ISO 21771 / DIN 3960, listed in :func:`span`) and checks its inputs before computing; a value that does
not describe a measurable gear raises ``ValueError`` (``TypeError`` if ``gear`` is not a ``Gear``).
The contacts aim at the measuring circle (:func:`measuring_circle_diameter`) and must touch the involute
(:func:`involute_limits`); span: :func:`span_teeth`, :func:`span`; balls: :func:`ideal_ball_diameter`,
:func:`ball_diameter`, :func:`over_balls`.
"""

from __future__ import annotations

import math
import operator
from collections.abc import Sequence

import numpy as np
from scipy.optimize import brentq

from cutting.gear import Gear
from cutting.involute import inv, inv_inverse

__all__ = [
    "BALL_SERIES_MM",
    "ball_contact_diameter",
    "ball_diameter",
    "ideal_ball_diameter",
    "involute_limits",
    "measuring_circle_diameter",
    "over_balls",
    "span",
    "span_contact_diameter",
    "span_min_face_width",
    "span_teeth",
]

#: Measuring-ball diameters [mm] that :func:`ball_diameter` rounds up to. This is skive's stock list,
#: metric sizes in steps of at most ~20 % (0.25 mm steps from 1.5 to 3.5 mm as in the series quoted
#: for DIN 3977 practice); it has NOT been checked against the text of DIN 3977 or ISO 3290-1, so pass
#: the balls you actually own as ``series`` when that matters.
BALL_SERIES_MM: tuple[float, ...] = (
    0.5, 0.6, 0.7, 0.8, 0.9, 1.0, 1.1, 1.25, 1.5, 1.75, 2.0, 2.25, 2.5, 2.75, 3.0, 3.25, 3.5,
    4.0, 4.5, 5.0, 5.5, 6.0, 6.5, 7.0, 7.5, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0, 15.0, 16.0,
    18.0, 20.0, 22.0, 25.0, 28.0, 30.0, 32.0, 35.0, 40.0, 45.0, 50.0, 55.0, 60.0, 70.0, 80.0,
    90.0, 100.0, 110.0, 120.0,
)  # fmt: skip

#: Relative slack on the involute-range checks (floating point only, not a tolerance).
_EPS = 1e-9


# ---- input checks ---------------------------------------------------------------------------------
def _finite(value: object, name: str) -> float:
    try:
        v = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(v):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return v


def _check_gear(gear: Gear) -> None:
    """Raise if ``gear`` is not a Gear with sane basic data and an involute to measure on."""
    if not isinstance(gear, Gear):
        raise TypeError(f"expected a cutting.gear.Gear, got {type(gear).__name__}")
    z = gear.teeth
    if isinstance(z, bool) or not isinstance(z, (int, np.integer)):
        raise ValueError(f"gear.teeth must be a whole number, got {z!r}")
    if z < 3:
        raise ValueError(f"gear.teeth must be at least 3 for span or ball measurement, got {z}")
    if not _finite(gear.normal_module, "gear.normal_module") > 0:
        raise ValueError(f"gear.normal_module must be > 0 mm, got {gear.normal_module!r}")
    an = _finite(gear.pressure_angle, "gear.pressure_angle")
    if not 0 < an < math.pi / 2:
        raise ValueError(f"gear.pressure_angle must lie in (0, pi/2) rad, got {an!r}")
    if not abs(_finite(gear.helix_angle, "gear.helix_angle")) < math.pi / 2:
        raise ValueError(f"gear.helix_angle must lie in (-pi/2, pi/2) rad, got {gear.helix_angle!r}")
    _finite(gear.profile_shift, "gear.profile_shift")
    da = _finite(gear.tip_diameter_value, "gear tip diameter")
    df = _finite(gear.root_diameter_value, "gear root diameter")
    if not (da > 0 and df > 0):
        raise ValueError(f"tip and root diameters must be > 0 mm, got d_a = {da!r}, d_f = {df!r}")
    if gear.internal and not df > da:
        raise ValueError(f"an internal gear needs d_f > d_a, got d_a = {da:.4f} mm, d_f = {df:.4f} mm")
    if not gear.internal and not da > df:
        raise ValueError(f"an external gear needs d_a > d_f, got d_a = {da:.4f} mm, d_f = {df:.4f} mm")
    lo, hi = involute_limits(gear)
    if not hi > lo:
        raise ValueError(
            f"the gear has no involute to measure on: involute range {lo:.4f} .. {hi:.4f} mm "
            f"(base diameter {gear.base_diameter:.4f} mm)"
        )


def _check_k(gear: Gear, k: object) -> int:
    if isinstance(k, bool):
        raise ValueError(f"the number of spanned teeth k must be a whole number, got {k!r}")
    try:
        kk = operator.index(k)  # type: ignore[arg-type]
    except TypeError:
        raise ValueError(f"the number of spanned teeth k must be a whole number, got {k!r}") from None
    if not 1 <= kk <= gear.teeth - 1:
        raise ValueError(f"the number of spanned teeth k must lie in 1 .. z - 1 = {gear.teeth - 1}, got {kk}")
    return kk


def _check_external_for_span(gear: Gear) -> None:
    if gear.internal:
        raise ValueError(
            "span (base tangent length) measurement is not possible on an internal gear: the anvils "
            "cannot reach two flanks from inside the ring; measure the dimension between balls instead "
            "(over_balls)"
        )


def _check_ball(D: object) -> float:
    d = _finite(D, "ball diameter D")
    if not d > 0:
        raise ValueError(f"ball diameter D must be > 0 mm, got {D!r}")
    return d


def _in_range(d: float, lo: float, hi: float) -> bool:
    tol = _EPS * max(1.0, hi)
    return lo - tol <= d <= hi + tol


# ---- geometric helpers ----------------------------------------------------------------------------
def involute_limits(gear: Gear) -> tuple[float, float]:
    """Diameter range ``(low, high)`` [mm] of the involute flank that a measuring element may touch.

    A measuring element must touch the involute: between the form diameter and the tip.
    External: ``(max(d_b, d_Ff), d_a)`` with ``d_Ff = Gear.rack_form_diameter`` (start of the involute
    generated by the basic rack). Internal: ``(max(d_b, d_a), d_f - 2 mn rho_fP (1 - sin(alpha_n)))``;
    the root-side end of an internal gear's involute depends on the cutter and is approximated by
    where the rounding of a basic-rack-shaped tool tip begins (exact for a rack, an approximation for
    shaper and skiving tools).
    """
    db = gear.base_diameter
    if gear.internal:
        root_form = gear.root_diameter_value - 2 * gear.mn * gear.rack.rho_f * (1 - math.sin(gear.alpha_n))
        return max(db, gear.tip_diameter_value), root_form
    return max(db, gear.rack_form_diameter), gear.tip_diameter_value


def measuring_circle_diameter(gear: Gear) -> float:
    """Target diameter for the measuring contacts, ``d_y = d + 2 x mn`` (external), ``d - 2 x mn`` (internal) [mm].

    The circle of the profile-shifted basic-rack datum line: half the rack working depth ``2 h_aP``
    below the basic-rack tip, i.e. mid working depth (DIN 3960 / KHK practice for choosing k and the
    ideal ball: contact "at the reference circle" of the shifted profile). Equal to ``d`` for ``x = 0``.

    Span and ball measurements should touch the flanks near mid working depth; this circle lies half the
    rack's working depth below the tip of a gear with the basic-rack tip diameter. It reproduces the classic
    rule ``k = z alpha_t / pi + 0.5`` and the "contact at the (shifted) reference circle" choice of the
    ideal ball (see :func:`span_teeth`, :func:`ideal_ball_diameter`).
    """
    return gear.reference_diameter + 2 * gear.sense * gear.x * gear.mn


# ---- span (base tangent length) -------------------------------------------------------------------
def _span_value(gear: Gear, k: int) -> float:
    mn, an = gear.mn, gear.alpha_n
    return mn * math.cos(an) * ((k - 0.5) * math.pi + gear.z * inv(gear.transverse_pressure_angle)) + (
        2 * gear.x * mn * math.sin(an)
    )


def _span_contact(gear: Gear, k: int) -> float:
    w_t = _span_value(gear, k) / math.cos(gear.base_helix_angle)
    return math.sqrt(gear.base_diameter**2 + w_t**2)


def span_teeth(gear: Gear) -> int:
    """Number of spanned teeth k for the span measurement (DIN 3960 / DIN 21773 practice).

    The anvils touch the two flanks on one base tangent; in the transverse section the contact points
    lie at roll length ``W_kt / 2 = W_k / (2 cos(beta_b))`` either side of the tangent point, so their
    transverse pressure angle is ``tan(alpha_M) = W_kt / d_b = [(k - 1/2) pi + 2 x tan(alpha_n) + z inv(alpha_t)] / z``.
    Asking for contact on the measuring circle ``d_y`` (:func:`measuring_circle_diameter`,
    ``cos(alpha_yt) = d_b / d_y``) gives the real-valued

        k* = z (tan(alpha_yt) - inv(alpha_t)) / pi - 2 x tan(alpha_n) / pi + 1/2,

    which for ``x = 0`` (``d_y = d``, ``tan(alpha_t) - inv(alpha_t) = alpha_t``) is the classic
    ``k* = z alpha_t / pi + 0.5`` (``z / 9 + 0.5`` for spur 20 deg; k = 3 for z = 20).

    skive returns the whole k in ``2 .. z - 1`` whose contact diameter (:func:`span_contact_diameter`)
    is closest to ``d_y`` *in diameter* and lies on the involute (:func:`involute_limits`). This equals
    ``round(k*)`` except just above the half-way points: the diameter grows faster than linearly with
    the roll length, so the switch from k to k + 1 moves from ``k* = k + 1/2`` up by about
    ``pi cos^2(alpha_yt) / (4 z tan(alpha_yt))`` (1.9 / z at 20 deg). For spur 20 deg, x = 0 this only
    matters at the exact ties z = 18, 27, 36, ..., which go to the smaller k = z / 9. It never returns
    a k whose anvils would touch the tip edge or the root fillet.

    Raises
    ------
    ValueError
        For an internal gear (use :func:`over_balls`), or when no k in ``2 .. z - 1`` touches the involute.

    Notes
    -----
    For helical gears the anvils also need face width, see :func:`span_min_face_width`; this is not
    checked here.
    """
    _check_gear(gear)
    _check_external_for_span(gear)
    z = int(gear.teeth)
    lo, hi = involute_limits(gear)
    target = min(max(measuring_circle_diameter(gear), lo), hi)
    ks = np.arange(2, z)
    w_t = (
        gear.mn * math.cos(gear.alpha_n) * ((ks - 0.5) * math.pi + z * inv(gear.transverse_pressure_angle))
        + 2 * gear.x * gear.mn * math.sin(gear.alpha_n)
    ) / math.cos(gear.base_helix_angle)
    d_m = np.sqrt(gear.base_diameter**2 + w_t**2)
    tol = _EPS * max(1.0, hi)
    ok = (d_m >= lo - tol) & (d_m <= hi + tol)
    if not np.any(ok):
        raise ValueError(
            f"no number of spanned teeth k in 2 .. {z - 1} puts the anvils on the involute "
            f"({lo:.4f} .. {hi:.4f} mm): measure this gear over balls"
        )
    dist = np.where(ok, np.abs(d_m - target), np.inf)
    return int(ks[int(np.argmin(dist))])


def span(gear: Gear, k: int) -> float:
    """Nominal span (base tangent length) over k teeth, in the normal section [mm].

    W_k = mn cos(alpha_n) [ (k - 0.5) pi + z inv(alpha_t) ] + 2 x mn sin(alpha_n)

    (ISO 21771:2007 / DIN 3960:1987 base tangent length). Derivation: in the transverse section the
    base-tangent distance between the two flanks is ``W_kt = (k - 1) p_bt + s_bt`` with the base
    thickness ``s_bt = d_b (s_t / d + inv(alpha_t))``, and ``W_k = W_kt cos(beta_b)``; the identity
    ``m_t cos(alpha_t) cos(beta_b) = mn cos(alpha_n)`` turns this into the formula above.
    Check value: z = 20, m = 2, 20 deg, x = 0: W3 = 15.321 mm, W4 = 21.225 mm.

    Notation (ISO 21771 / DIN 3960; every function of this module): ``inv(a) = tan(a) - a``;
    ``alpha_t = atan(tan(alpha_n) / cos(beta))``; ``d = z mn / cos(beta)``; ``d_b = d cos(alpha_t)``;
    ``sin(beta_b) = sin(beta) cos(alpha_n)``; ``s_n = mn (pi/2 + 2 x tan(alpha_n))`` for external and
    internal gears (profile shift ``x`` positive towards the tooth tip, see :mod:`cutting.gear`). Two
    identities are used throughout: ``mn cos(alpha_n) = m_t cos(alpha_t) cos(beta_b)`` (normal and
    transverse base pitch) and hence ``z mn cos(alpha_n) = d_b cos(beta_b)``.

    Parameters
    ----------
    gear : Gear
        An external gear.
    k : int
        Number of spanned teeth, ``1 <= k <= z - 1`` (use :func:`span_teeth` to choose it).

    Raises
    ------
    ValueError
        Internal gear; k not a whole number or out of range; the anvils would touch outside the
        involute (contact diameter :func:`span_contact_diameter` outside :func:`involute_limits`).
    """
    _check_gear(gear)
    _check_external_for_span(gear)
    kk = _check_k(gear, k)
    d_m = _span_contact(gear, kk)
    lo, hi = involute_limits(gear)
    if not _in_range(d_m, lo, hi):
        where = "above the tip diameter" if d_m > hi else "below the form diameter"
        raise ValueError(
            f"span over k = {kk} teeth is not measurable: the anvils would touch at d = {d_m:.4f} mm, "
            f"{where} (involute {lo:.4f} .. {hi:.4f} mm); choose k with span_teeth()"
        )
    return _span_value(gear, kk)


def span_contact_diameter(gear: Gear, k: int) -> float:
    """Diameter where the span anvils touch the flanks [mm].

    d_M = 2 sqrt(r_b^2 + (W_k / (2 cos(beta_b)))^2) = sqrt(d_b^2 + W_kt^2)

    In the transverse section both contact points lie on the same base tangent, at roll length
    ``W_kt / 2`` either side of its tangent point (DIN 3960 measuring circle of the span). On a helical
    gear each anvil touches its flank along a straight generator of the helicoid, so the contact runs
    over a range of diameters; this is the diameter in the transverse section where the two contact
    lines are symmetric. (On the micrometer spindle axis, with both anvils touching at equal diameter,
    the roll length is ``W_k cos(beta_b) / 2`` instead; the two agree for spur gears.)

    Not checked against the involute range (that is what this function is for); k and the gear are.
    """
    _check_gear(gear)
    _check_external_for_span(gear)
    return _span_contact(gear, _check_k(gear, k))


def span_min_face_width(gear: Gear, k: int, anvil_width: float = 5.0) -> float:
    """Face width a gear needs for span measurement over k teeth [mm].

    b_min = W_k sin|beta_b| + b_M cos(beta_b)    (DIN 3960; b_M = anvil width)

    With the anvils coaxial their contact points are ``W_k`` apart along the flank normal, which is
    inclined at ``beta_b`` to the transverse plane, hence axially ``W_k sin|beta_b|`` apart; each anvil
    touches along a helicoid generator (inclined at ``beta_b`` to the axis) over its width, axially
    ``b_M cos(beta_b)``. The absolute value makes it hold for left-hand (negative) helix angles too.
    For spur gears ``b_min = b_M``.

    Raises
    ------
    ValueError
        As :func:`span`, or ``anvil_width`` not > 0.
    """
    aw = _finite(anvil_width, "anvil_width")
    if not aw > 0:
        raise ValueError(f"anvil_width must be > 0 mm, got {anvil_width!r}")
    w = span(gear, k)
    bb = gear.base_helix_angle
    return w * abs(math.sin(bb)) + aw * math.cos(bb)


# ---- balls ----------------------------------------------------------------------------------------
def _ball_inv(gear: Gear, D: float) -> float:
    """inv(alpha_Kt) of the ball centre (see :func:`over_balls`)."""
    z = gear.z
    term = D / (z * gear.mn * math.cos(gear.alpha_n)) - math.pi / (2 * z) + 2 * gear.x * math.tan(gear.alpha_n) / z
    return inv(gear.transverse_pressure_angle) + gear.sense * term


def _ball_geometry(gear: Gear, D: float) -> tuple[float, float]:
    """(centre radius r_K, contact diameter d_Y) of a ball of diameter D; raises if it cannot rest in a space."""
    v = _ball_inv(gear, D)
    if not v > 0:
        if gear.internal:
            msg = f"a ball of D = {D:.4f} mm is too large for the tooth space of this internal gear"
        else:
            msg = f"a ball of D = {D:.4f} mm is too small: it would fall between the flanks to the base circle"
        raise ValueError(msg + " and would not rest on the involute")
    a_k = float(inv_inverse(v))
    if not a_k < 1.5:  # ~86 deg: the ball sits far outside any real gear
        raise ValueError(f"a ball of D = {D:.4f} mm does not rest in the tooth space (alpha_Kt = {a_k:.3f} rad)")
    rb = gear.base_radius
    r_k = rb / math.cos(a_k)
    roll = rb * math.tan(a_k) - gear.sense * 0.5 * D * math.cos(gear.base_helix_angle)
    if roll < 0:
        raise ValueError(f"a ball of D = {D:.4f} mm would touch the flank below the base circle: no involute there")
    return r_k, 2 * math.hypot(rb, roll)


def _check_ball_fits(gear: Gear, D: float, r_k: float, d_y: float) -> None:
    lo, hi = involute_limits(gear)
    if not _in_range(d_y, lo, hi):
        if gear.internal:
            where = "inside the tip circle" if d_y < lo else "in the root fillet"
        else:
            where = "above the tip circle" if d_y > hi else "below the form diameter"
        raise ValueError(
            f"a ball of D = {D:.4f} mm would touch the flank at d = {d_y:.4f} mm, {where}, not on the "
            f"involute ({lo:.4f} .. {hi:.4f} mm); choose another ball (ball_diameter())"
        )
    rf = gear.root_radius
    if (not gear.internal and r_k - D / 2 <= rf) or (gear.internal and r_k + D / 2 >= rf):
        raise ValueError(
            f"a ball of D = {D:.4f} mm would sit on the root circle d_f = {2 * rf:.4f} mm, not on the flanks"
        )


def ball_contact_diameter(gear: Gear, D: float) -> float:
    """Diameter where a ball of diameter D, resting in a tooth space, touches the flanks [mm].

    The ball centre lies on the space centre line at ``r_K = r_b / cos(alpha_Kt)`` (:func:`over_balls`).
    The contact normal is a normal of the involute helicoid: it lies in a plane tangent to the base
    cylinder and is inclined at ``beta_b`` to the transverse plane, so its transverse projection runs
    along the base tangent through the centre's projection and has length ``(D / 2) cos(beta_b)``:

        d_Y = 2 sqrt(r_b^2 + (r_b tan(alpha_Kt) - s (D / 2) cos(beta_b))^2),   s = +1 external, -1 internal

    (for spur gears simply ``r_b tan(alpha_Yt) = r_b tan(alpha_Kt) -/+ D/2``). The contact point lies
    in a transverse plane ``(D/2) sin(beta_b)`` from the centre's.

    Not checked against the involute range (that is what this function is for); raises ``ValueError``
    for D <= 0 or a ball that cannot rest in the space at all.
    """
    _check_gear(gear)
    d = _check_ball(D)
    return _ball_geometry(gear, d)[1]


def over_balls(gear: Gear, D: float) -> float:
    """Nominal dimension over two balls (external) or between two balls (internal), M_dK [mm].

    External (DIN 3960 / ISO 21771 / DIN 3977)::

        inv(alpha_Kt) = inv(alpha_t) + D / (z mn cos(alpha_n)) - pi / (2 z) + 2 x tan(alpha_n) / z

    Internal, derived from the same construction (DIN 3960 writes both with a signed z < 0 for
    internal gears, which flips every 1/z term)::

        inv(alpha_Kt) = inv(alpha_t) - D / (z mn cos(alpha_n)) + pi / (2 z) - 2 x tan(alpha_n) / z

    then ``d_K = d_b / cos(alpha_Kt)`` and
    z even: ``M = d_K + D`` (external), ``d_K - D`` (internal);
    z odd:  ``M = d_K cos(pi / (2 z)) + D`` (external), ``d_K cos(pi / (2 z)) - D`` (internal)
    (the balls in opposite spaces lie in one transverse plane, pi - pi/z apart).

    Derivation: a ball tangent to a flank has its centre on the parallel surface at distance D/2,
    which is again an involute helicoid of the same base cylinder, shifted along the base tangent by
    ``D / (2 cos(beta_b))`` in the transverse section. The flank's half angle at radius r is
    ``psi = s_t/d + s (inv(alpha_t) - inv(alpha_y))`` (``Gear.half_thickness_angle``; s = +1 external,
    -1 internal), so the tooth seen by the centre is widened (external) or the space narrowed
    (internal) by ``D / (d_b cos(beta_b)) = D / (z mn cos(alpha_n))`` in angle. Setting that half
    angle equal to ``pi / z`` (external: the centre is on the space centre line, pi/z from the tooth
    centre) resp. the space half angle ``pi/z - psi`` to 0 (internal) and using
    ``s_t / d = (pi/2 + 2 x tan(alpha_n)) / z`` gives the two lines above. Because the offset surface
    is exact, the form with ``D / (z mn cos(alpha_n))`` and the *transverse* ``inv(alpha_t)`` is exact
    for a ball (sphere) on a helical gear, D being the true ball diameter; it is not exact for pins
    (cylinders) on helical gears, which skive does not model.

    Raises
    ------
    ValueError
        D not > 0; the ball cannot rest in the space; it would touch outside the involute
        (:func:`involute_limits`) or sit on the root circle.
    """
    _check_gear(gear)
    d = _check_ball(D)
    r_k, d_y = _ball_geometry(gear, d)
    _check_ball_fits(gear, d, r_k, d_y)
    z = gear.z
    span_k = 2 * r_k if z % 2 == 0 else 2 * r_k * math.cos(math.pi / (2 * z))
    return span_k + gear.sense * d


def ideal_ball_diameter(gear: Gear) -> float:
    """Ball diameter whose contact lies exactly on the measuring circle d_y [mm] (not rounded).

    Solves ``d_Y(D) = d_y`` (:func:`ball_contact_diameter`, :func:`measuring_circle_diameter`) with
    brentq: with ``L(D) = r_b tan(alpha_Kt(D)) - s (D/2) cos(beta_b)`` the contact roll length,
    ``dL/dD = s (1 / (2 cos(beta_b) sin^2(alpha_Kt)) - cos(beta_b) / 2)`` has the sign of s, so the root
    is unique. Rack limit (z -> inf, x = 0): the contact is at half the space width ``pi mn / 4`` from
    the space centre line, ``(D/2) cos(alpha_n) = pi mn / 4``, ``D = pi mn / (2 cos(alpha_n)) = 1.672 mn``
    at 20 deg (cf. the rule of thumb D ~ 1.68 mn for external gears).
    """
    _check_gear(gear)
    rb = gear.base_radius
    target = measuring_circle_diameter(gear)
    if target <= gear.base_diameter:
        raise ValueError(f"the measuring circle d = {target:.4f} mm lies inside the base circle: no ideal ball")
    l_target = math.sqrt((target / 2) ** 2 - rb**2)
    cb = math.cos(gear.base_helix_angle)
    s = gear.sense
    base = gear.z * gear.mn * math.cos(gear.alpha_n)

    def roll(d: float) -> float:
        return rb * math.tan(float(inv_inverse(_ball_inv(gear, d)))) - s * 0.5 * d * cb - l_target

    # inv(alpha_Kt) = c0 + s D / base must stay > 0.
    c0 = inv(gear.transverse_pressure_angle) + s * (
        -math.pi / (2 * gear.z) + 2 * gear.x * math.tan(gear.alpha_n) / gear.z
    )
    if s > 0:
        lo = max(0.0, -c0 * base) * (1 + 1e-9) + 1e-9 * gear.mn
        hi = max(lo, gear.mn)
        while roll(hi) < 0:
            hi *= 2
            if hi > 1e3 * gear.mn:
                raise ValueError("no ball puts its contact on the measuring circle")
    else:
        if not c0 > 0:
            raise ValueError("the tooth space is closed at the base circle: no ball fits this internal gear")
        lo, hi = 1e-9 * gear.mn, c0 * base * (1 - 1e-9)
        if not roll(lo) > 0 > roll(hi):
            raise ValueError("no ball puts its contact on the measuring circle of this internal gear")
    return float(brentq(roll, lo, hi, xtol=1e-13, rtol=1e-14))


def ball_diameter(gear: Gear, series: Sequence[float] = BALL_SERIES_MM) -> float:
    """Measuring-ball diameter for :func:`over_balls` [mm] (DIN 3977 practice: contact near the reference circle).

    The ideal diameter (:func:`ideal_ball_diameter`: contact exactly on ``d_y = d +/- 2 x mn``) rounded
    up to the next size of ``series`` (default :data:`BALL_SERIES_MM`); a larger ball touches slightly
    towards the tip, as usual. For 20 deg the ideal is about 1.67-1.73 mn for external gears (cf. the
    rule of thumb 1.68 mn) and smaller for internal gears with few teeth (cf. 1.44 mn).

    Raises
    ------
    ValueError
        If no ideal ball exists, the series has no size large enough, or the chosen ball would not
        touch the involute between the form and tip diameters (or would sit on the root).
    """
    _check_gear(gear)
    sizes = sorted(_check_ball(v) for v in series)
    if not sizes:
        raise ValueError("the ball series is empty")
    ideal = ideal_ball_diameter(gear)
    pick = next((v for v in sizes if v >= ideal * (1 - 1e-12)), None)
    if pick is None:
        raise ValueError(
            f"the ideal ball D = {ideal:.4f} mm is larger than every size in the series (max {sizes[-1]} mm)"
        )
    r_k, d_y = _ball_geometry(gear, pick)
    _check_ball_fits(gear, pick, r_k, d_y)
    return pick
