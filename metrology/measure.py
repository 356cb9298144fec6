"""Measure a gear like a gear measuring machine: profile, helix, pitch, runout, thickness, ISO class.

The measurement probes its workpiece (:mod:`metrology.workpiece`: a mesh, or the exact swept volumes of a cut)
along nominal directions and uses nothing else but the nominal gear data. The result is the fixed JSON schema of
docs/measurement.md (deviations in micrometres, lengths in mm), built by :func:`measure`; ``workpiece`` says what
was measured.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from cutting.flank import SIDES, side_sign, twist_rate
from cutting.gear import Gear, form_roll_length
from cutting.involute import inv, inv_inverse
from cutting.modification import Modification
from metrology import thickness_nominal as nominal
from metrology import tolerances as iso
from metrology.datum import Datum, establish_datum, measuring_radius
from metrology.flank_lines import evaluate_many
from metrology.modification import chart_teeth, crowning, crowning_many, topography, twist
from metrology.probe import ball_seats
from metrology.span import measure_span
from metrology.traces import helix_trace, profile_trace
from metrology.workpiece import Workpiece, as_workpiece, probe_growing, turn

UM = 1e3  # mm -> um


@dataclass(frozen=True)
class MeasureOptions:
    """What the job's [measurement] section may set; None means the standard's default."""

    profile_start_diameter: float | None = None  # start of the evaluation range (active profile start)
    profile_end_diameter: float | None = None  # end of the evaluation range
    sections: tuple[float, ...] = (0.15, 0.50, 0.85)  # transverse sections, fractions of the face
    sector_teeth: int | None = None  # k of F_pk (default z/8)
    span_teeth: int | None = None  # k of W_k (default DIN 3960/21773)
    ball_diameter: float | None = None  # over-balls and runout ball (default DIN 3977)
    profile_points: int = 240
    helix_points: int = 200
    design: Modification | None = None  # the designed flank topography: deviations are evaluated against it
    # the flanks alone: the datum, profiles, helices, pitch and the traces (no runout, thickness, topography nor
    # class: what a fit of the flanks' signatures reads, `skive diagnose`'s study, in half the probing)
    flanks_only: bool = False

    @classmethod
    def from_job(cls, measurement: dict[str, Any] | None, design: Modification | None = None) -> MeasureOptions:
        """The options a job's [measurement] section sets (its None values: the standard's defaults) and its design."""
        return cls(**{k: v for k, v in (measurement or {}).items() if v is not None}, design=design)


def roll_length(gear: Gear, diameter: float) -> float:
    return math.sqrt(max((diameter / 2) ** 2 - gear.base_radius**2, 0.0))


def profile_range(gear: Gear, opt: MeasureOptions) -> tuple[float, float]:
    """Evaluation range (roll lengths [mm], from the root side towards the tip), ISO 1328-1:2013:
    from the start of the active profile to 95 % of the roll length between it and the tip form."""
    start = roll_length(gear, opt.profile_start_diameter) if opt.profile_start_diameter else form_roll_length(gear)
    tip = roll_length(gear, gear.tip_diameter_value)
    end = roll_length(gear, opt.profile_end_diameter) if opt.profile_end_diameter else start + 0.95 * (tip - start)
    return start, end


def helix_range(gear: Gear) -> tuple[float, float]:
    """L_beta = b - 2 min(0.05 b, mn), centred on the face [mm from mid face]."""
    half = (gear.face_width - 2 * min(0.05 * gear.face_width, gear.mn)) / 2
    return -half, half


def _signed_extreme(values: np.ndarray) -> float:
    v = values[np.isfinite(values)]
    return float(v[np.argmax(np.abs(v))]) if v.size else float("nan")


def _flank_block(kind: str, per_section: list[dict[str, np.ndarray]], mid: int, datum: Datum, zs: list[float]) -> dict:
    """Summary + per-tooth entries of profile ("alpha") or helix ("beta") evaluations, in micrometres."""
    F, fH, ff = (f"F_{kind}", f"f_H{kind}", f"f_f{kind}")
    n = len(per_section[0]["F"])
    order = np.argsort(datum.number(np.arange(n)))
    teeth = []
    for k in order:
        entry: dict[str, Any] = {"tooth": int(datum.number(k))}
        vals = [{F: s["F"][k] * UM, fH: s["f_H"][k] * UM, ff: s["f_f"][k] * UM} for s in per_section]
        entry.update(vals[mid])
        if len(vals) > 1:
            entry["worst"] = {
                F: max(v[F] for v in vals),
                fH: max((v[fH] for v in vals), key=abs),
                ff: max(v[ff] for v in vals),
            }
            entry["sections"] = [{"z_mm": z, **v} for z, v in zip(zs, vals, strict=True)]
        teeth.append(entry)
    all_F = np.concatenate([s["F"] for s in per_section]) * UM
    all_fH = np.concatenate([s["f_H"] for s in per_section]) * UM
    all_ff = np.concatenate([s["f_f"] for s in per_section]) * UM
    mid_s = per_section[mid]
    return {
        F: float(np.nanmax(all_F)),
        fH: _signed_extreme(all_fH),
        f"{fH}_mean": float(np.nanmean(mid_s["f_H"]) * UM),
        ff: float(np.nanmax(all_ff)),
        "mid_section": {
            F: float(np.nanmax(mid_s["F"]) * UM),
            fH: _signed_extreme(mid_s["f_H"] * UM),
            ff: float(np.nanmax(mid_s["f_f"]) * UM),
        },
        "teeth": teeth,
    }


def pitch_block(u: np.ndarray, k: int) -> dict[str, Any]:
    """Pitch deviations [um] from flank position deviations u along the circle, in tooth-number order.

    f_pi = u_i - u_(i-1) (actual minus nominal pitch ending at flank i, wrapping to the last flank for
    i = 1); F_pi = u_i - u_1; f_p = max |f_pi|; F_p = max F_pi - min F_pi; F_pk = max over i of the
    sum of k consecutive f_pi.
    """
    f_pi = u - np.roll(u, 1)
    F_pi = u - u[0]
    z = len(u)
    sums = np.array([np.abs(np.sum(np.take(f_pi, range(i, i + k), mode="wrap"))) for i in range(z)])
    return {
        "f_p": float(np.abs(f_pi).max()),
        "F_p": float(F_pi.max() - F_pi.min()),
        "F_pk": float(sums.max()),
        "k": k,
        "f_pi": [float(v) for v in f_pi],
        "F_pi": [float(v) for v in F_pi],
    }


def ball_centre_radius(gear: Gear, diameter: float) -> float:
    """Nominal radius of a ball centre in a space (DIN 3960): inv(a_Kt) = inv(a_t) + sense (D/(z mn cos a_n)
    - pi/(2z) + 2 x tan(a_n)/z), r_K = r_b / cos(a_Kt); sense = -1 flips every 1/z term for internal gears."""
    g = gear
    term = diameter / (g.z * g.mn * math.cos(g.alpha_n)) - math.pi / (2 * g.z) + 2 * g.x * math.tan(g.alpha_n) / g.z
    a_k = inv_inverse(inv(g.transverse_pressure_angle) + g.sense * term)
    return g.base_radius / math.cos(a_k)


def designed(opt: MeasureOptions, gear: Gear, side: str, L, z) -> np.ndarray:
    """The design's deviation [mm] along a trace (0 without a design): what the measured trace is compared to."""
    if opt.design is None:
        return np.zeros(np.broadcast_shapes(np.shape(L), np.shape(z)))
    return opt.design.deviation(gear, side, L, z)


def crowning_block(kind: str, x: np.ndarray, e: np.ndarray, design: np.ndarray) -> dict[str, float]:
    """Measured crowning C_alpha / C_beta [um] of the traces against the involute (the mean over the teeth) and
    the design's own crowning over the same range."""
    c = crowning_many(x, e) * UM
    return {
        f"C_{kind}": float(np.nanmean(c)),
        f"C_{kind}_min": float(np.nanmin(c)),
        f"C_{kind}_max": float(np.nanmax(c)),
        f"C_{kind}_design": crowning(x, np.broadcast_to(design, x.shape).astype(float)) * UM,
    }


def topography_block(
    wp: Workpiece, gear: Gear, datum: Datum, opt: MeasureOptions, roll: tuple[float, float], face: tuple[float, float]
) -> dict[str, Any]:
    """The flank topography [um] over the evaluation ranges, on the charted teeth: per flank the mean of those
    teeth, the design's, and their difference (grids roll length x face)."""
    numbers = chart_teeth(gear.teeth)
    index = {int(datum.number(k)): k for k in range(gear.teeth)}
    topo = topography(wp, gear, datum, roll, face, [index[n] for n in numbers])
    L, z = topo["L_mm"], topo["z_mm"]
    out: dict[str, Any] = {"L_mm": [float(v) for v in L], "z_mm": [float(v) for v in z], "teeth": numbers}
    for side in SIDES:
        e = np.asarray(topo[side]) * UM
        mean = np.nanmean(e, axis=0)
        design = designed(opt, gear, side, L[:, None], z[None, :]) * UM
        out[side] = {
            "deviation_um": mean.tolist(),
            "design_um": design.tolist(),
            "against_design_um": (mean - design).tolist(),
            "per_tooth_um": e.tolist(),
            "twist_um": twist(L, z, mean, gear.face_width),
            "twist_design_um": twist(L, z, np.broadcast_to(design, mean.shape), gear.face_width),
        }
    return out


def measure_gear(workpiece, gear: Gear, opt: MeasureOptions | None = None, name: str | None = None) -> dict[str, Any]:
    """Measure ``workpiece`` (a :class:`metrology.workpiece.Workpiece`, or a mesh) as the gear ``gear``; returns
    the measurement's JSON document (docs/measurement.md)."""
    opt = opt or MeasureOptions()
    wp = as_workpiece(workpiece, name)
    datum = establish_datum(wp, gear, name)
    roll, face = profile_range(gear, opt), helix_range(gear)
    L, zs, profile, profile_traces = _measure_profile(wp, gear, datum, opt, roll)
    zz, helix, helix_traces = _measure_helix(wp, gear, datum, opt, face)
    r_p = measuring_radius(gear)  # pitch on a circle near mid depth, mid section
    order = np.argsort(datum.number(np.arange(gear.teeth)))
    k_sector = opt.sector_teeth or iso.default_sector_pitches(gear.teeth)
    result: dict[str, Any] = {
        "evaluation": {
            "profile_roll_mm": list(roll),
            "profile_section_z_mm": zs,
            "helix_z_mm": list(face),
            "pitch_diameter_mm": 2 * r_p,
            # where the measured gear sits (a gear measuring machine's alignment): its turn from the nominal gear,
            # its mid face and the nominal index of the tooth reported as tooth 1; the deviation maps are placed by it
            "datum": {
                "rotation_deg": math.degrees(datum.rotation),
                "z_mid_mm": float(datum.z_mid),
                "tooth_1_index": int(datum.first_tooth),
            },
        },
        "profile": profile,
        "helix": helix,
        "pitch": _measure_pitch(wp, gear, datum, r_p, order, k_sector),
    }
    if not opt.flanks_only:
        result["runout"], over_balls = _measure_over_balls(wp, gear, datum, opt, order)
        result["thickness"] = _thickness_block(wp, gear, datum, opt, over_balls, face)
        result["topography"] = topography_block(wp, gear, datum, opt, roll, face)
        result["iso1328"] = iso1328_block(gear, result, k_sector)
    result["workpiece"] = {"kind": wp.kind, "name": wp.name}
    result["gear"] = {
        "teeth": gear.teeth,
        "normal_module_mm": gear.mn,
        "helix_angle_deg": math.degrees(gear.beta),
        "face_width_mm": gear.face_width,
        "internal": gear.internal,
        "datum_rotation_deg": math.degrees(datum.rotation),
    }
    result["_traces"] = {"L_mm": L, "z_mm": zz, "profile": profile_traces, "helix": helix_traces, "order": order}
    mid = int(np.argmin(np.abs(np.array(opt.sections) - 0.5)))  # the section the profile traces are kept of
    result["traces"] = traces_block(L, zs[mid], zz, gear.reference_diameter, profile_traces, helix_traces, order)
    return result


#: the most points of a trace measurement.json keeps (every trace's own points, evenly picked from the probe's)
TRACE_POINTS = 61


def traces_block(L, z_profile, zz, d_helix, profile, helix, order) -> dict[str, Any]:
    """The measured traces as measurement.json keeps them (what `skive diagnose` reads; docs/diagnose.md): the mid
    section's profiles over roll length and the helices over the face on the reference cylinder, each flank's per
    tooth in tooth-number order, the deviation from the designed flank along its normal [um] (+: material), at no
    more than :data:`TRACE_POINTS` of the probe's points (picked evenly)."""

    def picked(x: np.ndarray) -> np.ndarray:
        return np.unique(np.round(np.linspace(0, len(x) - 1, min(TRACE_POINTS, len(x)))).astype(int))

    def rows(t: np.ndarray, keep: np.ndarray) -> list[list[float | None]]:
        t = np.asarray(t)[np.asarray(order)][:, keep] * UM
        return [[round(float(v), 4) if np.isfinite(v) else None for v in row] for row in t]

    kp, kh = picked(L), picked(zz)
    return {
        "profile": {"z_mm": float(z_profile), "L_mm": [float(v) for v in L[kp]],
                    **{side: rows(profile[side], kp) for side in SIDES}},
        "helix": {"diameter_mm": float(d_helix), "z_mm": [float(v) for v in zz[kh]],
                  **{side: rows(helix[side], kh) for side in SIDES}},
    }  # fmt: skip


def measure_helix(workpiece, gear: Gear, opt: MeasureOptions | None = None, name: str | None = None) -> dict[str, Any]:
    """The helix part of :func:`measure_gear` alone (its datum, range, traces and helix block, the same figures): what
    an iteration that reads only the flanks' lead needs (the modification path's trial cuts: a tenth of the time)."""
    opt = opt or MeasureOptions()
    wp = as_workpiece(workpiece, name)
    datum = establish_datum(wp, gear, name)
    face = helix_range(gear)
    zz, helix, helix_traces = _measure_helix(wp, gear, datum, opt, face)
    return {"evaluation": {"helix_z_mm": list(face)}, "helix": helix, "_traces": {"z_mm": zz, "helix": helix_traces}}


def _measure_profile(
    wp: Workpiece, gear: Gear, datum: Datum, opt: MeasureOptions, roll: tuple[float, float]
) -> tuple[np.ndarray, list[float], dict[str, Any], dict[str, np.ndarray]]:
    """Profiles over the roll lengths ``roll`` in the transverse sections: (roll lengths, the sections' z [mm], the
    profile block per flank with its crowning, the mid section's traces against the design)."""
    L = np.linspace(*roll, opt.profile_points)
    radii = np.sqrt(gear.base_radius**2 + L**2)
    zs = [float((f - 0.5) * datum.face_width) for f in opt.sections]
    mid = int(np.argmin(np.abs(np.array(opt.sections) - 0.5)))
    prof: dict[str, list[dict[str, np.ndarray]]] = {side: [] for side in SIDES}
    traces: dict[str, np.ndarray] = {}
    crown: dict[str, dict[str, float]] = {}
    for j, zz in enumerate(zs):
        tr = profile_trace(wp, gear, datum, zz, radii)
        for side in SIDES:
            design = designed(opt, gear, side, L, zz)
            prof[side].append(evaluate_many(L, tr[side] - design))
            if j == mid:  # the mid section's traces: charts and the profile crowning
                traces[side] = tr[side] - design
                crown[side] = crowning_block("alpha", L, tr[side], design)
    block = {side: {**_flank_block("alpha", prof[side], mid, datum, zs), **crown[side]} for side in SIDES}
    return L, zs, block, traces


def _measure_helix(
    wp: Workpiece, gear: Gear, datum: Datum, opt: MeasureOptions, face: tuple[float, float]
) -> tuple[np.ndarray, dict[str, Any], dict[str, np.ndarray]]:
    """Helices on the reference cylinder over ``face`` (mm from mid face): (their z, the helix block per flank with
    its crowning, the traces against the design)."""
    zz = np.linspace(*face, opt.helix_points)
    ht = helix_trace(wp, gear, datum, gear.reference_radius, zz)
    l_ref = math.sqrt(gear.reference_radius**2 - gear.base_radius**2)
    hd = {side: designed(opt, gear, side, l_ref, zz) for side in SIDES}
    traces = {side: ht[side] - hd[side] for side in SIDES}
    block = {
        side: {
            **_flank_block("beta", [evaluate_many(zz, ht[side] - hd[side])], 0, datum, [0.0]),
            **crowning_block("beta", zz, ht[side], hd[side]),
        }
        for side in SIDES
    }
    for side in SIDES:  # one helix trace per flank: no sections
        for t in block[side]["teeth"]:
            t.pop("worst", None)
            t.pop("sections", None)
    return zz, block, traces


def _measure_pitch(
    wp: Workpiece, gear: Gear, datum: Datum, r_p: float, order: np.ndarray, k: int
) -> dict[str, dict[str, Any]]:
    """Pitch deviations per flank from the flank positions on the circle of radius ``r_p`` in the mid section."""
    pitch = {}
    at_circle = profile_trace(wp, gear, datum, 0.0, np.array([r_p]))
    for side in SIDES:
        e = at_circle[side][:, 0]
        u = r_p * e / (side_sign(gear, side) * gear.base_radius) * UM  # arc on the circle, counter-clockwise
        pitch[side] = pitch_block(u[order], k)
    return pitch


def _measure_over_balls(
    wp: Workpiece, gear: Gear, datum: Datum, opt: MeasureOptions, order: np.ndarray
) -> tuple[dict[str, Any], dict[str, Any]]:
    """Runout and dimension over balls with the same ball seated in every space: (runout block, over-balls block)."""
    D = opt.ball_diameter or nominal.ball_diameter(gear)
    centres = ball_seats(wp, gear, datum, D, ball_centre_radius(gear, D))
    rho = np.hypot(centres[:, 0], centres[:, 1])
    runout = {
        "F_r": float((rho.max() - rho.min()) * UM),
        "ball_diameter_mm": D,
        "ball_centre_radius_mm": [float(v) for v in rho[order]],
    }
    z = gear.teeth
    half = z // 2 if z % 2 == 0 else (z - 1) // 2
    chords = np.linalg.norm(centres - np.roll(centres, -half, axis=0), axis=1)
    m_dk = chords + (D if not gear.internal else -D)
    over_balls = {
        "ball_diameter_mm": D,
        "M_dK_mm": float(m_dk.mean()),
        "M_dK_min_mm": float(m_dk.min()),
        "M_dK_max_mm": float(m_dk.max()),
        "M_dK_nominal_mm": float(nominal.over_balls(gear, D)),
    }
    return runout, over_balls


def _thickness_block(
    wp: Workpiece,
    gear: Gear,
    datum: Datum,
    opt: MeasureOptions,
    over_balls: dict[str, Any],
    face: tuple[float, float],
) -> dict[str, Any]:
    """Tooth thickness (over balls, span at the end of the helix range ``face``) and tip and root diameters."""
    thickness: dict[str, Any] = {"over_balls": over_balls}
    if gear.internal:
        thickness["span"] = {
            "k": None,
            "W_k_mm": None,
            "W_k_nominal_mm": None,
            "note": "span measurement is not possible on an internal gear",
        }
    else:
        k_span = opt.span_teeth or nominal.span_teeth(gear)
        w = measure_span(wp, gear, datum, k_span, face[1])
        thickness["span"] = {
            "k": k_span,
            "W_k_mm": float(np.nanmean(w)),
            "W_k_min_mm": float(np.nanmin(w)),
            "W_k_max_mm": float(np.nanmax(w)),
            "W_k_nominal_mm": float(nominal.span(gear, k_span)),
        }
    thickness["tip_diameter_mm"], thickness["root_diameter_mm"] = _tip_root(wp, gear, datum)
    thickness["tip_diameter_nominal_mm"] = gear.tip_diameter_value
    thickness["root_diameter_nominal_mm"] = gear.root_diameter_value
    return thickness


def _tip_root(wp: Workpiece, gear: Gear, datum: Datum) -> tuple[float, float]:
    """Measured tip and root diameters: probed radially on every tooth's centre line (tip) and every space's (root)
    in the profile sections; the median of each."""
    pitch = 2 * math.pi / gear.teeth
    k = np.arange(gear.teeth)[:, None]
    zs = np.array([-0.35, 0.0, 0.35]) * gear.face_width
    tw = twist_rate(gear) * zs[None, :]
    out = []
    for radius, offset in ((gear.tip_radius, 0.0), (gear.root_radius, 0.5)):
        a = (k + offset) * pitch + tw + 0 * zs
        radial = np.stack([np.cos(a), np.sin(a), np.zeros_like(a)], -1)
        # air lies outside the tip and above the root of an external gear, inside both on an internal one
        up = -radial if gear.internal else radial
        p = turn(
            radius * radial + np.array([0.0, 0.0, 1.0]) * (zs[None, :, None] + 0 * a[..., None]),
            datum.rotation,
            datum.z_mid,
        )
        d = probe_growing(wp, p, turn(up, datum.rotation), (0.02, 0.1, 0.25 * gear.mn, 0.5 * gear.mn))
        r = radius + d * (-1 if gear.internal else 1)
        out.append(2 * float(np.nanmedian(r)) if np.isfinite(r).any() else float("nan"))
    return out[0], out[1]


def iso1328_block(gear: Gear, result: dict[str, Any], k: int) -> dict[str, Any]:
    """Tolerances and classes per ISO 1328-1:2013; a gear outside the standard's range says so."""
    beta = math.degrees(gear.beta)
    worst = {
        "f_p": max(result["pitch"][s]["f_p"] for s in SIDES),
        "F_p": max(result["pitch"][s]["F_p"] for s in SIDES),
        "F_alpha": max(result["profile"][s]["F_alpha"] for s in SIDES),
        "f_Halpha": max((result["profile"][s]["f_Halpha"] for s in SIDES), key=abs),
        "f_falpha": max(result["profile"][s]["f_falpha"] for s in SIDES),
        "F_beta": max(result["helix"][s]["F_beta"] for s in SIDES),
        "f_Hbeta": max((result["helix"][s]["f_Hbeta"] for s in SIDES), key=abs),
        "f_fbeta": max(result["helix"][s]["f_fbeta"] for s in SIDES),
        "F_r": result["runout"]["F_r"],
    }
    try:
        classes = iso.overall_class(worst, gear.teeth, gear.mn, gear.face_width, beta, k)
    except ValueError as exc:
        return {"standard": iso.STANDARD, "error": str(exc), "tolerances": None, "class": None, "measured": worst}
    a = classes["overall"]
    tol = iso.tolerances(a if a is not None else 11, gear.teeth, gear.mn, gear.face_width, beta, k)
    return {
        "standard": iso.STANDARD,
        "tolerances_class": a if a is not None else 11,
        "tolerances": tol,
        "class": classes,
        "measured": worst,
    }


#: the name the tests and scripts use
measure = measure_gear
