"""Cylindrical involute gear geometry per ISO 21771 (external and internal, spur and helical).

Conventions used throughout skive:

- lengths in mm, angles in radians inside the code (degrees only at the job-file boundary);
- helix angle signed, right hand positive;
- profile shift ``x`` positive when the profile reference line moves towards the tooth tip (ISO 21771 /
  DIN 3960): thicker teeth at the reference circle for external *and* internal gears, so the normal
  reference tooth thickness is ``s_n = mn (pi/2 + 2 x tan alpha_n)`` for both;
- diameters are positive for internal gears too; ``internal`` flips the sense where it matters
  (an internal gear's tip is its smallest diameter);
- gear frame: z along the gear axis, z = 0 on the mid face plane, tooth 0 centred on +x at z = 0;
  tooth k is centred at ``2 pi k / z`` (counter-clockwise seen from +z).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike

from cutting.errors import Problem
from cutting.involute import inv


@dataclass(frozen=True)
class BasicRack:
    """Basic rack profile in units of the normal module (ISO 53 profile A by default).

    ha: addendum coefficient of the gear (h_aP / mn)
    hf: dedendum coefficient of the gear (h_fP / mn)
    rho_f: root fillet radius coefficient of the rack (rho_fP / mn), rounds the generating tool tip
    """

    ha: float = 1.0
    hf: float = 1.25
    rho_f: float = 0.38

    def straight_dedendum(self, alpha_n: float) -> float:
        """Height (in mn) below the datum line down to where the rack tip fillet begins.

        This is the part of the tool tip that generates involute; undercut starts when it reaches
        below the base circle's line-of-action limit.
        """
        return self.hf - self.rho_f * (1.0 - math.sin(alpha_n))


ISO53_A = BasicRack()

#: Smallest normal tooth thickness at the tip, in multiples of mn, that skive accepts. 0.2 mn is the
#: usual design minimum for through-hardened gears (0.4 mn is used for case-hardened ones).
MIN_TIP_THICKNESS = 0.2


@dataclass(frozen=True)
class Gear:
    """A cylindrical involute gear.

    Parameters
    ----------
    teeth: number of teeth z (> 0)
    normal_module: mn [mm]
    pressure_angle: normal pressure angle alpha_n [rad]
    helix_angle: reference helix angle beta [rad], right hand positive
    face_width: b [mm]
    profile_shift: x (see module docstring for the sign)
    internal: True for an internal (ring) gear
    tip_diameter, root_diameter: da, df [mm]; None means the basic-rack default
    rack: basic rack profile
    """

    teeth: int
    normal_module: float
    pressure_angle: float = math.radians(20.0)
    helix_angle: float = 0.0
    face_width: float = 10.0
    profile_shift: float = 0.0
    internal: bool = False
    tip_diameter: float | None = None
    root_diameter: float | None = None
    rack: BasicRack = field(default=ISO53_A)

    # ---- ISO 21771 reference quantities -------------------------------------------------------
    @property
    def z(self) -> int:
        return self.teeth

    @property
    def mn(self) -> float:
        return self.normal_module

    @property
    def alpha_n(self) -> float:
        return self.pressure_angle

    @property
    def beta(self) -> float:
        return self.helix_angle

    @property
    def x(self) -> float:
        return self.profile_shift

    @property
    def sense(self) -> int:
        """+1 for external, -1 for internal: the direction from the root towards the tip is -sense * r."""
        return -1 if self.internal else 1

    @cached_property
    def transverse_module(self) -> float:
        """m_t = mn / cos(beta) [mm]."""
        return self.mn / math.cos(self.beta)

    @cached_property
    def transverse_pressure_angle(self) -> float:
        """alpha_t = atan(tan(alpha_n) / cos(beta)) [rad]."""
        return math.atan(math.tan(self.alpha_n) / math.cos(self.beta))

    @cached_property
    def reference_diameter(self) -> float:
        """d = z mn / cos(beta) [mm]."""
        return self.z * self.transverse_module

    @cached_property
    def base_diameter(self) -> float:
        """d_b = d cos(alpha_t) [mm]."""
        return self.reference_diameter * math.cos(self.transverse_pressure_angle)

    @cached_property
    def base_helix_angle(self) -> float:
        """beta_b = asin(sin(beta) cos(alpha_n)) [rad], signed like beta."""
        return math.asin(math.sin(self.beta) * math.cos(self.alpha_n))

    @cached_property
    def lead(self) -> float:
        """Lead p_z = pi d / tan(beta) = pi mn z / sin(beta) [mm], signed like beta; inf for spur."""
        if self.beta == 0.0:
            return math.inf
        return math.pi * self.reference_diameter / math.tan(self.beta)

    @cached_property
    def normal_pitch(self) -> float:
        """p_n = pi mn [mm]."""
        return math.pi * self.mn

    @cached_property
    def transverse_pitch(self) -> float:
        """p_t = pi m_t [mm]."""
        return math.pi * self.transverse_module

    @cached_property
    def transverse_base_pitch(self) -> float:
        """p_bt = p_t cos(alpha_t) [mm]."""
        return self.transverse_pitch * math.cos(self.transverse_pressure_angle)

    @cached_property
    def normal_tooth_thickness(self) -> float:
        """s_n = mn (pi/2 + 2 x tan(alpha_n)) at the reference circle [mm] (external and internal)."""
        return self.mn * (math.pi / 2 + 2 * self.x * math.tan(self.alpha_n))

    @cached_property
    def transverse_tooth_thickness(self) -> float:
        """s_t = s_n / cos(beta) [mm]."""
        return self.normal_tooth_thickness / math.cos(self.beta)

    @cached_property
    def tip_diameter_value(self) -> float:
        """d_a [mm]: as given, else d + 2 mn (ha + x) external, d - 2 mn (ha + x) internal."""
        if self.tip_diameter is not None:
            return float(self.tip_diameter)
        return self.reference_diameter + 2 * self.sense * self.mn * (self.rack.ha + self.x)

    @cached_property
    def root_diameter_value(self) -> float:
        """d_f [mm]: as given, else d - 2 mn (hf - x) external, d + 2 mn (hf - x) internal."""
        if self.root_diameter is not None:
            return float(self.root_diameter)
        return self.reference_diameter - 2 * self.sense * self.mn * (self.rack.hf - self.x)

    @property
    def reference_radius(self) -> float:
        return self.reference_diameter / 2

    @property
    def base_radius(self) -> float:
        return self.base_diameter / 2

    @property
    def tip_radius(self) -> float:
        return self.tip_diameter_value / 2

    @property
    def root_radius(self) -> float:
        return self.root_diameter_value / 2

    @cached_property
    def tooth_depth(self) -> float:
        """h = |d_a - d_f| / 2 [mm]."""
        return abs(self.tip_diameter_value - self.root_diameter_value) / 2

    # ---- tooth thickness at any diameter ------------------------------------------------------
    def half_thickness_angle(self, radius: ArrayLike) -> np.ndarray | float:
        """Half the angular tooth thickness psi(r) in a transverse section [rad].

        External: psi = s_t/d + inv(alpha_t) - inv(alpha_y); internal: psi = s_t/d - inv(alpha_t) + inv(alpha_y),
        with cos(alpha_y) = r_b / r. Valid for r >= r_b.
        """
        r = np.asarray(radius, dtype=float)
        alpha_y = np.arccos(np.clip(self.base_radius / r, -1.0, 1.0))
        out = self.transverse_tooth_thickness / self.reference_diameter + self.sense * (
            inv(self.transverse_pressure_angle) - inv(alpha_y)
        )
        return float(out) if np.ndim(out) == 0 else out

    def transverse_thickness_at(self, diameter: float) -> float:
        """Transverse arc tooth thickness s_yt on diameter d_y [mm]."""
        return float(diameter * self.half_thickness_angle(diameter / 2))

    def normal_thickness_at(self, diameter: float) -> float:
        """Normal tooth thickness s_yn on diameter d_y [mm]: s_yt cos(beta_y), tan(beta_y) = tan(beta) d_y / d."""
        beta_y = math.atan(math.tan(self.beta) * diameter / self.reference_diameter)
        return self.transverse_thickness_at(diameter) * math.cos(beta_y)

    @cached_property
    def tip_normal_thickness(self) -> float:
        """s_an: normal tooth thickness on the tip circle [mm] (negative means the flanks cross: pointed)."""
        return self.normal_thickness_at(self.tip_diameter_value)

    # ---- generation by the basic rack ---------------------------------------------------------
    @cached_property
    def min_profile_shift(self) -> float:
        """Smallest x free of undercut when generated by the basic rack (external gears).

        x_min = (hf - rho_f (1 - sin alpha_n)) - z sin^2(alpha_t) / (2 cos(beta)); z_min = 17 for spur 20 deg.
        """
        return self.rack.straight_dedendum(self.alpha_n) - self.z * math.sin(self.transverse_pressure_angle) ** 2 / (
            2 * math.cos(self.beta)
        )

    @cached_property
    def rack_form_diameter(self) -> float:
        """Diameter where the involute generated by the basic rack begins (external), d_Ff [mm].

        Roll length at the start: L = r_b tan(alpha_t) - mn (hf - rho_f(1 - sin alpha_n) - x) / sin(alpha_t).
        For an internal gear the involute starts at the tip; the root-side limit depends on the
        cutter, so this returns the tip diameter there.
        """
        if self.internal:
            return self.tip_diameter_value
        lift = self.mn * (self.rack.straight_dedendum(self.alpha_n) - self.x)
        roll = self.base_radius * math.tan(self.transverse_pressure_angle) - lift / math.sin(
            self.transverse_pressure_angle
        )
        return 2 * math.sqrt(self.base_radius**2 + max(roll, 0.0) ** 2)


def check_gear(gear: Gear, prefix: str = "gear") -> list[Problem]:
    """Every reason why ``gear`` is not a valid involute gear to make (undercut, pointed, no involute...)."""
    out: list[Problem] = []
    da, df, db = gear.tip_diameter_value, gear.root_diameter_value, gear.base_diameter
    if gear.internal:
        if not df > da:
            out.append(
                Problem(
                    f"{prefix}.root_diameter",
                    round(df, 6),
                    f"an internal gear's root diameter must exceed its tip diameter {da:.4f} mm",
                    f"give a root diameter above {da:.4f} mm",
                )
            )
            return out
        if da <= db:
            out.append(
                Problem(
                    f"{prefix}.tip_diameter",
                    round(da, 6),
                    f"the internal gear's tip circle lies inside its base circle d_b = {db:.4f} mm: "
                    "the tooth tips would not be involute",
                    f"use a tip diameter above {db:.4f} mm (or a profile shift below {gear.x:+.3f})",
                )
            )
            return out
    else:
        if not da > df > 0:
            out.append(
                Problem(
                    f"{prefix}.tip_diameter",
                    round(da, 6),
                    f"the tip diameter must exceed the root diameter {df:.4f} mm, which must be > 0",
                    "check tip_diameter, root_diameter and profile_shift",
                )
            )
            return out
        if gear.x < gear.min_profile_shift - 1e-9:
            out.append(
                Problem(
                    f"{prefix}.profile_shift",
                    gear.x,
                    f"the gear is undercut: z = {gear.z} needs x >= {gear.min_profile_shift:+.4f} to be free "
                    f"of undercut by the basic rack (hf = {gear.rack.hf}, rho_f = {gear.rack.rho_f})",
                    f"use profile_shift >= {gear.min_profile_shift:+.4f} or more teeth",
                )
            )
    if gear.tip_normal_thickness < MIN_TIP_THICKNESS * gear.mn:
        out.append(
            Problem(
                f"{prefix}.tip_diameter",
                round(da, 6),
                f"the teeth are pointed: normal tooth thickness at the tip s_an = {gear.tip_normal_thickness:.4f} mm "
                f"< {MIN_TIP_THICKNESS} mn = {MIN_TIP_THICKNESS * gear.mn:.4f} mm",
                "reduce the tip diameter (external) / enlarge it (internal), or reduce the profile shift",
            )
        )
    return out


def form_roll_length(gear: Gear) -> float:
    """Roll length where the active profile starts on the root side when the job does not set it [mm].

    External: where the involute generated by the basic rack begins,
    L = r_b tan(alpha_t) - mn (hf - rho_f (1 - sin alpha_n) - x) / sin(alpha_t), the earliest possible start.
    Internal: the tip circle of a standard mating pinion, d + 2 mn (ha - x): an internal gear's root form
    depends on the cutter, and no mate can use more of the flank than this.
    """
    if gear.internal:
        return math.sqrt(max((gear.reference_radius + gear.mn * (gear.rack.ha - gear.x)) ** 2 - gear.base_radius**2, 0))
    h = gear.mn * (gear.rack.straight_dedendum(gear.alpha_n) - gear.x)
    at = gear.transverse_pressure_angle
    return gear.base_radius * math.tan(at) - h / math.sin(at)
