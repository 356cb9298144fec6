"""The face-contour machine's electronic gearbox (seed 004: continuous indexing; the equal-coordinates scheme of
seed 000 fig. 4 as its means): one pulse train couples the work, the eccentric and the infeed to the tool head.

Seed 004 cuts the m radial slots of a face coupling with the tool head (radius R, at the setting angle lambda =
arcsin(L / (R m)), eq. 1) and the workpiece turning in the fixed ratio omega_t = m omega_w (eq. 11), the element's
path eq. 5 with S the feed per tool revolution, the slots corrected by one of the seed's kinematic controls: an
**eccentric** carrying the head (fig. 3, radius e, eq. 14; geared N times to the head, the N of eq. 15) or a
**cyclic change of the speed ratio**. :class:`ElectronicGearbox` makes every axis count the pulses of **reference
generator 14** (its axes, its masters and its converters there); the axes' servos
(:mod:`virtual_machine.controllers.cascade`) follow its commands.
"""

from __future__ import annotations

import math

import numpy as np

from cutting.errors import InputError, Problem
from cutting.face_contour.slots import FaceCoupling, held_speed_factor, work_offset, workpiece_angle

from .pulses import FrequencyDivider, RateMultiplier, ReferenceGenerator, Summator

_A, _H, _E, _Z, _Y = range(5)
#: what the work, the eccentric and the cross slide follow: generator 14's pulses, or the head's spindle encoder
MASTERS = ("generator", "head")  # the command layout: work angle a, head angle phi, eccentric [rad], infeed, cross [m]


class ElectronicGearbox:
    """Reference generator 14 -> head H; -> frequency divider 7 (1/m, eq. 11) -> summator 9 (+ cyclic-ratio
    modulation) -> work A; -> rate multiplier N -> eccentric E (fig. 3); -> rate multiplier ks (S per turn, eq. 5),
    gated at the depth -> infeed Z; function generator T (1 - cos q_s phi) -> cross slide Y.

    Every axis counts the pulses of generator 14 (p pulses per head revolution):

    - tool head H: the generator's pulses themselves (divider 6 with kv = 1: the generator's frequency sets the
      head's speed, with a half-cosine run-up), phi = phi0 + 2 pi n / p; with ``hold_speed`` the generator's
      frequency follows eq. 16 (:func:`cutting.face_contour.slots.held_speed_factor`): the head slows where the
      eccentric's speed adds to the tip's, so the tip keeps its speed at M all round (every axis counts the same
      pulses: the paths in phi stay the same, only their timing changes);
    - work spindle A: **frequency divider** 7 with k = m (the indexing ratio 1/m, eq. 11) -> **summator** 9, whose
      second input carries the cyclic-ratio modulation - A (1 - cos q phi) of
      :func:`cutting.face_contour.slots.workpiece_angle` (control "cyclic_ratio"; the CNC's function generator of the
      head's command angle) -> A;
    - eccentric E (control "eccentric"): a rate multiplier N (N pulses per generator pulse): the eccentric e geared
      N times to the head, E = N phi;
    - cross slide Y (control "work_setting", the work's setting changed during the cut): the CNC's function
      generator of the head's command angle, Y = T (1 - cos q_s phi) (:func:`cutting.face_contour.slots.work_offset`;
      q_s m cycles per workpiece revolution);
    - infeed Z: rate multiplier ks (S / resolution pulses per p generator pulses: the seed's feed S per tool
      revolution), gated by the CNC at the programmed depth (then the spark-out: one more workpiece revolution),
      Z = - min(S phi / 2 pi, depth).

    **Master** (``master``): ``"generator"`` (the equal-coordinates scheme of seed 000 fig. 4, default): every axis
    counts generator 14's pulses, so the work, the eccentric and the cross slide follow the head's *command*; where
    the head lags it (its drive's torsion under the cutting torque, its speed dipping as an element crosses a slot)
    the slots move with the lag. ``"head"`` (the master-slave scheme of seed 001 fig. 2 on this machine): the head
    still follows the generator, but the slaves count the pulses of the direct encoder on the cutter spindle (its
    absolute angle behind the head drive; speed and acceleration from the same encoder), so they copy what the head
    really does.

    The pulse-to-analog converters turn each axis's fine count (its divider's content included, no +-1 pulse jitter)
    into the position command and the generator's frequency into the speed feed-forward.

    Parameters: the coupling ``c``, the head turn ``start_turn`` the run starts at (the axes where the programme has
    them then), the head's full speed ``tool_speed`` [rad/s], ``pulses_per_rev`` (command pulses per revolution of
    A, H and E), ``infeed_resolution`` [m per infeed pulse], the generator's half-cosine run-up ``ramp`` [s] and
    ``hold_speed``: the head's speed by eq. 16 (the tip's speed held under the eccentric); ``master``: "generator" or
    "head" (the slaves follow the head's spindle encoder, ``command``'s ``head``).
    ``command(t, dt)`` gives the axes' positions, speeds and accelerations (A, H, E [rad], Z, Y [m]) for the tick that
    starts at t; ``update(dt, t)`` issues that tick's pulses."""

    def __init__(
        self,
        c: FaceCoupling,
        start_turn: int,
        tool_speed: float,
        pulses_per_rev: int,
        infeed_resolution: float,
        ramp: float,
        hold_speed: bool = False,
        master: str = "generator",
    ):
        if master not in MASTERS:
            raise ValueError(f"master: must be one of {MASTERS}, got {master!r}")
        self.master = master
        self.c, self.infeed_resolution, self.ramp = c, infeed_resolution, ramp
        self.hold_speed = hold_speed and c.eccentric_on
        p = pulses_per_rev
        self.rad = 2 * math.pi / p  # rad per command pulse
        self.f_full = tool_speed / self.rad  # Hz: generator frequency at the head's full speed
        self.gen14 = ReferenceGenerator(0.0)
        self.d7 = FrequencyDivider(c.m)
        self.s9 = Summator(1)
        self.mult_e = RateMultiplier(c.eccentric_ratio, 1)
        n_s = round(c.S * 1e-3 / infeed_resolution)
        if n_s < 1:
            raise InputError(
                Problem(
                    "coupling.S",
                    c.S,
                    f"the infeed per head turn is below the gearbox's infeed resolution {infeed_resolution * 1e3:g} mm",
                    f"give coupling.S >= {infeed_resolution * 1e3:g} mm",
                )
            )
        self.ks = RateMultiplier(n_s, p)
        self.feed_per_turn = n_s * infeed_resolution  # m: S as the gearbox realises it
        self.depth_pulses = round(c.depth * 1e-3 / infeed_resolution)
        self.phi0 = 2 * math.pi * start_turn
        self.a0 = float(workpiece_angle(c, self.phi0))
        self.e0 = c.eccentric_ratio * self.phi0 if c.eccentric_on else 0.0
        self.feed0 = round(start_turn * n_s)  # infeed pulses issued before the start (the plunge so far)
        self.eccentric = c.eccentric_on

    def scale(self, t: float) -> tuple[float, float]:
        """The generator's frequency as a fraction of its full value and its rate [1/s]: half-cosine run-up."""
        ramp = self.ramp
        if t >= ramp:
            return 1.0, 0.0
        return 0.5 * (1 - math.cos(math.pi * t / ramp)), 0.5 * math.pi / ramp * math.sin(math.pi * t / ramp)

    def _factor(self, phi: float) -> tuple[float, float]:
        """Eq. 16's factor on the head speed at head angle phi and its derivative in phi (1, 0 without it)."""
        if not self.hold_speed:
            return 1.0, 0.0
        k, dk = held_speed_factor(self.c, phi)
        return float(k), float(dk)

    @property
    def phi(self) -> float:
        """The head's commanded angle [rad]."""
        return self.phi0 + self.gen14.position * self.rad

    def _mid_tick(self, t: float, dt: float) -> tuple[float, float]:
        """The head angle and the generator's fraction of full frequency (run-up times eq. 16's factor) at the
        middle of the tick that starts at t."""
        phi = self.phi
        w = self.f_full * self.rad * self.scale(t)[0] * self._factor(phi)[0]
        phi_mid = phi + w * dt / 2
        return phi_mid, self.scale(t + dt / 2)[0] * self._factor(phi_mid)[0]

    def command(
        self, t: float, dt: float, head: tuple[float, float, float] | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Positions and speeds at the tick's start t, accelerations at its middle (the torque is held for the tick:
        a zero-order hold; the acceleration at the start would leave a phase lag of half a tick). ``head``: the
        head's spindle encoder now (angle [rad], speed [rad/s], acceleration [rad/s^2]), which the slaves follow
        under ``master = "head"``."""
        c, rad = self.c, self.rad
        phi = self.phi
        w = self.f_full * rad * self.scale(t)[0] * self._factor(phi)[0]  # head speed [rad/s]
        phi_est, fraction = self._mid_tick(t, dt)
        w_mid = self.f_full * rad * fraction  # [rad/s]
        s_mid, ds_mid = self.scale(t + dt / 2)
        k_mid, dk_mid = self._factor(phi_est)
        dw = self.f_full * rad * (ds_mid * k_mid + s_mid * dk_mid * w_mid)  # [rad/s^2]
        pos, vel, acc = np.zeros(5), np.zeros(5), np.zeros(5)
        phi_mid = phi + 0.5 * (w + w_mid) * dt / 2
        pos[_H], vel[_H], acc[_H] = phi, w, dw
        # work: divider 7 -> summator 9 (main: the divided train, second input: the cyclic-ratio modulation)
        self.s9.a = self.d7.fine_position
        self.s9.b = 0.0
        vel[_A], acc[_A] = w / c.m, dw / c.m
        if c.cyclic_on:
            amp, q = c.ratio_amplitude, c.ratio_cycles
            self.s9.b = (float(workpiece_angle(c, phi)) - phi / c.m) / rad
            vel[_A] -= amp * q * math.sin(q * phi) * w
            acc[_A] -= amp * q * (q * math.cos(q * phi_mid) * w_mid**2 + math.sin(q * phi_mid) * dw)
        self.s9.update(0.0)
        pos[_A] = self.a0 + self.s9.out * rad
        if self.eccentric:
            n = c.eccentric_ratio
            pos[_E], vel[_E], acc[_E] = self.e0 + self.mult_e.fine_position * rad, n * w, n * dw
        if c.work_setting_on:  # the function generator of the head's command angle (mm -> m)
            T, q = c.setting_offset * 1e-3, c.setting_cycles
            pos[_Y] = float(work_offset(c, phi)[0]) * 1e-3
            vel[_Y] = T * q * math.sin(q * phi) * w
            acc[_Y] = T * q * (q * math.cos(q * phi_mid) * w_mid**2 + math.sin(q * phi_mid) * dw)
        if self.master == "head" and head is not None:
            self._follow(head, dt, pos, vel, acc)
        fed = self.feed0 + self.ks.fine_position
        res = self.infeed_resolution
        pos[_Z] = -min(fed, self.depth_pulses) * res
        if fed < self.depth_pulses:
            vel[_Z], acc[_Z] = -self.feed_per_turn * w / (2 * math.pi), -self.feed_per_turn * dw / (2 * math.pi)
        return pos, vel, acc

    def _follow(
        self, head: tuple[float, float, float], dt: float, pos: np.ndarray, vel: np.ndarray, acc: np.ndarray
    ) -> None:
        """The slaves' commands from the head's spindle encoder (angle, speed, acceleration): the same functions of
        the head angle as the generator's counts give them, at the head's real angle; accelerations at the tick's
        middle, as :meth:`command`'s (the torque is held over the tick)."""
        c = self.c
        phi, w, dw = head
        mid, w_mid = phi + w * dt / 2, w + dw * dt / 2
        a = float(workpiece_angle(c, phi))
        pos[_A], vel[_A], acc[_A] = a, w / c.m, dw / c.m
        if c.cyclic_on:
            amp, q = c.ratio_amplitude, c.ratio_cycles
            vel[_A] -= amp * q * math.sin(q * phi) * w
            acc[_A] -= amp * q * (q * math.cos(q * mid) * w_mid**2 + math.sin(q * mid) * dw)
        if self.eccentric:
            n = c.eccentric_ratio
            pos[_E], vel[_E], acc[_E] = n * phi, n * w, n * dw
        if c.work_setting_on:
            T, q = c.setting_offset * 1e-3, c.setting_cycles
            pos[_Y] = float(work_offset(c, phi)[0]) * 1e-3
            vel[_Y] = T * q * math.sin(q * phi) * w
            acc[_Y] = T * q * (q * math.cos(q * mid) * w_mid**2 + math.sin(q * mid) * dw)

    def update(self, dt: float, t: float) -> None:
        """Issue the pulses of the tick that starts at t, at the generator frequency of its middle (the pulses then
        advance each command by what its speed and held acceleration move the axis: the trapezoid rule)."""
        gen = self.gen14
        gen.frequency = self.f_full * self._mid_tick(t, dt)[1]
        gen.update(dt)
        self.d7.inp = gen.out
        self.d7.update(dt)
        self.mult_e.inp = gen.out
        self.mult_e.update(dt)
        # the CNC's gate: the feed stops at the programmed depth (the spark-out turns on)
        self.ks.inp = gen.out if self.feed0 + self.ks.position < self.depth_pulses else 0
        self.ks.update(dt)
