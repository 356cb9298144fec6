"""Machine setting sheets: the seeds' setting formulas for every structure, realised on real setting organs.

A machine of seed 000 (skiving: S1 mechanical, S2 hydraulic with differential, S3 hydraulic shaft, S4 mechatronic)
or of seed 001 (the thread-cutting group Fv(B1 P2)) is set by ratios that its organs (change-gear guitars, coding
discs, integer frequency dividers) can only approximate: each sheet computes the seed's formulas, realises each on its
organ and states what the realised value's error does to the gear. :func:`setup_sheet` gives a job's
:class:`SetupSheet` of :class:`Setting` rows, one function per structure (:func:`sheet_mechanical` ...
:func:`sheet_mechatronic`, :func:`thread_sheet`); the signs: :func:`feed_over_lead`. The formulas per structure and
where skive departs from the printed seed: docs/machines.md, "Setting sheets".
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

from cutting.errors import InputError, Problem
from virtual_machine.job import Job, machine_constants
from virtual_machine.setting.change_gears import STANDARD_SET, ChangeGearSet, choose_change_gears


@dataclass
class Setting:
    """One setting organ: the seed formula's value and how the machine realises it."""

    name: str
    organ: str  # the seed element that carries it, e.g. "guitar ix (chain 4 -> 5)"
    formula: str
    value: float  # the formula's value (ideal)
    realised: float | None = None  # what the organ really sets
    realisation: dict[str, Any] = field(default_factory=dict)  # gears / integer coefficients
    effect: dict[str, float] = field(default_factory=dict)  # consequences of the realisation error

    @property
    def relative_error(self) -> float:
        if self.realised is None or self.value == 0:
            return 0.0
        return (self.realised - self.value) / self.value

    def to_json(self) -> dict[str, Any]:
        return {
            "organ": self.organ,
            "formula": self.formula,
            "value": self.value,
            "realised": self.realised,
            "relative_error": self.relative_error,
            **self.realisation,
            "effect": self.effect,
        }


@dataclass
class SetupSheet:
    structure: str
    kind: str  # "skiving" or "thread"
    settings: dict[str, Setting]
    constants: dict[str, float]
    geometry: dict[str, Any]
    passes: list[dict[str, float]]
    sanity: dict[str, float]
    notes: list[str]

    def to_json(self) -> dict[str, Any]:
        return {
            "structure": self.structure,
            "kind": self.kind,
            "settings": {k: s.value for k, s in self.settings.items()},
            "realisation": {k: s.to_json() for k, s in self.settings.items()},
            "constants": self.constants,
            "geometry": self.geometry,
            "passes": self.passes,
            "sanity": self.sanity,
            "notes": self.notes,
        }


# ---- realising a ratio ---------------------------------------------------------------------------
def gear_set_of(job: Job) -> ChangeGearSet:
    teeth = job.machine.change_gears
    return STANDARD_SET if teeth is None else ChangeGearSet("job", tuple(teeth))


def realise_guitar(setting: Setting, gear_set: ChangeGearSet, stages: int) -> Setting:
    """Choose change gears for ``setting.value`` (0 means the chain is disengaged)."""
    if setting.value == 0:
        setting.realised = 0.0
        setting.realisation = {"gears": None, "note": "chain disengaged (spur gear: no helix term)"}
        return setting
    try:
        train = choose_change_gears(abs(setting.value), gear_set, stages)
    except ValueError as exc:
        raise InputError(
            Problem(
                f"setting.{setting.name}",
                setting.value,
                f"{setting.organ} cannot set {setting.formula} = {abs(setting.value):.6g}: {exc}",
                "change the machine constant of that chain (machine.c1..c4, i_sigma, i01), the speed or feed, "
                "or supply machine.change_gears",
            )
        ) from exc
    setting.realised = math.copysign(train.ratio, setting.value)
    setting.realisation = {
        "gears": {"a_b_c_d" if stages == 2 else "a_b": list(train.teeth)},
        "describe": train.describe(),
        "set": gear_set.name,
    }
    return setting


def realise_pulse_generator(setting: Setting, steps_per_rev: int, max_windows: int) -> Setting:
    """Hydraulic pulse generator (coding disc of N windows) driving a stepping motor of q steps/rev.

    The ratio slave/master is N / q: the available ratios are a discrete set (seed 000 fig. 2).
    """
    if setting.value == 0:
        setting.realised = 0.0
        setting.realisation = {"disc_windows": None, "note": "generator disengaged (spur gear)"}
        return setting
    n = min(max(1, round(abs(setting.value) * steps_per_rev)), max_windows)
    setting.realised = math.copysign(n / steps_per_rev, setting.value)
    setting.realisation = {"disc_windows": n, "steps_per_rev": steps_per_rev}
    return setting


def divider_for_rate(f_ref: float, pulses_per_rev: float, rpm: float) -> float:
    """Divider coefficient k that turns f_ref into a command of ``rpm``: k = 60 f_ref / (p n)."""
    return 60.0 * f_ref / (pulses_per_rev * rpm)


def multiple_near(value: float, step: int) -> int:
    """The multiple of ``step`` nearest to ``value`` (at least ``step``)."""
    return max(step, step * round(value / step))


# ---- error consequences --------------------------------------------------------------------------
def ratio_error_effect(job: Job, eps: float) -> dict[str, float]:
    """A generating-ratio error eps: pitch arc per work revolution, and the drift over the face width.

    Per work revolution the work lags eps * 2 pi rad: eps pi d2 of arc on the reference circle. While the
    cutter crosses the face (b / s revolutions) the drift accumulates to r_b2 2 pi eps b / s along the base
    tangent: a helix slope error.
    """
    g, s = job.gear, job.process.axial_feed
    return {
        "pitch_um_per_work_rev": eps * math.pi * g.reference_diameter * 1e3,
        "helix_drift_um_over_face": eps * 2 * math.pi * g.base_radius * g.face_width / s * 1e3,
    }


def lead_error_effect(job: Job, eps: float) -> dict[str, float]:
    """A tooth-line ratio error eps: lead error eps T, helix slope eps b tan(beta_b) over the face."""
    g = job.gear
    return {
        "lead_um": eps * abs(g.lead) * 1e3,
        "helix_slope_um_over_face": eps * g.face_width * abs(math.tan(g.base_helix_angle)) * 1e3,
    }


def speed_effect(eps: float, what: str) -> dict[str, float]:
    return {f"{what}_percent": eps * 100}


# ---- skiving structures --------------------------------------------------------------------------
def _skiving_constants(job: Job, names: tuple[str, ...]) -> dict[str, float]:
    m = job.machine
    table = {
        "c1": m.c1,
        "c2": m.c2,
        "c3": m.c3,
        "c4": m.c4,
        "i_sigma": m.i_sigma,
        "t_tv": m.lead_screw_pitch,
        "n_m": m.motor_speed,
        "f_ref": m.reference_frequency,
        "p_cmd": m.command_pulses_per_rev,
        "q_step": m.hydraulic_steps_per_rev,
        "n_disc_max": m.hydraulic_max_windows,
    }
    return {n: table[n] for n in names}


def feed_over_lead(job: Job) -> float:
    """dir2 s_z / p_z: the carriage travel per work revolution over the signed lead, times the work's direction of
    rotation (+1 with the cutter, -1 against it); 0 for spur.

    The work turns phi2 = r phi0 - 2 pi z / p_z (cutting.skiving.kinematics), with z = s_z |phi2| / 2 pi, so per work
    turn the cutter turns (1 + dir2 s_z / p_z) / |r|: B4 slows the work (per cutter turn) when this is positive. An
    external gear turns against the cutter (dir2 = -1), an internal one with it: the sign is the gear's as much as
    the feed's.

    The sign conventions of skive: the additional rotation B4 and the "1 + s/T" of S3 carry the signs of the helix
    hand, the feed direction and the work's direction of rotation (s/T -> dir2 s_z / p_z with s_z = -s for a
    downward feed and dir2 = -1 for an external gear, which turns against the cutter); T is the lead of the gear
    helix, pi mn z2 / sin(beta2); see :mod:`cutting.skiving.kinematics`.
    """
    g = job.gear
    if g.helix_angle == 0:
        return 0.0
    s_z = -job.process.axial_feed if job.process.feed_direction == "down" else job.process.axial_feed
    dir_work = 1.0 if job.skiving.speed_ratio > 0 else -1.0
    return dir_work * s_z / g.lead


def sheet_mechanical(job: Job) -> tuple[dict[str, Setting], tuple[str, ...]]:
    """S1, seed 000 fig. 1: guitars ix, iy, iv, is; one motor M1 and a differential."""
    g, c, m, p = job.gear, job.cutter, job.machine, job.process
    gs = gear_set_of(job)
    T = g.lead
    ix = Setting(
        "ix", "guitar ix (Fv internal link, 4 -> 5)", "z0 / (c1 iS z2)", c.teeth / (m.c1 * m.i_sigma * g.teeth)
    )
    iy = Setting(
        "iy",
        "guitar iy (Fs internal link, 13 -> 14)",
        "t_TV / (T c2 iS)",
        0.0 if math.isinf(T) else m.lead_screw_pitch / (T * m.c2 * m.i_sigma),
    )
    iv = Setting("iv", "guitar iv (Fv external link, 10 -> 3)", "n0 / (c3 n_M)", p.tool_speed / (m.c3 * m.motor_speed))
    is_ = Setting("is", "guitar is (Fs external link, 7 -> 13)", "s / c4", p.axial_feed / m.c4)
    for s in (ix, iy, iv, is_):
        realise_guitar(s, gs, 2)
    ix.effect = ratio_error_effect(job, ix.relative_error)
    iy.effect = lead_error_effect(job, iy.relative_error) if iy.value else {}
    iv.effect = speed_effect(iv.relative_error, "cutting_speed")
    is_.effect = speed_effect(is_.relative_error, "feed")
    return {s.name: s for s in (ix, iy, iv, is_)}, ("c1", "c2", "c3", "c4", "i_sigma", "t_tv", "n_m")


def sheet_hydraulic_differential(job: Job) -> tuple[dict[str, Setting], tuple[str, ...]]:
    """S2, seed 000 fig. 2: kx on GGI1/GShD1, ky on GGI2/GShD2, iv two-gear guitar, is on GGI3."""
    g, c, m, p = job.gear, job.cutter, job.machine, job.process
    q, nmax = m.hydraulic_steps_per_rev, m.hydraulic_max_windows
    T = g.lead
    kx = Setting(
        "kx",
        "pulse generator GGI1 -> stepping motor GShD1",
        "z0 / (c1 iS z2)",
        c.teeth / (m.c1 * m.i_sigma * g.teeth),
    )
    ky = Setting(
        "ky",
        "pulse generator GGI2 -> stepping motor GShD2",
        "t_TV / (T c2 iS)",
        0.0 if math.isinf(T) else m.lead_screw_pitch / (T * m.c2 * m.i_sigma),
    )
    iv = Setting("iv", "two-gear guitar iv (M -> 7)", "n0 / (c3 n_M)", p.tool_speed / (m.c3 * m.motor_speed))
    is_ = Setting("is", "pulse generator GGI3 -> stepping motor GShD3 (lead screw)", "s / c4", p.axial_feed / m.c4)
    realise_pulse_generator(kx, q, nmax)
    realise_pulse_generator(ky, q, nmax)
    realise_guitar(iv, gear_set_of(job), 1)
    realise_pulse_generator(is_, q, nmax)
    kx.effect = ratio_error_effect(job, kx.relative_error)
    ky.effect = lead_error_effect(job, ky.relative_error) if ky.value else {}
    iv.effect = speed_effect(iv.relative_error, "cutting_speed")
    is_.effect = speed_effect(is_.relative_error, "feed")
    consts = ("c1", "c2", "c3", "c4", "i_sigma", "t_tv", "n_m", "q_step", "n_disc_max")
    return {s.name: s for s in (kx, ky, iv, is_)}, consts


def sheet_hydraulic_shaft(job: Job) -> tuple[dict[str, Setting], tuple[str, ...]]:
    """S3, seed 000 fig. 3: one hydraulic shaft carries B2 + B4; kx = (z2/z0)(1 + s/T) / c1."""
    g, c, m, p = job.gear, job.cutter, job.machine, job.process
    q, nmax = m.hydraulic_steps_per_rev, m.hydraulic_max_windows
    kx = Setting(
        "kx",
        "pulse generator GGI -> stepping motor GShD (work -> tool)",
        "(z2/z0)(1 + s/T) / c1",
        g.teeth / c.teeth * (1 + feed_over_lead(job)) / m.c1,
    )
    iv = Setting("iv", "two-gear guitar iv (M -> 8)", "n0 / (c3 n_M)", p.tool_speed / (m.c3 * m.motor_speed))
    is_ = Setting("is", "guitar is (5 -> 9 -> lead screw)", "s / c4", p.axial_feed / m.c4)
    realise_pulse_generator(kx, q, nmax)
    realise_guitar(iv, gear_set_of(job), 1)
    realise_guitar(is_, gear_set_of(job), 2)
    kx.effect = ratio_error_effect(job, kx.relative_error)
    iv.effect = speed_effect(iv.relative_error, "cutting_speed")
    is_.effect = speed_effect(is_.relative_error, "feed")
    return {s.name: s for s in (kx, iv, is_)}, ("c1", "c3", "c4", "n_m", "q_step", "n_disc_max")


def sheet_mechatronic(job: Job) -> tuple[dict[str, Setting], tuple[str, ...]]:
    """S4, seed 000 fig. 4: dividers 6 (kv), 7 (kx), 21 (ks), 22 (ky) on reference generator 14.

    kv is taken as the multiple nearest 60 f_ref / (p n0) that makes kx = c1 kv z2 / z0 an exact integer,
    so the generating ratio carries no rounding error; ks, ky are rounded (ky is large, so the lead error
    is far below a micrometre).

    A divider (frequency divider = pulse counter + coefficient block) emits one pulse per k input pulses:
    f_out = f_ref / k. Seed 000's ky for S4 is printed as ks t_TV / (c2 T); deriving it from the same calculation
    displacements with this divider law (as kx is) gives ky = c2 ks T / t_TV, which skive uses; with the printed
    form the lead would be wrong by a factor (T/t_TV)^2. c2 of S4 is the ratio (work per M2 revolution / screw per
    M3 revolution) of the two drives.
    """
    g, c, m, p = job.gear, job.cutter, job.machine, job.process
    f, pp = m.reference_frequency, m.command_pulses_per_rev
    factor = Fraction(m.c1).limit_denominator(10**6) * Fraction(g.teeth, c.teeth)  # kx / kv
    kv_ideal = divider_for_rate(f, pp, p.tool_speed)
    kv_int = multiple_near(kv_ideal, factor.denominator)
    kv = Setting(
        "kv",
        "frequency divider 6 (tool spindle speed)",
        "60 f_ref / (p n0)",
        kv_ideal,
        float(kv_int),
        {"integer": kv_int},
    )
    kv.effect = speed_effect(kv_ideal / kv_int - 1, "cutting_speed")  # n ~ 1/k
    kx_ideal = m.c1 * kv_int * g.teeth / c.teeth
    kx_int = round(kx_ideal)
    kx = Setting(
        "kx", "frequency divider 7 (work spindle, B2)", "c1 kv z2 / z0", kx_ideal, float(kx_int), {"integer": kx_int}
    )
    kx.effect = ratio_error_effect(job, kx_ideal / kx_int - 1)
    n0 = 60 * f / (pp * kv_int)
    n_screw = p.axial_feed * n0 * c.teeth / g.teeth / m.lead_screw_pitch  # rpm of the lead screw
    ks_ideal = divider_for_rate(f, pp, n_screw)
    ks_int = max(1, round(ks_ideal))
    ks = Setting(
        "ks",
        "frequency divider 21 (lead screw, feed)",
        "60 f_ref / (p n_TV)",
        ks_ideal,
        float(ks_int),
        {"integer": ks_int},
    )
    ks.effect = speed_effect(ks_ideal / ks_int - 1, "feed")
    if g.helix_angle == 0:
        ky = Setting(
            "ky",
            "frequency divider 22 (work spindle, B4)",
            "c2 ks T / t_TV",
            0.0,
            0.0,
            {"integer": None, "note": "divider 22 off: spur gear, no additional rotation"},
        )
    else:
        ky_ideal = m.c2 * ks_int * abs(g.lead) / m.lead_screw_pitch
        ky_int = round(ky_ideal)
        sign = "-" if feed_over_lead(job) > 0 else "+"  # B4 adds to the work pulses when it speeds the work
        ky = Setting(
            "ky",
            "frequency divider 22 (work spindle, B4)",
            "c2 ks T / t_TV",
            ky_ideal,
            float(ky_int),
            {"integer": ky_int, "summator_9_input": sign},
        )
        ky.effect = lead_error_effect(job, ky_ideal / ky_int - 1)
    return {s.name: s for s in (kv, kx, ks, ky)}, ("c1", "c2", "t_tv", "f_ref", "p_cmd")


SKIVING_SHEETS = {
    "mechanical": sheet_mechanical,
    "hydraulic-differential": sheet_hydraulic_differential,
    "hydraulic-shaft": sheet_hydraulic_shaft,
    "mechatronic": sheet_mechatronic,
}


def skiving_geometry(job: Job) -> tuple[dict[str, Any], list[dict[str, float]], dict[str, float]]:
    g, c, st = job.gear, job.cutter, job.skiving
    geometry = {
        "gear": {
            "z": g.teeth,
            "mn_mm": g.mn,
            "mt_mm": g.transverse_module,
            "alpha_n_deg": math.degrees(g.alpha_n),
            "alpha_t_deg": math.degrees(g.transverse_pressure_angle),
            "beta_deg": math.degrees(g.beta),
            "beta_b_deg": math.degrees(g.base_helix_angle),
            "d_mm": g.reference_diameter,
            "db_mm": g.base_diameter,
            "da_mm": g.tip_diameter_value,
            "df_mm": g.root_diameter_value,
            "lead_mm": g.lead,
            "pt_mm": g.transverse_pitch,
            "pbt_mm": g.transverse_base_pitch,
            "sn_mm": g.normal_tooth_thickness,
            "internal": g.internal,
        },
        "cutter": {
            "z": c.teeth,
            "beta_deg": math.degrees(c.beta),
            "x": c.x,
            "d_mm": c.reference_diameter,
            "db_mm": c.base_diameter,
            "da_mm": st.cutter_tip_diameter,
            "edge": job.cutter_options.edge,
        },
        "shaft_angle_deg": math.degrees(st.shaft_angle),
        "centre_distance_final_mm": st.final_centre_distance,
        "generated_root_diameter_mm": st.generated_root_diameter,
        "speed_ratio_n2_n0": st.speed_ratio,
        "differential_rotation_deg_per_mm": math.degrees(st.differential_rotation_per_mm),
        "work_speed_rpm": st.work_speed,
    }
    passes = [
        {"pass": i + 1, "infeed_mm": inc, "depth_mm": d, "centre_distance_mm": a, "travel_mm": L, "time_s": t}
        for i, (inc, d, a, L, t) in enumerate(
            zip(st.passes, st.pass_depths, st.pass_centre_distances, st.pass_travel, st.pass_times, strict=True)
        )
    ]
    sanity = {
        "cutting_speed_m_min": st.cutting_speed,
        "total_time_s": sum(st.pass_times),
        "depth_short_of_full_mm": st.full_depth - sum(st.passes),
    }
    return geometry, passes, sanity


# ---- thread-cutting group of seed 001 --------------------------------------------------------------
def thread_sheet(job: Job, structure: str) -> SetupSheet:
    """Seed 001: mechanical ix (+ iv), master-slave kx, equal coordinates kv, kx.

    Mechanical ix = P / (i01 t_TV); master-slave kx = P / (i0 P_TV); equal coordinates kv and kx = c kv / P with
    c = i01 P_TV."""
    t, m, p = job.thread, job.machine, job.process
    P = t["lead"]
    n_sp = 1000 * p.cutting_speed / (math.pi * t["diameter"])

    def lead_effect(eps: float) -> dict[str, float]:
        return {"lead_um": eps * P * 1e3, "pitch_um_over_length": eps * t["length"] * 1e3}

    if structure == "mechanical":
        name, settings, consts = "thread-mechanical", _thread_mechanical(job, n_sp, lead_effect), THREAD_CONSTS[0]
    elif m.synchronization == "master-slave":
        name, settings, consts = "thread-master-slave", _thread_master_slave(job, lead_effect), THREAD_CONSTS[1]
    else:
        name, settings = "thread-equal-coordinates", _thread_equal_coordinates(job, n_sp, lead_effect)
        consts = THREAD_CONSTS[2]
    table = {
        "i0": m.i0,
        "i01": m.i01,
        "c3": m.c3,
        "t_tv": m.lead_screw_pitch,
        "n_m": m.motor_speed,
        "f_ref": m.reference_frequency,
        "p_cmd": m.command_pulses_per_rev,
        "n_enc": m.encoder_lines,
    }
    feed = P * n_sp / 60  # mm/s
    passes = [{"pass": i + 1, "infeed_mm": inc, "time_s": t["length"] / feed} for i, inc in enumerate(p.passes)]
    return SetupSheet(
        name,
        "thread",
        settings,
        {k: table[k] for k in consts},
        {"lead_mm": P, "hand": t["hand"], "diameter_mm": t["diameter"], "spindle_speed_rpm": n_sp},
        passes,
        {"cutting_speed_m_min": p.cutting_speed, "total_time_s": len(passes) * t["length"] / feed},
        [],
    )


#: the machine constants each form of the thread group's sheet lists: mechanical, master-slave, equal coordinates
THREAD_CONSTS = (("i01", "c3", "t_tv", "n_m"), ("i0", "t_tv", "p_cmd", "n_enc"), ("i01", "t_tv", "f_ref", "p_cmd"))


def _thread_mechanical(job: Job, n_sp: float, lead_effect) -> dict[str, Setting]:
    """Seed 001 fig. 1: the guitars ix (the lead) and iv (the spindle speed ``n_sp`` [rpm])."""
    m, P, t_tv = job.machine, job.thread["lead"], job.machine.lead_screw_pitch
    ix = realise_guitar(
        Setting("ix", "guitar ix (5 -> R1 -> 6 -> TV)", "P / (i01 t_TV)", P / (m.i01 * t_tv)), gear_set_of(job), 2
    )
    ix.effect = lead_effect(ix.relative_error)
    iv = realise_guitar(
        Setting("iv", "guitar iv (M -> 8 -> R2 -> 5)", "n / (c3 n_M)", n_sp / (m.c3 * m.motor_speed)),
        gear_set_of(job),
        2,
    )
    iv.effect = speed_effect(iv.relative_error, "cutting_speed")
    return {"ix": ix, "iv": iv}


def _thread_master_slave(job: Job, lead_effect) -> dict[str, Setting]:
    """Seed 001 fig. 2: encoder 6 (4 counts per line) -> counter 7 with block 8 -> M2 (p pulses/rev) -> i0 -> TV.
    Block 8 holds two integers: the counter adds N per encoder pulse and emits a pulse per K (a rate multiplier),
    so slave pulses per master pulse = N / K; a plain divide-by-K (N = 1) misses most leads by percent."""
    m, P = job.machine, job.thread["lead"]
    e = 4 * m.encoder_lines
    pp = m.command_pulses_per_rev
    kx_val = P / (m.i0 * m.lead_screw_pitch)
    frac = Fraction(kx_val * pp / e).limit_denominator(65535)
    kx = Setting(
        "kx",
        "frequency divider: counter 7 + coefficient block 8",
        "P / (i0 P_TV)",
        kx_val,
        float(frac) * e / pp,
        {"block_N": frac.numerator, "counter_K": frac.denominator, "encoder_counts_per_rev": e},
    )
    kx.effect = lead_effect(kx.relative_error)
    return {"kx": kx}


def _thread_equal_coordinates(job: Job, n_sp: float, lead_effect) -> dict[str, Setting]:
    """Seed 001 fig. 3: dividers kv (counter 9 + block 11, the spindle at ``n_sp`` [rpm]) and kx (counter 10 +
    block 12, the carriage) on one reference generator."""
    m, P, t_tv = job.machine, job.thread["lead"], job.machine.lead_screw_pitch
    f, pp = m.reference_frequency, m.command_pulses_per_rev
    c_const = Fraction(m.i01 * t_tv / P).limit_denominator(10**6)  # kx / kv
    kv_ideal = divider_for_rate(f, pp, n_sp)
    kv_int = multiple_near(kv_ideal, c_const.denominator)
    kv = Setting(
        "kv",
        "frequency divider: counter 9 + block 11 (spindle)",
        "60 f_ref / (p n)",
        kv_ideal,
        float(kv_int),
        {"integer": kv_int},
    )
    kv.effect = speed_effect(kv_ideal / kv_int - 1, "cutting_speed")
    kx_ideal = m.i01 * t_tv * kv_int / P
    kx = Setting(
        "kx",
        "frequency divider: counter 10 + block 12 (carriage)",
        "c kv / P, c = i01 P_TV",
        kx_ideal,
        float(round(kx_ideal)),
        {"integer": round(kx_ideal)},
    )
    kx.effect = lead_effect(kx_ideal / round(kx_ideal) - 1)
    return {"kv": kv, "kx": kx}


def setup_sheet(job: Job, structure: str | None = None) -> SetupSheet:
    """The setting sheet of ``job`` for ``structure`` (default: the job's [machine] structure)."""
    structure = structure or job.machine.structure
    if job.kind == "thread":
        if structure not in ("mechanical", "mechatronic"):
            raise InputError(
                Problem(
                    "--structure",
                    structure,
                    "the thread group of seed 001 exists as 'mechanical' or 'mechatronic'",
                    "use one of those (with machine.synchronization 'master-slave' or 'equal-coordinates')",
                ),
                job.source,
            )
        return thread_sheet(job, structure)
    if structure not in SKIVING_SHEETS:
        raise InputError(
            Problem("--structure", structure, "not a skiving structure", f"use one of {', '.join(SKIVING_SHEETS)}"),
            job.source,
        )
    job = dataclasses.replace(job, machine=machine_constants(job.machine, structure))
    settings, const_names = SKIVING_SHEETS[structure](job)
    geometry, passes, sanity = skiving_geometry(job)
    notes = []
    if sanity["depth_short_of_full_mm"] > 1e-6:
        notes.append(
            f"the passes stop {sanity['depth_short_of_full_mm']:.3f} mm short of full depth: the teeth come "
            "out thicker than nominal"
        )
    if structure == "mechatronic":
        notes.append("ky follows c2 ks T / t_TV (divider law f_out = f_ref / k); seed 000 prints ks t_TV / (c2 T)")
    return SetupSheet(
        structure, "skiving", settings, _skiving_constants(job, const_names), geometry, passes, sanity, notes
    )
