"""The machine's geometric errors (cutting/skiving/machine_geometry.py, [machine.model.geometry]; issue 43): the job's
section, the one forward kinematics the ideal cut and the simulated machine share, and the known answers on the gear."""

from __future__ import annotations

import dataclasses
import functools
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from small_jobs import small_job

from cutting.errors import InputError
from cutting.skiving.edge import make_edge
from cutting.skiving.exact_solve import _poses, compiled_pose
from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.signatures import flank_deviation_first_order
from cutting.skiving.tooling import Clamping
from cutting.skiving.trajectory import ideal_passes
from metrology.measure import measure_gear
from virtual_machine.job import parse_job
from virtual_machine.runtime.machine_run import relative_pose
from virtual_machine.setting.machine_layout import machine_params

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"
EVERY_ERROR = """
[machine.model]
radial_stiffness = 1.0e8

[machine.model.geometry]
shaft_angle_error = 0.01
centre_distance_offset = 0.004
cutter_offset_error = -0.02
carriage_squareness_x = 0.01
carriage_squareness_y = -0.02
lead_screw_periodic_error = 0.003
lead_screw_periodic_phase = 30.0
work_spindle_radial_error = 0.005
work_spindle_radial_phase = 60.0
work_spindle_tilt_error = 0.02
work_spindle_tilt_phase = -45.0
"""


def job_with(extra: str, face_width: float = 4.0):
    return parse_job(tomllib.loads(small_job(edge=None, face_width=face_width) + extra))


def test_the_section_gives_every_error_in_the_jobs_units() -> None:
    job = job_with(EVERY_ERROR)
    g = job.skiving.geometry
    assert g.shaft_angle_error == pytest.approx(math.radians(0.01))
    assert (g.centre_distance_offset, g.cutter_offset_error) == (0.004, -0.02)
    assert (g.carriage_squareness_x, g.carriage_squareness_y) == pytest.approx((1e-4, -2e-4))  # per 100 mm -> per mm
    assert g.lead_screw_periodic_phase == pytest.approx(math.radians(30.0))
    assert g.lead_screw_pitch == job.machine.lead_screw_pitch  # one period a screw turn
    assert g.work_spindle_tilt_error == pytest.approx(2e-4) and not g.exact
    # the machine model's own parameters beside it are untouched
    assert machine_params(job).radial_stiffness == 1.0e8
    assert job_with("").skiving.geometry.exact


@pytest.mark.parametrize(
    ("line", "key", "words"),
    [
        ("centre_distance_offset = 2.0", "centre_distance_offset", "set-up error"),
        ("shaft_angle_error = 5.0", "shaft_angle_error", "beyond +-1 deg"),
        ('cutter_offset_error = "0.01"', "cutter_offset_error", ""),
        ("shaft_angle = 0.01", "shaft_angle", "did you mean 'shaft_angle_error'"),
        ("lead_screw_periodic_error = nan", "lead_screw_periodic_error", "finite"),
    ],
)
def test_bad_geometry_is_refused_naming_the_key(line: str, key: str, words: str) -> None:
    with pytest.raises(InputError) as err:
        job_with(f"\n[machine.model.geometry]\n{line}\n")
    text = str(err.value)
    assert f"machine.model.geometry.{key}" in text and words in text, text


def test_the_cut_and_the_run_place_the_tool_by_the_same_geometry() -> None:
    """One forward kinematics: the ideal motion's poses (numpy), the compiled pose the removal and the measurement
    solve on, and the run's poses from its axes (relative_pose) agree to rounding with every error set; the spindle's
    synchronous error motions place the blank as a clamping eccentricity and tilt of the same vector and angle do (so
    their signatures on the gear are those tests/test_cutter_errors.py proves: F_r = 2 e, the pitch's sinusoid, the
    helix slope turning round the gear)."""
    st = job_with(EVERY_ERROR).skiving
    motion = ideal_passes(st)[-1]
    t = np.linspace(0.0, motion.duration, 41)
    rot, trans = motion.pose(t)
    kind, w = compiled_pose(motion)
    r2, o2 = np.empty((len(t), 9)), np.empty((len(t), 3))
    _poses(0, len(t), kind, w, t, r2, o2)
    assert np.abs(r2.reshape(-1, 3, 3) - rot).max() < 1e-12 and np.abs(o2 - trans).max() < 1e-9
    phi0, s = motion.cutter_angle(t), motion.carriage(t)
    q = np.stack(
        [phi0, st.speed_ratio * phi0 + st.differential_rotation_per_mm * s, s, np.full_like(t, motion.centre_distance)],
        -1,
    )
    r3, o3 = relative_pose(st, q)
    assert np.abs(r3 - rot).max() < 1e-12 and np.abs(o3 - trans).max() < 1e-9
    # the nominal kinematics stay the CNC's (the edge is designed for them): the machine's pose differs by the errors
    _, o0 = st.cutter_pose(phi0, s, motion.centre_distance)
    assert np.abs(o0 - trans).max() > 0.01
    spindle = job_with(
        "\n[machine.model.geometry]\nwork_spindle_radial_error = 0.005\nwork_spindle_radial_phase = 60.0\n"
    )
    clamped = job_with("\n[workpiece]\neccentricity = 0.005\neccentricity_phase = 60.0\n")
    assert clamped.skiving.clamping == Clamping(0.005, math.radians(60.0))
    assert np.abs(spindle.skiving.blank_frame - clamped.skiving.blank_frame).max() < 1e-15
    # and its tilt error motion (mm per 100 mm: an angle) as the clamping's tilt (a runout at the reference diameter)
    d = spindle.gear.reference_diameter
    wobble = job_with("\n[machine.model.geometry]\nwork_spindle_tilt_error = 0.02\nwork_spindle_tilt_phase = 30.0\n")
    tilted = job_with(f"\n[workpiece]\ntilt = {0.02 / 100 * d}\ntilt_phase = 30.0\n")
    assert np.abs(wobble.skiving.blank_frame - tilted.skiving.blank_frame).max() < 1e-15


def spur_external(extra: str = ""):
    """assets/jobs/spur_external.toml (z 40, mn 2) on a 4 mm face: its flanks in the steady cut are those of the full
    face (the same profile and pitch figures, measured) at a fifth of the measurement."""
    text = (JOBS / "spur_external.toml").read_text().replace("face_width = 20.0", "face_width = 4.0")
    return parse_job(tomllib.loads(text + extra))


def _measured(st):
    """The exact swept surface of the finishing pass (it passes through the whole space at full depth: the flanks
    are its own), measured."""
    exact = SweptVolumes(st.gear, make_edge(st, "conjugate"), ideal_passes(st)[-1:])
    return measure_gear(exact, st.gear)


def test_a_centre_distance_offset_thickens_the_teeth_by_its_span_signature() -> None:
    """Known answer (docs/machine_geometry.md; domain.md section 8): the axes 10 um farther apart than commanded make
    the span 2 delta_a sin(alpha_n) = 6.84 um larger, within 5 % (measured 6.84 um); the profile and the pitch do not
    change, within 0.3 um (measured: f_Halpha +0.17 um on both flanks, the crossed axes' second order: the edge is
    conjugate at the commanded centre distance only; F_p +0.02 um)."""
    nominal = _measured(spur_external().skiving)
    offset = _measured(spur_external("\n[machine.model.geometry]\ncentre_distance_offset = 0.010\n").skiving)
    change = (offset["thickness"]["span"]["W_k_mm"] - nominal["thickness"]["span"]["W_k_mm"]) * 1e3
    expected = 2 * 10.0 * math.sin(math.radians(20.0))
    assert change == pytest.approx(expected, rel=0.05), (change, expected)
    for side in ("left", "right"):
        for key in ("F_alpha", "f_Halpha", "f_falpha"):
            assert abs(offset["profile"][side][key] - nominal["profile"][side][key]) < 0.3, (side, key)
        for key in ("f_p", "F_p"):
            assert abs(offset["pitch"][side][key] - nominal["pitch"][side][key]) < 0.3, (side, key)


def small(extra: str = "", helix: float = 0.0, face_width: float = 8.0):
    """The small job (z 18, mn 1) on an 8 mm face, spur or with a helix [deg]; its finishing pass measured."""
    text = small_job(edge=None, face_width=face_width).replace(
        "normal_module = 1.0\n", f"normal_module = 1.0\nhelix_angle = {helix}\n"
    )
    return parse_job(tomllib.loads(text + extra))


def predicted_profile_slope(job, side: str, roll: tuple[float, float], points: int = 21) -> float:
    """The first-order profile slope [um] the job's machine geometry leaves on ``side`` (cutting/skiving/signatures.py:
    the envelope theorem at the generating points of the mid section, its mean line over the evaluation range)."""
    st = job.skiving
    nominal = dataclasses.replace(st, geometry=st.geometry.without_errors())
    L = np.linspace(*roll, points)
    d = flank_deviation_first_order(nominal, st, side, L, 0.0) * 1e3
    return float(np.polyfit(L, d, 1)[0] * (L[-1] - L[0]))


@functools.cache
def _nominal(helix: float, machine: str) -> dict:
    """The small job's measurement on the exact machine (shared by the tests: read, never changed)."""
    return _measured(small(machine, helix).skiving)


def _helix_change(extra: str, helix: float = 0.0, machine: str = ""):
    """(nominal, with the errors) measurements of the small job and its transverse pressure angle and base helix."""
    nominal = _nominal(helix, machine)
    job = small(machine + "\n[machine.model.geometry]\n" + extra, helix)
    g = job.gear
    alpha_t = math.atan(math.tan(g.alpha_n) / math.cos(g.beta))
    return nominal, _measured(job.skiving), alpha_t, math.atan(math.tan(g.beta) * math.cos(alpha_t))


@pytest.mark.parametrize(("axis", "flank_part"), [("x", "sin"), ("y", "cos")])
def test_the_carriages_squareness_tapers_or_twists_the_helix(axis: str, flank_part: str) -> None:
    """Known answer (docs/machine_geometry.md): the carriage off parallel to the work axis by c per mm moves the cutter
    by c s at carriage position s. Along x (the centre distance) each flank moves out by c s sin(alpha_t) along its
    base tangent: the same helix slope c L_beta sin(alpha_t) on both flanks (a taper); along y (tangential at the
    mesh) by -+c s cos(alpha_t): the slope c L_beta cos(alpha_t), opposite on the two flanks (the teeth twisted).
    And the profile: a section's points are generated at carriage positions that differ along the roll (the contact
    runs up the rake face, which the shaft angle tilts: about L_alpha cos(alpha_t) tan(Sigma)), so the profile
    slope is c times that times sin(alpha_t) (x, opposite on the flanks) or cos(alpha_t) (y, the same on both): the
    first-order signature at the generating points (cutting/skiving/signatures.py). Each within 10 % on the spur
    small job at 0.3 mm per 100 mm (helix 7.39 and 20.30 um: measured 7.36 / 7.38 and 20.33; profile predicted 1.55
    and 4.43 um, measured 1.58 and 4.39)."""
    c = 0.3  # mm per 100 mm
    nominal, errored, alpha_t, _ = _helix_change(f"carriage_squareness_{axis} = {c}")
    lo, hi = errored["evaluation"]["helix_z_mm"]
    part = math.sin(alpha_t) if flank_part == "sin" else math.cos(alpha_t)
    expected = c / 100 * (hi - lo) * part * 1e3
    change = {s: errored["helix"][s]["f_Hbeta_mean"] - nominal["helix"][s]["f_Hbeta_mean"] for s in ("left", "right")}
    assert abs(change["left"]) == pytest.approx(expected, rel=0.10), (change, expected)
    assert abs(change["right"]) == pytest.approx(expected, rel=0.10), (change, expected)
    assert (change["left"] * change["right"] > 0) == (axis == "x"), change
    roll = tuple(errored["evaluation"]["profile_roll_mm"])
    job = small(f"\n[machine.model.geometry]\ncarriage_squareness_{axis} = {c}\n")
    for side in ("left", "right"):
        slope = errored["profile"][side]["f_Halpha_mean"] - nominal["profile"][side]["f_Halpha_mean"]
        assert slope == pytest.approx(predicted_profile_slope(job, side, roll), rel=0.10), side


def _sine(z: np.ndarray, y: np.ndarray, wavelength: float) -> float:
    """The amplitude of the sine of ``wavelength`` in y(z) beside a straight line (least squares)."""
    k = 2 * math.pi / wavelength
    a = np.stack([np.ones_like(z), z, np.sin(k * z), np.cos(k * z)], -1)
    coef = np.linalg.lstsq(a, y, rcond=None)[0]
    return float(np.hypot(coef[2], coef[3]))


def test_the_screws_periodic_error_waves_a_helical_flank_and_leaves_a_spur_one() -> None:
    """Known answer: the carriage e sin(2 pi z / p) off along the work axis moves a helical flank along its base
    tangent by e tan(beta_b) sin(2 pi z / p) (the helix term: an axial shift is a turn of the work, domain.md
    section 8): the helix traces wave with the screw's pitch at that amplitude, within 10 %; a spur flank's normal
    has no axial part: no wave (below 0.1 um) and its slope within 0.3 um. Screw pitch 2 mm, e = 10 um, the small
    job at 15 deg."""
    e, pitch = 0.010, 2.0
    screw = f"\n[machine]\nlead_screw_pitch = {pitch}\n"
    nominal, errored, _, beta_b = _helix_change(f"lead_screw_periodic_error = {e}", 15.0, screw)
    z = errored["_traces"]["z_mm"]
    for side in ("left", "right"):
        d = (np.asarray(errored["_traces"]["helix"][side]) - np.asarray(nominal["_traces"]["helix"][side])) * 1e3
        amplitude = np.mean([_sine(z, row, pitch) for row in d])  # um, per tooth's trace
        assert amplitude == pytest.approx(e * math.tan(beta_b) * 1e3, rel=0.10), (side, amplitude)
    # on a spur gear the feed marks move with the carriage (up to 0.6 um at a point), but no wave and no slope appear
    spur0, spur1, _, _ = _helix_change(f"lead_screw_periodic_error = {e}", 0.0, screw)
    for side in ("left", "right"):
        d = (np.asarray(spur1["_traces"]["helix"][side]) - np.asarray(spur0["_traces"]["helix"][side])) * 1e3
        assert np.mean([_sine(z, row, pitch) for row in d]) < 0.1, side
        assert abs(spur1["helix"][side]["f_Hbeta_mean"] - spur0["helix"][side]["f_Hbeta_mean"]) < 0.3, side


@pytest.mark.parametrize("helix", [0.0, 15.0])
def test_a_shaft_angle_error_tilts_the_profile_by_the_contacts_height_on_the_rake_face(helix: float) -> None:
    """Known answer (docs/machine_geometry.md): the swivel head turned by d_Sigma about the common perpendicular
    moves the tool at the generating point P by d_Sigma x (P - c). The contact runs up the rake face along the roll
    (its height over the cutter centre about lambda cos(alpha_t) tan(Sigma) at roll lambda from the pitch point), so
    the flank normal's y part turns this into a profile slope of about d_Sigma L_alpha cos^2(alpha_t) tan(Sigma);
    on a helical gear its axial part adds one of the same sign on both flanks. The first-order signature at the
    generating points (cutting/skiving/signatures.py) within 10 %, per flank, at d_Sigma = 0.1 deg on the small job,
    spur (Sigma 20 deg: 2.57 um predicted, 2.58 / 2.57 measured) and at 15 deg (Sigma 35 deg: 2.76, 2.79 / 2.79);
    the helix and the pitch within 0.3 um."""
    d_sigma = 0.1
    nominal, errored, _, _ = _helix_change(f"shaft_angle_error = {d_sigma}", helix)
    roll = tuple(errored["evaluation"]["profile_roll_mm"])
    job = small(f"\n[machine.model.geometry]\nshaft_angle_error = {d_sigma}\n", helix)
    for side in ("left", "right"):
        slope = errored["profile"][side]["f_Halpha_mean"] - nominal["profile"][side]["f_Halpha_mean"]
        assert slope == pytest.approx(predicted_profile_slope(job, side, roll), rel=0.10), side
        assert abs(errored["helix"][side]["f_Hbeta_mean"] - nominal["helix"][side]["f_Hbeta_mean"]) < 0.3, side
        assert abs(errored["pitch"][side]["F_p"] - nominal["pitch"][side]["F_p"]) < 0.3, side


def continuous_generation_start(st, roll: tuple[float, float], points: int = 25) -> float:
    """The roll length from which the finishing pass generates the profile by a moving contact: where the
    generating carriage position's rate along the roll first reaches half its value at mid profile (below it, at the
    root end, the generating instant stalls: the edge's end cuts those points over several passages, whose scallops
    the first order does not follow; cutting/skiving/signatures.py)."""
    from cutting.flank import flank_points
    from cutting.skiving.signatures import generating_instant

    g = st.gear
    L = np.linspace(*roll, points)
    a = st.final_centre_distance
    edge = make_edge(st, "conjugate")
    s = np.array([generating_instant(st, flank_points(g, "left", np.array([x / g.base_radius]), 0.0, 0)[0], a, edge)[1]
                  for x in L])  # fmt: skip
    rate = np.abs(np.diff(s) / np.diff(L))
    return float(L[int(np.argmax(rate >= 0.5 * rate[len(rate) // 2]))])


def test_a_cutter_offset_turns_the_gear_and_tilts_the_profile_a_little() -> None:
    """Known answer: the cutter centre moved by d_y along y (tangential at the mesh) moves each flank along its
    normal by d_y n_y, at the generating points about -+d_y cos(beta_b) cos(alpha_t): what a turn of the gear by
    d_y cos(alpha_t) / r_b = d_y / r does. The measured gear sits turned by d_y / r (its datum, within 1 %: 5.561
    mrad against 5.556 at d_y = 50 um on the spur small job); what varies of n_y along the roll (the generating
    points leave the line of action near the root) tilts the profile, opposite on the two flanks. Over the profile
    the finishing pass generates by a moving contact (from L 0.36 mm on the small job: below it the generating
    instant stalls at the edge's end and the nominal cut itself stands up to 0.66 um off the involute in scallops the
    first order does not follow) the measured slope is the predicted one within 10 % (-0.510 / 0.516 um against
    -0.510 / 0.510); over the whole ISO range, root end included, 0.52 / 0.54 against 0.61 um (within 20 %); helix,
    pitch and span within 0.3 um."""
    dy = 0.05
    nominal, errored, _, _ = _helix_change(f"cutter_offset_error = {dy}")
    r = small().gear.reference_radius
    turn = math.radians(errored["evaluation"]["datum"]["rotation_deg"] - nominal["evaluation"]["datum"]["rotation_deg"])
    assert abs(turn) == pytest.approx(dy / r, rel=0.01), (turn, dy / r)
    roll = tuple(errored["evaluation"]["profile_roll_mm"])
    job = small(f"\n[machine.model.geometry]\ncutter_offset_error = {dy}\n")
    start = continuous_generation_start(job.skiving, roll)
    L = np.asarray(errored["_traces"]["L_mm"])
    kept = L >= start
    for side in ("left", "right"):
        slope = errored["profile"][side]["f_Halpha_mean"] - nominal["profile"][side]["f_Halpha_mean"]
        assert slope == pytest.approx(predicted_profile_slope(job, side, roll), rel=0.20), side
        change = np.asarray(errored["_traces"]["profile"][side]) - np.asarray(nominal["_traces"]["profile"][side])
        measured = np.polyfit(L[kept], change.mean(0)[kept] * 1e3, 1)[0] * (L[-1] - start)
        assert measured == pytest.approx(predicted_profile_slope(job, side, (start, roll[1])), rel=0.10), side
        for block, key in (("helix", "f_Hbeta_mean"), ("pitch", "F_p"), ("pitch", "f_p")):
            assert abs(errored[block][side][key] - nominal[block][side][key]) < 0.3, (side, key)
    span = (errored["thickness"]["span"]["W_k_mm"] - nominal["thickness"]["span"]["W_k_mm"]) * 1e3
    assert abs(span) < 0.3


def test_the_run_makes_its_gear_on_the_machine_as_built() -> None:
    """`skive run`'s co-simulation: the machine's dynamics are those of the machine as designed (the axes' records
    and the loads the same bit for bit: micrometres of geometry change no lever arm the drives feel), and the gear it
    cuts is placed by the geometry (relative_pose): 10 um of centre distance offset grows the span by
    2 delta_a sin(alpha_n) = 6.84 um within 5 % (measured 7.00 um; the small job on a 4 mm face at 0.4 mm feed), the
    profile slope within 0.3 um."""
    from cutting.skiving.sampled_motion import sampled_passes
    from virtual_machine.processes.skiving.cosim import cosimulate

    out = {}
    for name, extra in (("nominal", ""), ("offset", "\n[machine.model.geometry]\ncentre_distance_offset = 0.010\n")):
        job = parse_job(tomllib.loads(small_job(edge=None, face_width=4.0, axial_feed=0.4) + extra))
        sim = cosimulate(job, removal="none")
        exact = SweptVolumes(job.gear, sim.edge, sampled_passes(job.skiving, sim.record.passes))
        out[name] = (sim, measure_gear(exact, job.gear))
    (sim0, doc0), (sim1, doc1) = out["nominal"], out["offset"]
    assert np.array_equal(sim0.record.q, sim1.record.q) and np.array_equal(sim0.load_rows, sim1.load_rows)
    change = (doc1["thickness"]["span"]["W_k_mm"] - doc0["thickness"]["span"]["W_k_mm"]) * 1e3
    assert change == pytest.approx(2 * 10.0 * math.sin(math.radians(20.0)), rel=0.05)
    for side in ("left", "right"):
        assert abs(doc1["profile"][side]["f_Halpha_mean"] - doc0["profile"][side]["f_Halpha_mean"]) < 0.3


def test_a_study_varies_the_geometry_as_any_job_key(tmp_path) -> None:
    """Every geometry key is a study key (its default 0 where the base job has none); a wrong one is refused naming
    the valid ones."""
    from virtual_machine.studies.design import cases
    from virtual_machine.studies.spec import load_study

    def study_file(text: str) -> Path:
        path = tmp_path / "study.toml"
        path.write_text(f'base = "{JOBS / "default.toml"}"\n' + text)
        return path

    key = "machine.model.geometry.centre_distance_offset"
    study = load_study(study_file(f'[[vary]]\nkey = "{key}"\nvalues = [0.0, 0.01]\ntolerance = 0.005\n'))
    made = [parse_job(tomllib.loads(c.job_text)).skiving.geometry.centre_distance_offset for c in cases(study)]
    assert made == [0.0, 0.01]
    with pytest.raises(InputError) as err:
        load_study(study_file('[[vary]]\nkey = "machine.model.geometry.centre_offset"\nvalues = [0.01]\n'))
    assert "unknown machine geometry key" in str(err.value) and key in str(err.value)


def test_the_model_scope_lists_each_source_with_its_value_in_the_jobs_units() -> None:
    """measurement.json's model_scope (virtual_machine/output/model_scope.py): the run's sources with their values as
    the job gives them (deg, mm, mm per 100 mm), the cutter's errors and the clamping; what it leaves out with why;
    `skive cut` says the machine's dynamics are not in it."""
    from virtual_machine.output.model_scope import model_scope, scope_lines
    from virtual_machine.setting.machine_layout import machine_params

    extra = EVERY_ERROR + "\n[workpiece]\neccentricity = 0.004\n\n[cutter.errors]\nradial_runout = 0.003\n"
    job = job_with(extra)
    scope = model_scope(job, machine_params(job), "run")
    values = {it["key"]: (it["value"], it["unit"]) for it in scope["included"]}
    assert values["machine.model.geometry.shaft_angle_error"] == (pytest.approx(0.01), "deg")
    assert values["machine.model.geometry.carriage_squareness_y"] == (pytest.approx(-0.02), "mm/100 mm")
    assert values["machine.model.geometry.work_spindle_tilt_error"] == (pytest.approx(0.02), "mm/100 mm")
    assert values["workpiece.eccentricity"] == (0.004, "mm") and values["cutter.errors.radial_runout"] == (0.003, "mm")
    left_out = {it["source"] for it in scope["not_included"]}
    assert not any("geometry" in s for s in left_out) and any("thermal" in s for s in left_out)
    assert "  not included" in scope_lines(scope)
    cut = model_scope(job_with(""), None, "cut")
    assert any("dynamics" in it["source"] for it in cut["not_included"])
    assert any("geometry" in it["source"] for it in cut["not_included"])


ARCSEC = math.pi / 180 / 3600


def _fit_once_per_turn(values: np.ndarray) -> tuple[float, float]:
    """(amplitude, largest residual) of the once-around sinusoid in per-tooth values."""
    k = np.arange(len(values))
    a = np.stack([np.ones(len(k)), np.sin(2 * np.pi * k / len(k)), np.cos(2 * np.pi * k / len(k))], -1)
    coef = np.linalg.lstsq(a, values, rcond=None)[0]
    return float(np.hypot(coef[1], coef[2])), float(np.abs(values - a @ coef).max())


def test_a_work_encoders_eccentricity_turns_each_space_by_its_reading() -> None:
    """Known answer: the work spindle held at its encoder's reading stands e sin(B2 + phase) behind: each space is
    cut turned by that at its own angle, so the cumulative pitch of both flanks is a once-around sinusoid of amplitude
    r_p e along the measuring circle (domain.md section 8: F_p and runout, profile and helix clean), within 10 %
    (measured 0.998 of it at 60 arcsec; the small job at 0.1 mm feed, whose feed marks disturb a pitch probe less)."""
    text = small_job(edge=None, face_width=8.0, axial_feed=0.1)
    nominal = _measured(parse_job(tomllib.loads(text)).skiving)
    extra = "\n[machine.model.geometry]\nwork_encoder_eccentricity = 60.0\nwork_encoder_phase = 30.0\n"
    errored = _measured(parse_job(tomllib.loads(text + extra)).skiving)
    r_p = errored["evaluation"]["pitch_diameter_mm"] / 2
    for side in ("left", "right"):
        d = np.array(errored["pitch"][side]["F_pi"]) - np.array(nominal["pitch"][side]["F_pi"])
        amplitude, residual = _fit_once_per_turn(d)
        assert amplitude == pytest.approx(r_p * 60 * ARCSEC * 1e3, rel=0.10), side
        assert residual < 0.2, side
        for block, key in (("profile", "f_Halpha_mean"), ("helix", "f_Hbeta_mean")):
            assert abs(errored[block][side][key] - nominal[block][side][key]) < 0.3, (side, key)


def test_a_tool_encoders_eccentricity_waves_the_helix_with_the_cutters_phase() -> None:
    """Known answer: the tool spindle stands e sin(B1 + phase) behind, a turn of the work of ratio e: a flank point is
    moved along its base tangent by r_b ratio e sin(B1 + phase) at the cutter angle that generates it. A space is
    visited once a work turn, the cutter then z2 / z0 turns further: its phase at the visits advances by
    2 pi frac(z2 / z0) per axial feed s, a wave of s / |z2 / z0 - round(z2 / z0)| along the helix (3.4 mm: z 18,
    z0 17, s 0.2 mm) of that amplitude, within 10 % (0.769 against 0.774 um at 20 arcsec on the small job)."""
    nominal, errored, _, _ = _helix_change("tool_encoder_eccentricity = 20.0")
    st = small().skiving
    g, z0 = st.gear, st.cutter.teeth
    wavelength = st.axial_feed / abs(g.teeth / z0 - round(g.teeth / z0))
    z = errored["_traces"]["z_mm"]
    expected = g.base_radius * abs(st.speed_ratio) * 20 * ARCSEC * 1e3
    for side in ("left", "right"):
        d = (np.asarray(errored["_traces"]["helix"][side]) - np.asarray(nominal["_traces"]["helix"][side])) * 1e3
        assert np.mean([_sine(z, row, wavelength) for row in d]) == pytest.approx(expected, rel=0.10), side


def test_the_run_reads_the_encoders_in_its_controllers() -> None:
    """`skive run`: the encoders' errors enter where each structure's controllers read the spindles (here the
    electronic gearbox's IP2): the synchronisation error the machine makes gains a once-per-work-turn sinusoid
    (the differences of the run against the exact machine explained by it: residual below a fifth of it). Its
    amplitude is what the servo loop follows of the encoder's error at the work spindle's 31 Hz: measured 1.88 um
    against r2 e = 2.62 um (a perfect servo's, as `skive cut` takes it): between half and the whole of it."""
    from virtual_machine.processes.skiving.cosim import cosimulate

    records = []
    for extra in ("", "\n[machine.model.geometry]\nwork_encoder_eccentricity = 60.0\n"):
        job = parse_job(tomllib.loads(small_job(edge=None, face_width=4.0, axial_feed=0.4) + extra))
        records.append(cosimulate(job, removal="none").record)
    a, b = records
    cut = b.cutting
    d = (b.sync_um - a.sync_um)[cut]
    b2 = b.q[cut, 1]
    basis = np.stack([np.ones(len(d)), np.sin(b2), np.cos(b2)], -1)
    coef = np.linalg.lstsq(basis, d, rcond=None)[0]
    amplitude = float(np.hypot(coef[1], coef[2]))
    full = job.gear.reference_radius * 60 * ARCSEC * 1e3
    assert 0.5 * full < amplitude < 1.05 * full, (amplitude, full)
    assert np.abs(d - basis @ coef).max() < 0.2 * amplitude


def test_what_the_machine_added_holds_its_geometry() -> None:
    """The ideal-cut reference of `skive run`'s "what the machine added" is the exact kinematics on the machine as
    designed: a job's geometric errors are the machine's, so its reference is the same job's without them (the same
    span to the nanometre), and the run's difference from it shows them."""
    from virtual_machine.processes.skiving.machine_added import ideal_measurement

    offset = ideal_measurement(job_with("\n[machine.model.geometry]\ncentre_distance_offset = 0.010\n"), "conjugate")
    exact = ideal_measurement(job_with(""), "conjugate")
    assert offset["thickness"]["span"]["W_k_mm"] == pytest.approx(exact["thickness"]["span"]["W_k_mm"], abs=1e-9)
