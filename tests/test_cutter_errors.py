"""The cutter's deviations and the blank's clamping, cut on the ideal machine and measured on the exact swept surface
against their first-order signatures (docs/cutter.md, "What each deviation does to the gear").

Known answers, for a spur gear z2 = 20, mn = 1, cut by a z0 = 17, beta0 = 20 deg cutter:
- clamping eccentricity e: F_r = 2e; the cumulative pitch a once-per-turn sinusoid of amplitude e / cos(alpha_y)
  on the measuring circle; every tooth's profile slope changes by e * (its evaluation range in roll angle) as a
  sinusoid round the gear, whose mean stays;
- clamping tilt tau: every tooth's helix slope changes by tau * L_beta as a sinusoid round the gear;
- a cutter tooth displaced by f along its pitch circle: the bands of the face it generates move by
  f cos(alpha_n) cos(beta0) normal to the flank, into the material on the flank it leads with;
- a cutter centre e_c off the spindle axis: tooth k moves by e_c in a direction fixed on the cutter, so the bands
  it generates move by e_c cos(beta_b0) cos(theta_k - psi + const) normal to the flank: the deepest and highest
  bands are +-e_c cos(beta_b0).
The measurement's datum (the mean tooth position) takes up a constant share of a one-sided change: bands are
measured from the median of the change along each trace.
"""

from __future__ import annotations

import functools
import math
from dataclasses import replace

import numpy as np
import pytest

from cutting.gear import Gear
from cutting.skiving.edge import make_edge
from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.kinematics import SkivingSetup
from cutting.skiving.tooling import Clamping, CutterErrors
from cutting.skiving.trajectory import ideal_passes
from metrology.datum import establish_datum
from metrology.measure import MeasureOptions, helix_range, measure_gear
from metrology.traces import helix_trace

DEG = math.pi / 180
UM = 1e3


def setup_at(feed: float) -> SkivingSetup:
    """The default job's gear and cutter in one full-depth pass at ``feed`` mm per work revolution."""
    return SkivingSetup(Gear(20, 1.0, 20 * DEG, 0.0, 4.0), Gear(17, 1.0, 20 * DEG, 20 * DEG, 10.0), 3000, feed, (2.25,))


#: fine feed marks (F_r 0.3 um) for the once-per-turn signatures; the default feed for the cutter's bands
FINE, COARSE = setup_at(0.05), setup_at(0.2)
#: a test that reads the mid section's profile, the helix, the pitch and the runout alone has the profile measured in
#: that section alone (the same figures, a quarter less probing); F_alpha and f_falpha are the worst of three sections
MID = MeasureOptions(sections=(0.5,))


@functools.cache
def workpiece(st: SkivingSetup) -> SweptVolumes:
    return SweptVolumes(st.gear, make_edge(st, "conjugate"), ideal_passes(st))


@functools.cache
def measured(st: SkivingSetup, opt: MeasureOptions | None = None) -> dict:
    return measure_gear(workpiece(st), st.gear, opt or MeasureOptions())


@functools.cache
def helix_traces(st: SkivingSetup) -> dict[str, np.ndarray]:
    """Every tooth's helix trace per flank [mm] (teeth, points): the measurement's own (measure_gear's ``_traces``,
    the same datum, range and points) without the rest of the measurement, which the band tests do not read."""
    g, wp = st.gear, workpiece(st)
    z = np.linspace(*helix_range(g), MeasureOptions().helix_points)
    return helix_trace(wp, g, establish_datum(wp, g), g.reference_radius, z)


def sinusoid(values: np.ndarray) -> tuple[float, float]:
    """Amplitude of the once-per-turn sinusoid fitted to one value per tooth, and the largest residual."""
    z = len(values)
    th = 2 * np.pi * np.arange(z) / z
    a = np.stack([np.cos(th), np.sin(th), np.ones(z)], 1)
    c = np.linalg.lstsq(a, values, rcond=None)[0]
    return float(np.hypot(c[0], c[1])), float(np.abs(values - a @ c).max())


def per_tooth(doc: dict, block: str, side: str, name: str) -> np.ndarray:
    return np.array([t[name] for t in doc[block][side]["teeth"]])


def band_change(base: dict, other: dict, side: str) -> np.ndarray:
    """The change of every helix trace point [um], from the median change of its trace (the datum's share)."""
    d = (np.array(other[side]) - np.array(base[side])) * UM
    assert np.isfinite(d).mean() > 0.95
    return d - np.nanmedian(d, axis=1, keepdims=True)


def test_eccentricity_gives_twice_its_runout_and_a_sinusoidal_pitch():
    e = 0.008
    base, ecc = measured(FINE), measured(replace(FINE, clamping=Clamping(e, 40 * DEG)), MID)
    assert base["runout"]["F_r"] < 0.5  # the ideal cut's feed marks alone
    assert ecc["runout"]["F_r"] == pytest.approx(2 * e * UM, rel=0.05)
    g = FINE.gear
    r_p = ecc["evaluation"]["pitch_diameter_mm"] / 2
    alpha_y = math.acos(g.base_radius / r_p)
    for side in ("left", "right"):
        amplitude, residual = sinusoid(np.array(ecc["pitch"][side]["F_pi"]) - np.array(base["pitch"][side]["F_pi"]))
        assert amplitude == pytest.approx(e * UM / math.cos(alpha_y), rel=0.05)
        assert residual < 0.3
        # each tooth's profile slope turns with it; their mean and the helix slopes stay
        lo, hi = ecc["evaluation"]["profile_roll_mm"]
        slope = per_tooth(ecc, "profile", side, "f_Halpha") - per_tooth(base, "profile", side, "f_Halpha")
        assert sinusoid(slope)[0] == pytest.approx(e * UM * (hi - lo) / g.base_radius, rel=0.10)
        assert abs(ecc["profile"][side]["f_Halpha_mean"] - base["profile"][side]["f_Halpha_mean"]) < 0.3
        assert abs(ecc["helix"][side]["f_Hbeta_mean"] - base["helix"][side]["f_Hbeta_mean"]) < 0.3


def test_tilt_turns_the_helix_slope_round_the_gear():
    tilt = 0.02  # axial runout at the reference diameter: tau = tilt / d
    base, tilted = measured(FINE), measured(replace(FINE, clamping=Clamping(tilt=tilt, tilt_phase=30 * DEG)), MID)
    lo, hi = tilted["evaluation"]["helix_z_mm"]
    expected = tilt / FINE.gear.reference_diameter * (hi - lo) * UM
    for side in ("left", "right"):
        change = per_tooth(tilted, "helix", side, "f_Hbeta") - per_tooth(base, "helix", side, "f_Hbeta")
        amplitude, residual = sinusoid(change)
        assert amplitude == pytest.approx(expected, rel=0.10)
        assert residual < 0.1 * expected
        assert abs(tilted["helix"][side]["f_Hbeta_mean"] - base["helix"][side]["f_Hbeta_mean"]) < 0.3
    assert tilted["runout"]["F_r"] < 1.0  # a tilt about mid face leaves the mid section where it was


def test_one_cutter_tooth_ahead_cuts_its_bands_deeper_on_its_leading_flank():
    f = 0.005
    pitch = [0.0] * 17
    pitch[5], pitch[6] = f, -f  # tooth 5 alone stands f ahead along +phi of the cutter
    base, errored = helix_traces(COARSE), helix_traces(replace(COARSE, cutter_errors=CutterErrors(pitch=tuple(pitch))))
    depth = f * math.cos(COARSE.cutter.alpha_n) * math.cos(COARSE.cutter.helix_angle) * UM
    # the cutter's left flank faces +phi and generates the gear's left flank (cutting.skiving.edge.mate_flank)
    left, right = band_change(base, errored, "left"), band_change(base, errored, "right")
    assert -np.nanmin(left, axis=1) == pytest.approx(np.full(20, depth), rel=0.15)  # every space meets tooth 5
    assert np.nanmax(right, axis=1) == pytest.approx(np.full(20, depth), rel=0.15)  # material it left
    assert np.nanmax(left) < 0.3 and np.nanmin(right) > -0.3  # no other tooth moved
    # the bands where tooth 5 finished are where the kinematics put it: one band of one feed per meeting
    banded = (left < -depth / 2).mean(axis=1)
    z_lo, z_hi = helix_range(COARSE.gear)
    bands = banded * (z_hi - z_lo) / COARSE.axial_feed
    assert np.all((bands > 0.5) & (bands < 2.6))  # 17 revolutions (3.4 mm of feed) between two meetings


def test_cutter_radial_runout_moves_every_band_by_its_tooths_offset():
    e_c = 0.005
    errors = CutterErrors(radial_runout=2 * e_c, radial_runout_phase=0.3)
    base, errored = helix_traces(COARSE), helix_traces(replace(COARSE, cutter_errors=errors))
    c = COARSE.cutter
    beta_b0 = math.asin(math.sin(c.helix_angle) * math.cos(c.alpha_n))
    expected = e_c * math.cos(beta_b0) * UM
    for side in ("left", "right"):
        d = (np.array(errored[side]) - np.array(base[side])) * UM
        assert np.nanmax(d) == pytest.approx(expected, rel=0.15)  # the tooth the offset pushes into the space
        assert -np.nanmin(d) == pytest.approx(expected, rel=0.15)  # and the one it pulls back


def _job(**sections) -> dict:
    import tomllib

    from checks import JOBS

    data = tomllib.loads((JOBS / "default.toml").read_text())
    for name, table in sections.items():
        if name == "errors":
            data["cutter"]["errors"] = table
        else:
            data[name] = table
    return data


def test_deviations_are_job_keys_and_bad_ones_are_refused_with_what_to_change():
    from cutting.errors import InputError
    from virtual_machine.job import parse_job

    job = parse_job(
        _job(errors={"radial_runout": 0.006, "radial_runout_phase": 90.0}, workpiece={"eccentricity": 0.004})
    )
    st = job.skiving
    assert st.cutter_errors.radial_runout == 0.006
    assert st.cutter_errors.radial_runout_phase == pytest.approx(math.pi / 2)
    assert st.clamping.eccentricity == 0.004
    from virtual_machine.studies.spec import base_value, set_key

    for key in ("cutter.errors.radial_runout", "workpiece.tilt", "cutter.rake_face_offset", "cutter.rake_angle"):
        assert base_value(_job(), key) == 0.0  # study keys
        assert parse_job(set_key(_job(), key, 0.004)).skiving != parse_job(_job()).skiving
    assert parse_job(set_key(_job(), "cutter.rake_angle", 5.0)).skiving.rake.rake_angle == pytest.approx(5 * DEG)
    with pytest.raises(InputError, match=r"cutter\.rake_angle.*from -20 to 20"):
        parse_job(set_key(_job(), "cutter.rake_angle", 25.0))
    profiled = parse_job(_job(errors={"profile_slope_left": 0.004, "profile_form_right": -0.002})).skiving
    assert profiled.cutter_errors.profile_slope == (0.004, 0.0) and profiled.cutter_errors.profile_form == (0.0, -0.002)
    listed = parse_job(_job(errors={"profile_slope_left": [0.001 * (k % 3) for k in range(17)]})).skiving
    assert listed.cutter_errors.profile_per_tooth and len(listed.cutter_errors.profile_slope[0]) == 17
    assert listed.cutter_errors.tooth_profile(2)[0] == (0.002, 0.0)
    alike = parse_job(_job(errors={"profile_form_right": [0.002] * 17})).skiving.cutter_errors  # one value after all
    assert alike.profile_form == (0.0, 0.002) and not alike.profile_per_tooth
    random = parse_job(_job(errors={"pitch_tolerance": 0.004, "seed": 7})).skiving.cutter_errors.pitch
    assert len(random) == 17 and abs(sum(random)) < 1e-12 and max(map(abs, random)) <= 0.004 + 1e-12
    for bad, key, says in [
        ({"errors": {"pitch": [0.001] * 17}}, "cutter.errors.pitch", "subtract their mean"),
        ({"errors": {"pitch": [0.0] * 5}}, "cutter.errors.pitch", "17 numbers"),
        ({"errors": {"radial_runout": 8.0}}, "cutter.errors.radial_runout", "8 um is 0.008"),
        ({"errors": {"profile_slope_left": -5.0}}, "cutter.errors.profile_slope_left", "8 um is 0.008"),
        ({"errors": {"profile_form_right": [0.001] * 5}}, "cutter.errors.profile_form_right", "17 numbers"),
        ({"errors": {"profile_form_left": [0.004] * 16 + [8.0]}}, "cutter.errors.profile_form_left", "8 um is 0.008"),
        ({"errors": {"profile_slope_right": "0.004"}}, "cutter.errors.profile_slope_right", "a number or a list"),
        ({"errors": {"radial_runot": 0.01}}, "cutter.errors.radial_runot", "did you mean 'radial_runout'"),
        ({"workpiece": {"eccentricity": -0.01}}, "workpiece.eccentricity", ">= 0"),
        ({"errors": {"pitch": [0.0] * 17, "pitch_tolerance": 0.01}}, "cutter.errors.pitch", "one of the two"),
    ]:
        with pytest.raises(InputError) as info:
            parse_job(_job(**bad))
        text = str(info.value)
        assert key in text and says in text, text


@pytest.mark.parametrize("slope, form", [((0.005, -0.005), (0.0, 0.0)), ((0.0, 0.0), (0.005, 0.005))])
def test_a_cutter_profile_deviation_maps_through_the_generating_onto_the_gear(slope, form):
    """The cutter's profile deviation e(u) (u along its active flank by roll length, docs/cutter.md) moves the gear's
    flank where the envelope says each edge radius generates it: by -e cos(beta_b0) along the normal (a spur gear's
    transverse deviation). Predicted over the gear's evaluation range from the roll map (gear roll -> cutter roll),
    against the exact measurement of the cut: f_Halpha within 10 %, f_falpha within 10 % plus the feed marks."""
    from cutting.skiving.cutter_profile import active_flank, roll_map

    base = measured(FINE)  # f_falpha: the worst of the three sections (the form's case reads it)
    errored = measured(
        replace(FINE, cutter_errors=CutterErrors(profile_slope=slope, profile_form=form)), None if any(form) else MID
    )
    c = FINE.cutter
    cos_bb0 = math.cos(math.asin(math.sin(c.helix_angle) * math.cos(c.alpha_n)))
    lo, hi = errored["evaluation"]["profile_roll_mm"]
    edge = make_edge(FINE, "conjugate")
    for k, side in enumerate(("left", "right")):
        l2, l0 = roll_map(FINE, edge, side)
        at_tip, at_form = active_flank(FINE, edge, side)
        roll = np.linspace(lo, hi, 200)
        u = (np.interp(roll, l2, l0) - (at_tip + at_form) / 2) / (at_form - at_tip)
        gear = -(slope[k] * u + form[k] * (4 * u**2 - 1 / 3)) * cos_bb0 * UM
        line = np.polyfit(roll, gear, 1)
        f_h, f_f = line[0] * (hi - lo), np.ptp(gear - np.polyval(line, roll))
        change = errored["profile"][side]["f_Halpha_mean"] - base["profile"][side]["f_Halpha_mean"]
        assert change == pytest.approx(f_h, rel=0.10)
        if form[k]:
            assert abs(errored["profile"][side]["f_falpha"] - f_f) <= 0.1 * f_f + base["profile"][side]["f_falpha"]


def test_each_cutter_tooth_cuts_with_its_own_profile():
    """Tooth 5 alone carries a 5 um profile slope on its left flank (a list of one per tooth): the gear's left
    flanks change only where tooth 5 finished them, its bands (found on a cut where tooth 5 alone stands ahead,
    as in the pitch test above), and there by the slope the generating maps onto the gear (the uniform slope's
    first-order prediction, above): a fit of the change to that prediction within 10 %, the median change at each
    roll length within 15 % of it, elsewhere no change (0.3 um), the right flanks unchanged. Deviations on a grid
    of roll lengths x face positions on every tooth, probed on the exact swept surface from one datum (the base
    cut's: the change is absolute)."""
    from cutting.skiving.cutter_profile import active_flank, roll_map
    from metrology.measure import profile_range
    from metrology.workpiece import flank_deviation

    f_h, z0 = 0.005, COARSE.cutter.teeth
    slope = tuple(f_h if k == 5 else 0.0 for k in range(z0))
    pitch = [0.0] * z0
    pitch[5], pitch[6] = 0.005, -0.005
    cuts = [COARSE, replace(COARSE, cutter_errors=CutterErrors(pitch=tuple(pitch)))]
    cuts.append(replace(COARSE, cutter_errors=CutterErrors(profile_slope=(slope, 0.0))))
    g = COARSE.gear
    datum = establish_datum(workpiece(COARSE), g)
    lo, hi = profile_range(g, MeasureOptions())
    roll = np.linspace(lo, hi, 9)
    z = np.linspace(*helix_range(g), 61)
    grid = (roll[None, :, None] / g.base_radius, z[None, None, :], np.arange(g.teeth)[:, None, None])

    def deviations(st: SkivingSetup, side: str) -> np.ndarray:
        return flank_deviation(workpiece(st), g, datum, side, *grid) * UM

    base, ahead, profiled = (deviations(st, "left") for st in cuts)
    depth = 0.005 * math.cos(COARSE.cutter.alpha_n) * math.cos(COARSE.cutter.helix_angle) * UM
    bands, clear = ahead - base < -0.8 * depth, ahead - base > -0.2 * depth  # borders between bands left out
    assert 0.03 < bands.mean() < 0.25 and bands.any(axis=(1, 2)).all()  # one band in 17 revolutions, every space
    c = COARSE.cutter
    cos_bb0 = math.cos(math.asin(math.sin(c.helix_angle) * math.cos(c.alpha_n)))
    edge = make_edge(COARSE, "conjugate")
    l2, l0 = roll_map(COARSE, edge, "left")
    at_tip, at_form = active_flank(COARSE, edge, "left")
    u = (np.interp(roll, l2, l0) - (at_tip + at_form) / 2) / (at_form - at_tip)
    expected = np.broadcast_to((-f_h * u * cos_bb0 * UM)[None, :, None], base.shape)
    change = profiled - base
    ok = bands & np.isfinite(change)
    gain = float(np.sum(change[ok] * expected[ok]) / np.sum(expected[ok] ** 2))
    assert gain == pytest.approx(1.0, abs=0.10)  # measured 0.953
    assert np.median(np.abs(change[ok] - expected[ok])) < 0.2  # measured 0.10 um (the bands' borders move a little)
    for i in np.flatnonzero(np.abs(expected[0, :, 0]) > 0.5):  # the roll map's line, roll by roll (worst 9 %)
        assert np.median(change[:, i][ok[:, i]]) == pytest.approx(expected[0, i, 0], rel=0.15)
    assert np.nanpercentile(np.abs(change[clear]), 99) < 0.3  # measured 0: the other teeth's surfaces as they were
    right = [deviations(st, "right") for st in (cuts[0], cuts[2])]
    assert np.nanmax(np.abs(right[1] - right[0])) < 0.3


def test_the_tooth_ahead_takes_more_of_the_chip_and_the_next_one_in_its_space_less():
    """The load on every cutter tooth from the chips of the cut (cutting/skiving/tool_load.py): on the ideal cutter
    all teeth take the same largest chip; with tooth 5 standing 5 um ahead, the finishing pass's chip energy grows
    most on tooth 5 and falls most on the tooth that visits its space next, one work revolution later:
    (5 - z2) mod z0 = 2 (passage m + z2, tooth (-m - z2) mod z0)."""
    from cutting.materials import material
    from cutting.skiving.ideal_cut import cut_ideal
    from cutting.skiving.tool_load import tool_load

    pitch = [0.0] * 17
    pitch[5], pitch[6] = 0.005, -0.005
    loads = []
    for errors in (CutterErrors(), CutterErrors(pitch=tuple(pitch))):
        st = replace(COARSE, passes=(1.75, 0.5), cutter_errors=errors)
        loads.append(tool_load(cut_ideal(st, "conjugate", 0.01, 0.02).result.chips, st, material("16MnCr5")))
    base, errored = loads
    for p in base:
        assert p["chip_thickness_spread"] < 1.01
        paths = np.array([t["cut_length_m"] for t in p["teeth"]])
        assert (paths > 0).all() and paths.max() / paths.min() < 1.05
    energy = [np.array([t["chip_energy_J"] for t in load[-1]["teeth"]]) for load in (base, errored)]
    change = energy[1] / energy[0] - 1
    assert int(np.argmax(change)) == 5 and int(np.argmin(change)) == (5 - 20) % 17
