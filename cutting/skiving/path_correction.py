"""Flank modifications made by the tool's path in skiving (seed 003's radial and tangential corrections).

Along the stroke the CNC may change the centre distance by da(s) (the radial correction k_r: both flanks of a
space move alike, e = k_r da with k_r ~ sin(alpha_t) on an external gear) and turn the work by an extra dphi2(s)
through the electronic gearbox's summator (the tangential correction k_t: the flanks move oppositely,
e = +-r_b dphi2). Together they make any modification that depends on the face position z alone: lead crowning,
end relief, a helix angle modification, or different ones on the two flanks. What varies over the profile (profile
crowning, tip relief, twist) the path cannot make: that takes a modified cutter.

:class:`PathCorrection` holds the two corrections at knots over the carriage position and interpolates them with
a cubic spline (a chain of cubic Bezier segments, C2 at the knots); :func:`corrected_motion` samples the ideal
motion of a pass with them applied, as a :class:`cutting.skiving.sampled_motion.SampledMotion` that the removal and the
exact swept surface take like any other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.interpolate import CubicSpline

from cutting.skiving.kinematics import rot_z
from cutting.skiving.sampled_motion import SampledMotion
from cutting.skiving.trajectory import PassMotion


@dataclass(frozen=True, eq=False)
class PathCorrection:
    """Radial ``da`` [mm] and tangential ``dphi`` [rad] corrections at the carriage positions ``s`` [mm] (the
    knots, increasing); constant beyond the end knots."""

    s: np.ndarray
    da: np.ndarray
    dphi: np.ndarray

    @classmethod
    def zero(cls, s: np.ndarray) -> PathCorrection:
        s = np.asarray(s, dtype=float)
        return cls(s, np.zeros_like(s), np.zeros_like(s))

    @cached_property
    def _splines(self) -> tuple[CubicSpline, CubicSpline]:
        return CubicSpline(self.s, self.da, bc_type="natural"), CubicSpline(self.s, self.dphi, bc_type="natural")

    def at(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        s = np.clip(np.asarray(s, dtype=float), self.s[0], self.s[-1])
        da, dphi = self._splines
        return da(s), dphi(s)

    def at_point(self, s: float) -> tuple[float, float]:
        """The corrections at one carriage position (the CNC's tick)."""
        da, dphi = self.at(s)
        return float(da), float(dphi)

    def bezier(self) -> list[dict[str, list[float]]]:
        """The path as cubic Bezier segments between the knots: per segment the carriage span and the four
        control values of da [mm] and dphi [rad] (what a CNC's spline interpolation takes)."""
        out = []
        for name, values in (("da", self.da), ("dphi", self.dphi)):
            spline = CubicSpline(self.s, values, bc_type="natural")
            d = spline.derivative()
            for i in range(len(self.s) - 1):
                s0, s1 = self.s[i], self.s[i + 1]
                h = s1 - s0
                y0, y1 = float(spline(s0)), float(spline(s1))
                c = [y0, y0 + h * float(d(s0)) / 3, y1 - h * float(d(s1)) / 3, y1]
                if name == "da":
                    out.append({"s": [float(s0), float(s1)], "da": c})
                else:
                    out[i]["dphi"] = c
        return out


def corrected_motion(motion: PassMotion, correction: PathCorrection, rate: float = 4000.0) -> SampledMotion:
    """The pass's ideal motion with the path corrections applied, sampled at ``rate`` [Hz] (Hermite-interpolated
    by the engine between samples, 0.06 um on a 50 mm lever at 4 kHz)."""
    setup = motion.setup
    n = max(4, math.ceil(motion.duration * rate) + 1)
    t = np.linspace(0.0, motion.duration, n)
    s = motion.carriage(t)
    da, dphi = correction.at(s)
    a = motion.centre_distance + da
    rot, trans = setup.cutter_pose(motion.cutter_angle(t), s, a)
    back = rot_z(-dphi)  # the work turned on by dphi: the cutter turns back by it in the work frame
    return SampledMotion(
        setup, motion.index, t, back @ rot, np.einsum("nij,nj->ni", back, trans), motion.cutter_angle(t), s, a
    )
