"""ISO 1328-1:2013 flank tolerances of cylindrical involute gears, in micrometres.

Every tolerance is the class-5 formula times the step factor ``sqrt(2)**(A - 5)`` of the flank tolerance
class ``A`` (1..11), computed unrounded and rounded **once** per clause 5.2.3 (see :func:`round_tolerance`);
composite and derived tolerances are computed from the *unrounded* components. Gear data: ``d = z*mn/cos(beta)``
reference diameter in mm, ``mn`` normal module in mm, ``b`` face width in mm, ``z`` number of teeth, ``k`` number
of pitches of a sector (``F_pk`` only). Outside the standard's range (:func:`validate`) the functions raise
``ValueError`` rather than extrapolate. The sources and the choices made without the standard's text:
docs/measurement.md, "ISO 1328-1 tolerances".
"""

import math
import numbers
from collections.abc import Callable, Mapping
from typing import NamedTuple

__all__ = [
    "CLASSES",
    "PARAMETERS",
    "check_class",
    "default_sector_pitches",
    "grade",
    "helix_form",
    "helix_slope",
    "overall_class",
    "profile_form",
    "profile_slope",
    "reference_diameter",
    "round_tolerance",
    "runout",
    "sector_pitch",
    "single_pitch",
    "step_factor",
    "tolerances",
    "total_cumulative_pitch",
    "total_helix",
    "total_profile",
    "validate",
]

STANDARD = "ISO 1328-1:2013"
CLASSES = tuple(range(1, 12))
"""Flank tolerance classes of ISO 1328-1:2013, 1 (finest) to 11."""

PARAMETERS = ("f_p", "F_p", "F_pk", "F_alpha", "f_Halpha", "f_falpha", "F_beta", "f_Hbeta", "f_fbeta", "F_r")
"""Keys of :func:`tolerances`, :func:`grade` and :func:`overall_class`."""

# validity ranges of ISO 1328-1:2013, clause 1 (inclusive)
Z_RANGE = (5, 1000)
D_RANGE = (5.0, 15000.0)  # mm
MN_RANGE = (0.5, 70.0)  # mm
B_RANGE = (4.0, 1200.0)  # mm
BETA_MAX_DEG = 45.0

_TIE_EPS = 1e-9  # in units of the rounding step
_GRADE_SLACK_UM = 1e-9  # a measured value equal to a tolerance up to float noise meets it


# --------------------------------------------------------------------------------------------------- checks


def _outside(name: str, value: float, rule: str) -> ValueError:
    return ValueError(
        f"{name} = {value!r} is outside the range {rule}; {STANDARD} does not define tolerances outside "
        "this range; do not extrapolate"
    )


def _check_range(name: str, value: float, lo: float, hi: float, unit: str = "") -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name} must be a real number, got {value!r}")
    v = float(value)
    if not lo <= v <= hi:  # also rejects NaN
        raise _outside(name, value, f"{lo:g} <= {name} <= {hi:g}{unit}")
    return v


def _check_int(name: str, value: float) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not float(value).is_integer():
        raise ValueError(f"{name} must be a whole number, got {value!r}")
    return int(value)


def check_class(A: int) -> int:
    """Return the flank tolerance class ``A`` after checking it is an integer in 1..11.

    Raises
    ------
    ValueError
        If ``A`` is not an integer (``bool`` and ``float`` are refused) or outside 1..11.
    """
    if isinstance(A, bool) or not isinstance(A, numbers.Integral):
        raise ValueError(f"accuracy class A must be an integer 1..11 ({STANDARD}), got {A!r}")
    if not CLASSES[0] <= A <= CLASSES[-1]:
        raise ValueError(f"accuracy class A = {A} is outside 1 <= A <= 11 defined by {STANDARD}")
    return int(A)


def _check_z(z: int) -> int:
    zi = _check_int("z", z)
    if not Z_RANGE[0] <= zi <= Z_RANGE[1]:
        raise _outside("z", z, f"{Z_RANGE[0]} <= z <= {Z_RANGE[1]}")
    return zi


def _check_d(d: float) -> float:
    return _check_range("d", d, *D_RANGE, " mm")


def _check_mn(mn: float) -> float:
    return _check_range("mn", mn, *MN_RANGE, " mm")


def _check_b(b: float) -> float:
    return _check_range("b", b, *B_RANGE, " mm")


def _check_k(k: int, z: int) -> int:
    ki = _check_int("k", k)
    if not 1 <= ki <= z / 2:
        raise ValueError(f"sector pitches k = {k!r} must satisfy 1 <= k <= z/2 = {z / 2:g}")
    return ki


def validate(z: int, d: float, mn: float, b: float, beta_deg: float) -> None:
    """Check gear data against the validity range of ISO 1328-1:2013 (clause 1).

    ``5 <= z <= 1000``, ``5 <= d <= 15000 mm``, ``0.5 <= mn <= 70 mm``, ``4 <= b <= 1200 mm``,
    ``|beta| <= 45 deg``; all bounds inclusive. Outside them ISO 1328-1:2013 defines no tolerances; every function
    of this module raises ``ValueError`` there rather than extrapolate.

    Raises
    ------
    ValueError
        Naming the parameter, its value and the valid range, for the first value outside it.
    """
    _check_z(z)
    _check_d(d)
    _check_mn(mn)
    _check_b(b)
    if isinstance(beta_deg, bool) or not isinstance(beta_deg, numbers.Real):
        raise ValueError(f"beta_deg must be a real number, got {beta_deg!r}")
    if not abs(float(beta_deg)) <= BETA_MAX_DEG:
        raise _outside("beta_deg", beta_deg, f"|beta_deg| <= {BETA_MAX_DEG:g} deg")


def reference_diameter(z: int, mn: float, beta_deg: float) -> float:
    """Reference diameter ``d = z*mn/cos(beta)`` in mm (``mn`` in mm, ``beta`` in degrees)."""
    return z * mn / math.cos(math.radians(beta_deg))


def default_sector_pitches(z: int) -> int:
    """Default number of pitches of a sector: ``k = z/8`` rounded half up, at least 2.

    Half up (z = 20 -> k = 3) rather than Python's ``round`` (which gives 2), consistent with the rounding of
    the tolerances; the standard leaves ``k`` to the purchaser, so pass ``k`` when it is agreed.
    """
    return max(2, math.floor(z / 8 + 0.5))


# -------------------------------------------------------------------------------------- factor and rounding


def step_factor(A: int) -> float:
    """Step factor ``sqrt(2)**(A - 5)`` between flank tolerance classes (dimensionless).

    Computed as ``2**((A - 5)//2)`` times ``sqrt(2)`` for odd ``A - 5``, so that the factor of class
    ``A + 2`` is exactly (bit for bit) twice that of class ``A``.
    """
    A = check_class(A)
    n = A - 5
    return math.ldexp(math.sqrt(2.0) if n % 2 else 1.0, n // 2)


def round_tolerance(value_um: float) -> float:
    """Round a tolerance in um once per ISO 1328-1:2013 clause 5.2.3.

    Above 10 um to the nearest 1 um, from 5 to 10 um to the nearest 0.5 um, below 5 um to the nearest
    0.1 um. The band is chosen from the unrounded value. Ties go up (``floor(x/step + 0.5)``), with an
    epsilon of 1e-9 step so that float noise does not flip a tie: 9.25 -> 9.5, 12.5 -> 13, 3.05 -> 3.1.

    Parameters
    ----------
    value_um : float
        Unrounded tolerance, um, finite and >= 0.

    Returns
    -------
    float
        Rounded tolerance, um.
    """
    x = float(value_um)
    if not math.isfinite(x) or x < 0:
        raise ValueError(f"a tolerance must be finite and >= 0 um, got {value_um!r}")
    step = 1.0 if x > 10.0 else 0.5 if x >= 5.0 else 0.1
    return round(math.floor(x / step + 0.5 + _TIE_EPS) * step, 1)


def _finish(A: int, class5_um: float, rounded: bool) -> float:
    value = class5_um * step_factor(A)
    return round_tolerance(value) if rounded else value


# ------------------------------------------------------------------------------------- class-5 formulas (um)


def _fp5(d: float, mn: float) -> float:
    return 0.001 * d + 0.4 * mn + 5.0


def _Fp5(d: float, mn: float) -> float:
    return 0.002 * d + 0.55 * math.sqrt(d) + 0.7 * mn + 12.0


def _fHa5(d: float, mn: float) -> float:
    return 0.4 * mn + 0.001 * d + 4.0


def _ffa5(mn: float) -> float:
    return 0.55 * mn + 5.0


def _fHb5(d: float, b: float) -> float:
    return 0.05 * math.sqrt(d) + 0.35 * math.sqrt(b) + 4.0


def _ffb5(d: float, b: float) -> float:
    return 0.07 * math.sqrt(d) + 0.45 * math.sqrt(b) + 4.0


def _Fpk5(d: float, mn: float, z: int, k: int) -> float:
    return _fp5(d, mn) + 4.0 * k / z * (0.001 * d + 0.55 * math.sqrt(d) + 0.3 * mn + 7.0)


# ----------------------------------------------------------------------------------------- tolerances (um)


def single_pitch(A: int, d: float, mn: float, *, rounded: bool = True) -> float:
    """Single pitch tolerance ``f_pT`` in um.

    ``f_pT = (0.001 d + 0.4 mn + 5) * sqrt(2)**(A - 5)``, ``d`` and ``mn`` in mm, rounded once per 5.2.3.

    Parameters
    ----------
    A : int
        Flank tolerance class, 1..11.
    d : float
        Reference diameter, mm (5..15000).
    mn : float
        Normal module, mm (0.5..70).
    rounded : bool, optional
        ``False`` returns the unrounded value.

    Returns
    -------
    float
        Tolerance, um.
    """
    A = check_class(A)
    return _finish(A, _fp5(_check_d(d), _check_mn(mn)), rounded)


def total_cumulative_pitch(A: int, d: float, mn: float, *, rounded: bool = True) -> float:
    """Total cumulative pitch tolerance ``F_pT`` in um.

    ``F_pT = (0.002 d + 0.55 sqrt(d) + 0.7 mn + 12) * sqrt(2)**(A - 5)``, ``d`` and ``mn`` in mm, rounded
    once per 5.2.3.

    Parameters
    ----------
    A : int
        Flank tolerance class, 1..11.
    d : float
        Reference diameter, mm (5..15000).
    mn : float
        Normal module, mm (0.5..70).
    rounded : bool, optional
        ``False`` returns the unrounded value.

    Returns
    -------
    float
        Tolerance, um.
    """
    A = check_class(A)
    return _finish(A, _Fp5(_check_d(d), _check_mn(mn)), rounded)


def profile_slope(A: int, d: float, mn: float, *, rounded: bool = True) -> float:
    """Profile slope tolerance ``f_HalphaT`` in um (a limit for the magnitude of the signed ``f_Halpha``).

    ``f_HalphaT = (0.4 mn + 0.001 d + 4) * sqrt(2)**(A - 5)``, ``d`` and ``mn`` in mm, rounded once per 5.2.3.

    Parameters
    ----------
    A : int
        Flank tolerance class, 1..11.
    d : float
        Reference diameter, mm (5..15000).
    mn : float
        Normal module, mm (0.5..70).
    rounded : bool, optional
        ``False`` returns the unrounded value.

    Returns
    -------
    float
        Tolerance, um.
    """
    A = check_class(A)
    return _finish(A, _fHa5(_check_d(d), _check_mn(mn)), rounded)


def profile_form(A: int, mn: float, *, rounded: bool = True) -> float:
    """Profile form tolerance ``f_falphaT`` in um.

    ``f_falphaT = (0.55 mn + 5) * sqrt(2)**(A - 5)``, ``mn`` in mm, rounded once per 5.2.3.

    Parameters
    ----------
    A : int
        Flank tolerance class, 1..11.
    mn : float
        Normal module, mm (0.5..70).
    rounded : bool, optional
        ``False`` returns the unrounded value.

    Returns
    -------
    float
        Tolerance, um.
    """
    A = check_class(A)
    return _finish(A, _ffa5(_check_mn(mn)), rounded)


def total_profile(A: int, d: float, mn: float, *, rounded: bool = True) -> float:
    """Total profile tolerance ``F_alphaT`` in um.

    ``F_alphaT = sqrt(f_HalphaT**2 + f_falphaT**2)`` from the *unrounded* slope and form tolerances of class
    ``A`` (equivalently the class-5 root-sum-square times ``sqrt(2)**(A - 5)``), rounded once per 5.2.3.
    Rounding the components first can move the total by a step: class 7, z = 30, mn = 2 mm, beta = 20 deg
    gives 16 um here, 15 um from the rounded components (9.5 and 12 um).

    Parameters
    ----------
    A : int
        Flank tolerance class, 1..11.
    d : float
        Reference diameter, mm (5..15000).
    mn : float
        Normal module, mm (0.5..70).
    rounded : bool, optional
        ``False`` returns the unrounded value.

    Returns
    -------
    float
        Tolerance, um.
    """
    A = check_class(A)
    d, mn = _check_d(d), _check_mn(mn)
    return _finish(A, math.hypot(_fHa5(d, mn), _ffa5(mn)), rounded)


def helix_slope(A: int, d: float, b: float, *, rounded: bool = True) -> float:
    """Helix slope tolerance ``f_HbetaT`` in um (a limit for the magnitude of the signed ``f_Hbeta``).

    ``f_HbetaT = (0.05 sqrt(d) + 0.35 sqrt(b) + 4) * sqrt(2)**(A - 5)``, ``d`` and ``b`` in mm, rounded once
    per 5.2.3.

    Parameters
    ----------
    A : int
        Flank tolerance class, 1..11.
    d : float
        Reference diameter, mm (5..15000).
    b : float
        Face width, mm (4..1200).
    rounded : bool, optional
        ``False`` returns the unrounded value.

    Returns
    -------
    float
        Tolerance, um.
    """
    A = check_class(A)
    return _finish(A, _fHb5(_check_d(d), _check_b(b)), rounded)


def helix_form(A: int, d: float, b: float, *, rounded: bool = True) -> float:
    """Helix form tolerance ``f_fbetaT`` in um.

    ``f_fbetaT = (0.07 sqrt(d) + 0.45 sqrt(b) + 4) * sqrt(2)**(A - 5)``, ``d`` and ``b`` in mm, rounded once
    per 5.2.3.

    Parameters
    ----------
    A : int
        Flank tolerance class, 1..11.
    d : float
        Reference diameter, mm (5..15000).
    b : float
        Face width, mm (4..1200).
    rounded : bool, optional
        ``False`` returns the unrounded value.

    Returns
    -------
    float
        Tolerance, um.
    """
    A = check_class(A)
    return _finish(A, _ffb5(_check_d(d), _check_b(b)), rounded)


def total_helix(A: int, d: float, b: float, *, rounded: bool = True) -> float:
    """Total helix tolerance ``F_betaT`` in um.

    ``F_betaT = sqrt(f_HbetaT**2 + f_fbetaT**2)`` from the *unrounded* slope and form tolerances of class
    ``A`` (equivalently the class-5 root-sum-square times ``sqrt(2)**(A - 5)``), rounded once per 5.2.3.
    Rounding the components first can move the total by a step: class 9, d = 63.85 mm, b = 20 mm gives
    36 um here, 35 um from the rounded components (24 and 26 um).

    Parameters
    ----------
    A : int
        Flank tolerance class, 1..11.
    d : float
        Reference diameter, mm (5..15000).
    b : float
        Face width, mm (4..1200).
    rounded : bool, optional
        ``False`` returns the unrounded value.

    Returns
    -------
    float
        Tolerance, um.
    """
    A = check_class(A)
    d, b = _check_d(d), _check_b(b)
    return _finish(A, math.hypot(_fHb5(d, b), _ffb5(d, b)), rounded)


def runout(A: int, d: float, mn: float, *, rounded: bool = True) -> float:
    """Runout tolerance ``F_rT`` in um (informative annex of ISO 1328-1:2013).

    ``F_rT = 0.9 F_pT = 0.9 (0.002 d + 0.55 sqrt(d) + 0.7 mn + 12) * sqrt(2)**(A - 5)`` from the unrounded
    ``F_pT``, ``d`` and ``mn`` in mm, rounded once per 5.2.3.

    Parameters
    ----------
    A : int
        Flank tolerance class, 1..11.
    d : float
        Reference diameter, mm (5..15000).
    mn : float
        Normal module, mm (0.5..70).
    rounded : bool, optional
        ``False`` returns the unrounded value.

    Returns
    -------
    float
        Tolerance, um.
    """
    A = check_class(A)
    return _finish(A, 0.9 * _Fp5(_check_d(d), _check_mn(mn)), rounded)


def sector_pitch(A: int, d: float, mn: float, z: int, k: int, *, rounded: bool = True) -> float:
    """Sector pitch tolerance ``F_pkT`` over ``k`` pitches in um (informative annex; **check**).

    ``F_pkT = f_pT + (4 k / z) (0.001 d + 0.55 sqrt(d) + 0.3 mn + 7) * sqrt(2)**(A - 5)``, i.e. the class-5
    sum ``(0.001 d + 0.4 mn + 5) + (4k/z)(...)`` times the step factor, from the unrounded ``f_pT``, rounded
    once per 5.2.3. ``d``, ``mn`` in mm.

    Check: this formula is taken from the project notes (``metrology-notes.md``, marked "check") and was not
    confirmed against the text of the standard or a second source.

    Parameters
    ----------
    A : int
        Flank tolerance class, 1..11.
    d : float
        Reference diameter, mm (5..15000).
    mn : float
        Normal module, mm (0.5..70).
    z : int
        Number of teeth (5..1000).
    k : int
        Number of pitches in the sector, ``1 <= k <= z/2``.
    rounded : bool, optional
        ``False`` returns the unrounded value.

    Returns
    -------
    float
        Tolerance, um.
    """
    A = check_class(A)
    z = _check_z(z)
    return _finish(A, _Fpk5(_check_d(d), _check_mn(mn), z, _check_k(k, z)), rounded)


# ------------------------------------------------------------------------------------------ whole gear


class _Gear(NamedTuple):
    d: float
    mn: float
    b: float
    z: int
    k: int


def _gear(z: int, mn: float, b: float, beta_deg: float, k: int | None) -> _Gear:
    z = _check_z(z)
    _check_mn(mn)
    if isinstance(beta_deg, bool) or not isinstance(beta_deg, numbers.Real) or not abs(beta_deg) <= BETA_MAX_DEG:
        raise _outside("beta_deg", beta_deg, f"|beta_deg| <= {BETA_MAX_DEG:g} deg")
    d = reference_diameter(z, float(mn), float(beta_deg))
    validate(z, d, mn, b, beta_deg)
    k = default_sector_pitches(z) if k is None else _check_k(k, z)
    return _Gear(d, float(mn), float(b), z, k)


_BY_PARAMETER: dict[str, Callable[[int, _Gear, bool], float]] = {
    "f_p": lambda A, g, r: single_pitch(A, g.d, g.mn, rounded=r),
    "F_p": lambda A, g, r: total_cumulative_pitch(A, g.d, g.mn, rounded=r),
    "F_pk": lambda A, g, r: sector_pitch(A, g.d, g.mn, g.z, g.k, rounded=r),
    "F_alpha": lambda A, g, r: total_profile(A, g.d, g.mn, rounded=r),
    "f_Halpha": lambda A, g, r: profile_slope(A, g.d, g.mn, rounded=r),
    "f_falpha": lambda A, g, r: profile_form(A, g.mn, rounded=r),
    "F_beta": lambda A, g, r: total_helix(A, g.d, g.b, rounded=r),
    "f_Hbeta": lambda A, g, r: helix_slope(A, g.d, g.b, rounded=r),
    "f_fbeta": lambda A, g, r: helix_form(A, g.d, g.b, rounded=r),
    "F_r": lambda A, g, r: runout(A, g.d, g.mn, rounded=r),
}
assert tuple(_BY_PARAMETER) == PARAMETERS


def _check_parameter(parameter: str) -> str:
    if parameter not in _BY_PARAMETER:
        raise ValueError(f"unknown parameter {parameter!r}; expected one of {', '.join(PARAMETERS)}")
    return parameter


def tolerances(
    A: int, z: int, mn: float, b: float, beta_deg: float, k: int | None = None, *, rounded: bool = True
) -> dict[str, float]:
    """All ISO 1328-1:2013 flank tolerances of one gear and class, in um.

    Parameters
    ----------
    A : int
        Flank tolerance class, 1..11.
    z : int
        Number of teeth.
    mn : float
        Normal module, mm.
    b : float
        Face width, mm.
    beta_deg : float
        Helix angle at the reference diameter, degrees (sign = hand, ignored).
    k : int, optional
        Pitches per sector for ``F_pk``; default :func:`default_sector_pitches` (``z/8`` half up, >= 2).
    rounded : bool, optional
        ``False`` returns the unrounded values.

    Returns
    -------
    dict[str, float]
        Keys :data:`PARAMETERS`: ``f_p``, ``F_p``, ``F_pk``, ``F_alpha``, ``f_Halpha``, ``f_falpha``,
        ``F_beta``, ``f_Hbeta``, ``f_fbeta``, ``F_r``.

    Raises
    ------
    ValueError
        From :func:`validate` (with ``d = z mn / cos(beta)``) or :func:`check_class`.
    """
    A = check_class(A)
    g = _gear(z, mn, b, beta_deg, k)
    return {name: fn(A, g, rounded) for name, fn in _BY_PARAMETER.items()}


def _grade(value_um: float, parameter: str, g: _Gear) -> int | None:
    if isinstance(value_um, bool) or not isinstance(value_um, numbers.Real) or not math.isfinite(value_um):
        raise ValueError(f"measured {parameter} must be a finite number in um, got {value_um!r}")
    magnitude = abs(float(value_um))
    fn = _BY_PARAMETER[parameter]
    for A in CLASSES:
        if fn(A, g, True) >= magnitude - _GRADE_SLACK_UM:
            return A
    return None


def grade(
    value_um: float, parameter: str, z: int, mn: float, b: float, beta_deg: float, k: int | None = None
) -> int | None:
    """Flank tolerance class achieved by one measured deviation.

    The smallest class ``A`` in 1..11 whose rounded tolerance for ``parameter`` is >= ``|value_um|``
    (the magnitude, so signed slope deviations ``f_Halpha``, ``f_Hbeta`` grade alike either way).

    Parameters
    ----------
    value_um : float
        Measured deviation, um.
    parameter : str
        One of :data:`PARAMETERS`.
    z, mn, b, beta_deg, k
        Gear data as in :func:`tolerances`.

    Returns
    -------
    int or None
        The class, or ``None`` if the deviation exceeds the class-11 tolerance.
    """
    _check_parameter(parameter)
    return _grade(value_um, parameter, _gear(z, mn, b, beta_deg, k))


def overall_class(
    measured: Mapping[str, float], z: int, mn: float, b: float, beta_deg: float, k: int | None = None
) -> dict[str, int | None]:
    """Class of each measured deviation and the overall (worst) class.

    Parameters
    ----------
    measured : Mapping[str, float]
        Measured deviations in um keyed by names from :data:`PARAMETERS` (any subset, at least one).
    z, mn, b, beta_deg, k
        Gear data as in :func:`tolerances`.

    Returns
    -------
    dict[str, int | None]
        ``{parameter: class}`` for each parameter given, plus ``"overall"``: the largest class, or ``None``
        if any deviation is worse than class 11.
    """
    if not measured:
        raise ValueError("measured must name at least one parameter")
    for parameter in measured:
        _check_parameter(parameter)
    g = _gear(z, mn, b, beta_deg, k)
    result: dict[str, int | None] = {p: _grade(v, p, g) for p, v in measured.items()}
    classes = list(result.values())
    result["overall"] = None if None in classes else max(c for c in classes if c is not None)
    return result
