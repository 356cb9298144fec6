"""The CNC's part program for a skiving job: run-up, then per pass infeed, feed stroke, retract and return.

Segments are produced tick by tick as :class:`CncState` plus the radial slide's target; a feed stroke ends
when the lead screw has received exactly the pass's pulses, and the rapid return undoes those pulses (and
the B4 pulses of the helix) with a linear interpolator, so every pass starts in the same helix phase.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.path_correction import PathCorrection
from cutting.skiving.trajectory import PassMotion
from virtual_machine.structures.mechatronic import CncState


@dataclass(frozen=True)
class ProgramSettings:
    runup: float = 0.4  # s: shortest reference generator ramp 0 -> f_ref (smooth step), axes keep their ratios
    # rad/s^2: the work spindle's largest acceleration in the run-up (the smooth step peaks at 1.5x its mean); the
    # small machine's work drive holds 740 and saturates at 1000 (its motor's peak torque), so the ramp
    # lengthens for fast jobs instead of losing synchronism; MachineRun takes the machine's own (work_acceleration)
    runup_acceleration: float = 600.0
    following_error_limit: float = 1000.0  # um of arc on d: the CNC stops the job beyond this sync error
    settle: float = 0.1  # s: dwell at speed before the first pass
    radial_move: float = 0.08  # s: duration of a radial infeed or retract move
    retract: float = 1.0  # mm: radial clearance for the return stroke
    rapid_speed: float = 60.0  # mm/s: carriage speed of the return stroke


@dataclass
class Tick:
    segment: str  # "runup", "settle", "infeed", "feed", "retract", "return"
    pass_index: int  # -1 outside a pass
    cnc: CncState
    radial: float  # radial slide target [m]


def smoothstep(x: float) -> float:
    x = min(max(x, 0.0), 1.0)
    return x * x * (3 - 2 * x)


def runup_time(setup: SkivingSetup, settings: ProgramSettings) -> float:
    """Length of the run-up ramp [s]: the shortest ramp, or longer where the work spindle's acceleration limit
    asks for it."""
    omega2 = abs(setup.work_speed) * 2 * math.pi / 60
    return max(settings.runup, 1.5 * omega2 / settings.runup_acceleration)


def program_duration(
    setup: SkivingSetup, settings: ProgramSettings | None = None, passes: Sequence[PassMotion] | None = None
) -> float:
    """Machine time of the whole program [s] (the return of S3 at feed rate counted as a rapid: an estimate for
    progress bars). ``passes``: the setup's ideal passes if the caller has them."""
    from cutting.skiving.trajectory import ideal_passes

    settings = settings or ProgramSettings()
    passes = ideal_passes(setup) if passes is None else passes
    return pass_start_times(setup, settings, passes)[-1] + passes[-1].duration


def pass_start_times(setup: SkivingSetup, settings: ProgramSettings, passes: Sequence[PassMotion]) -> list[float]:
    """Machine time at which each pass's feed stroke starts [s] (as :func:`program` makes them: the run-up and the
    settle, then per pass the stroke, the retract, the return at the rapid speed, the infeed and its dwell)."""
    t = runup_time(setup, settings) + settings.settle
    out = [t]
    for i in range(len(passes) - 1):
        travel = abs(passes[i + 1].s_start - passes[i].s_start - passes[i].v_s * passes[i].duration)
        t += passes[i].duration + 3 * settings.radial_move + travel / settings.rapid_speed
        out.append(t)
    return out


def program(
    setup: SkivingSetup,
    dt: float,
    screw_pulses_per_mm: float,
    machine,
    settings: ProgramSettings | None = None,
    correction: PathCorrection | None = None,
    work_pulses_per_rad: float = 0.0,
    passes: Sequence[PassMotion] | None = None,
) -> Iterator[Tick]:
    """Ticks of the whole job. ``machine`` is the structure: the CNC reads the pulses it has issued
    (``screw_pulses``, ``b4_pulses``) and its B4 pulses for a screw position (``b4_for_screw``).

    ``correction`` (a flank modification's path, seed 003): during the finishing stroke the CNC sets the radial
    slide to the pass's centre distance plus da(s) and asks summator 9 for the extra work turn dphi2(s), in
    ``work_pulses_per_rad`` command pulses per radian, at the carriage position s it has commanded. ``passes``: the
    setup's ideal passes if the caller has them (the run's plan)."""
    from cutting.skiving.trajectory import ideal_passes

    settings = settings or ProgramSettings()
    passes = ideal_passes(setup) if passes is None else passes
    down = setup.feed_direction == "down"
    feed_dir = -1 if down else 1
    out_sign = -1.0 if setup.gear.internal else 1.0  # retracting increases a (external), decreases it (internal)
    a = [m.centre_distance * 1e-3 for m in passes]
    n = max(1, round(runup_time(setup, settings) / dt))
    for k in range(n):
        yield Tick("runup", -1, CncState(scale=smoothstep((k + 1) / n), feed_dir=feed_dir), a[0])
    settle = Tick("settle", -1, CncState(scale=1.0, feed_dir=feed_dir), a[0])  # constant ticks are shared
    for _ in range(round(settings.settle / dt)):
        yield settle
    moves = max(1, round(settings.radial_move / dt))
    for i, motion in enumerate(passes):
        target = round(motion.duration * abs(motion.v_s) * screw_pulses_per_mm)  # pulses of the stroke
        start_screw = machine.screw_pulses
        feed = Tick("feed", i, CncState(scale=1.0, feed=True, feed_dir=feed_dir), a[i])
        corrected = correction is not None and i == len(passes) - 1
        while abs(machine.screw_pulses - start_screw) < target:
            if corrected:
                s = motion.s_start + math.copysign(abs(machine.screw_pulses - start_screw), motion.v_s) / (
                    screw_pulses_per_mm
                )
                da, dphi = correction.at_point(s)
                cnc = CncState(scale=1.0, feed=True, feed_dir=feed_dir, correction_b4=dphi * work_pulses_per_rad)
                yield Tick("feed", i, cnc, a[i] + da * 1e-3)
                continue
            yield feed
        if i == len(passes) - 1:
            return
        away = a[i] + out_sign * settings.retract * 1e-3
        for k in range(moves):
            yield Tick(
                "retract", i, CncState(scale=1.0, feed_dir=feed_dir), a[i] + (away - a[i]) * smoothstep((k + 1) / moves)
            )
        # back to the start of the next pass (its travel differs with the depth), B4 following the carriage
        next_start = round((passes[i + 1].s_start - passes[0].s_start) * screw_pulses_per_mm)
        screw_back = next_start - machine.screw_pulses
        b4_back = machine.b4_for_screw(next_start) - machine.b4_pulses
        travel = abs(screw_back) / screw_pulses_per_mm
        if getattr(machine, "returns_by_reversing", False):
            # no traverse drive: the feed chain runs backwards at the feed rate (S3) until the screw is back
            back = Tick("return", i, CncState(scale=1.0, feed_dir=feed_dir, reverse=True), away)
            while (next_start - machine.screw_pulses) * -feed_dir > 0:
                yield back
            travel = 0.0
        steps = math.ceil(travel / settings.rapid_speed / dt)
        done_s = done_b = 0
        for k in range(steps):
            f = smoothstep((k + 1) / steps)
            s, b = round(screw_back * f), round(b4_back * f)
            yield Tick(
                "return", i, CncState(scale=1.0, feed_dir=feed_dir, rapid_screw=s - done_s, rapid_b4=b - done_b), away
            )
            done_s, done_b = s, b
        for k in range(moves):
            yield Tick(
                "infeed",
                i + 1,
                CncState(scale=1.0, feed_dir=feed_dir),
                away + (a[i + 1] - away) * smoothstep((k + 1) / moves),
            )
        for _ in range(moves):  # dwell: let the radial slide and the carriage settle
            yield Tick("infeed", i + 1, CncState(scale=1.0, feed_dir=feed_dir), a[i + 1])
