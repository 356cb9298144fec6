"""The scenario jobs of assets/jobs/scenarios/: each runs on the simulated machine (machine and cutting forces, the
gear measured as skive run measures it) and shows the deviation theory predicts for the one thing it changes against
its baseline.

A phase error of the work that drifts with the carriage tilts the helix: a drift de/ds of the synchronisation
error (arc on the reference circle) per mm of carriage over the face changes the helix slope deviation by
de/ds L_beta cos(alpha_t) (the arc turned into the base tangent), with opposite signs on the two flanks.

Every gear is measured on the exact swept surface of the motion the machine made (no chord error), so the
signatures are held to 5 % of theory (or 0.1-0.25 um where a signature is only a few micrometres).
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest

from cutting.skiving.edge import make_edge
from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.sampled_motion import sampled_passes
from cutting.skiving.trajectory import ideal_passes
from metrology.measure import measure_gear
from virtual_machine.job import load_job
from virtual_machine.processes.skiving.cosim import cosimulate
from virtual_machine.setting.sheet import setup_sheet

pytestmark = pytest.mark.slow  # whole machine jobs (pytest -m 'not slow' skips them)

SCENARIOS = Path(__file__).resolve().parents[1] / "assets" / "jobs" / "scenarios"
SIDES = ("left", "right")


#: the scenarios whose runs test_study.py's studies take as their cases: run once in the session, as a study case
#: (skive run: the same co-simulation, and the same measurement of the exact swept surface with the mesh beside it)
STUDIED = ("helical_mechatronic", "lead_screw_error", "mechanical_change_gears")


@pytest.fixture(scope="module")
def scenario(shared_runs):
    """name -> (job, the machine's motion record, measurement of the exact swept surface of the motion the machine
    made): each scenario job run once, the tests share it. The studied ones first, as a study's worker runs a case
    (tests/shared_runs.py): test_study.py, in the other process, takes them from the store. The others are
    co-simulated without a workpiece (removal "none"): the force is the chip of the moment's, not the removal's, so
    the motion is the same bit for bit, and the gear is measured on its exact swept surface, not on the removal's
    solid; the dexel removal would take ~3/4 of each co-simulation's time."""
    for name in STUDIED:
        shared_runs.run(SCENARIOS / f"{name}.toml")

    @functools.cache
    def run(name: str):
        job = load_job(SCENARIOS / f"{name}.toml")
        if name in STUDIED:
            result, record = shared_runs.run(SCENARIOS / f"{name}.toml")
            return job, record, result["measurement"]
        sim = cosimulate(job, removal="none")
        exact = SweptVolumes(job.gear, sim.edge, sampled_passes(job.skiving, sim.record.passes))
        return job, sim.record, measure_gear(exact, job.gear)

    return run


@functools.cache
def ideal_cut_of_baseline():
    """The baseline job cut with the ideal kinematics (exact ratios, no machine): the exact swept surface of the
    ideal passes, measured the same way."""
    job = load_job(SCENARIOS / "helical_mechatronic.toml")
    exact = SweptVolumes(job.gear, make_edge(job.skiving, job.cutter_options.edge), ideal_passes(job.skiving))
    return measure_gear(exact, job.gear)


@pytest.fixture(scope="module")
def helical(scenario):
    """The helical baseline and the scenarios against it: name -> (job, motion record, measurement)."""
    return {name: scenario(name) for name in ("helical_mechatronic", "lead_screw_error", "no_correction")}


def drift_um_per_mm(rec, face_width: float) -> float:
    """Slope of the synchronisation error against the carriage while the mesh point crosses the face [um/mm]."""
    s, e = rec.q[rec.cutting, 2], rec.sync_um[rec.cutting]
    over = np.abs(s) < face_width / 2
    return float(np.polyfit(s[over], e[over], 1)[0])


def helix_change(doc, base) -> dict[str, float]:
    return {s: doc["helix"][s]["f_Hbeta_mean"] - base["helix"][s]["f_Hbeta_mean"] for s in SIDES}


def base_tangent_length(job, doc) -> float:
    """L_beta cos(alpha_t) [mm]: turns a phase drift per mm of carriage (arc on d) into the helix slope [um]."""
    g = job.gear
    z0, z1 = doc["evaluation"]["helix_z_mm"]
    return (z1 - z0) * math.cos(math.atan(math.tan(g.alpha_n) / math.cos(g.beta)))


def predicted_helix_change(job, doc, rec, base_rec) -> float:
    """The left-flank change of f_Hbeta [um] that the change of the sync error's drift predicts."""
    slope = drift_um_per_mm(rec, job.gear.face_width) - drift_um_per_mm(base_rec, job.gear.face_width)
    return -slope * base_tangent_length(job, doc)


def helix_parts(doc, ref) -> tuple[float, float]:
    """The change of f_Hbeta against ``ref`` split into the part opposite on the flanks (a phase drift: the helix
    angle changes; left-flank sign) and the part alike on both (the tooth thickness changes along the face)."""
    d = helix_change(doc, ref)
    return (d["left"] - d["right"]) / 2, (d["left"] + d["right"]) / 2


def measured_change(doc, ref, name: str) -> float:
    return doc["iso1328"]["measured"][name] - ref["iso1328"]["measured"][name]


def test_lead_screw_pitch_error_tilts_the_helix(helical) -> None:
    """The carriage travels (1 + eps) times what the CNC counts, the differential rotation follows the count: the
    lead grows by eps, so the helix slope deviation changes by eps L_beta tan(beta_b), opposite on the flanks."""
    (job, base_rec, base), (bad_job, rec, bad) = helical["helical_mechatronic"], helical["lead_screw_error"]
    eps = bad_job.machine.model["lead_screw_pitch_error"]
    g = job.gear
    alpha_t = math.atan(math.tan(g.alpha_n) / math.cos(g.beta))
    tan_beta_b = math.tan(g.beta) * math.cos(alpha_t)
    z0, z1 = bad["evaluation"]["helix_z_mm"]
    expected = eps * (z1 - z0) * tan_beta_b * 1e3  # um
    assert 8.0 < expected < 10.0
    change = helix_change(bad, base)
    assert change["left"] * change["right"] < 0, change
    for s in SIDES:  # measured -8.88 / +8.93 um against 9.03 um (dexel removal, 2026-11-26)
        assert abs(change[s]) == pytest.approx(expected, rel=0.05), change
    # the same from the recorded drift: r2 |dphi2/ds| eps = 2.7 um per mm of carriage (measured 8.90 um)
    assert abs(predicted_helix_change(bad_job, bad, rec, base_rec)) == pytest.approx(expected, rel=0.05)
    # the pitch does not care (measured +0.25 um); the profile slope moves too, by the same amount on both
    # flanks (measured -4.7 / -4.8 um: in skiving root and tip of a flank are generated at different carriage
    # positions, mirrored between the flanks, and the phase drifts with the carriage), less than the helix
    assert abs(bad["iso1328"]["measured"]["F_p"] - base["iso1328"]["measured"]["F_p"]) < 0.5
    profile = [bad["profile"][s]["f_Halpha_mean"] - base["profile"][s]["f_Halpha_mean"] for s in SIDES]
    assert profile[0] * profile[1] > 0 and max(map(abs, profile)) < expected


def test_adaptive_correction_holds_the_phase_under_the_cutting_load(helical) -> None:
    """Without the correction (keys open) the axes are only speed-controlled: the cutting torque's changes leave
    phase errors that stay. The correction reduces the sync error while cutting at least 5x (seed 000's purpose);
    without it the phase drifts over the face and tilts the helix by that drift, opposite on the flanks."""
    (job, base_rec, base), (_, rec, free) = helical["helical_mechatronic"], helical["no_correction"]
    with_, without = base_rec.sync_stats("cut")["rms_um"], rec.sync_stats("cut")["rms_um"]
    assert without > 5 * with_, (with_, without)
    change = helix_change(free, base)
    assert change["left"] * change["right"] < 0, change
    predicted = predicted_helix_change(job, free, rec, base_rec)
    assert abs(predicted) > 5.0  # a real effect, not scatter
    # the helix angle part (measured 9.0 um against 10.2 predicted); the part alike on the flanks (a taper of the
    # tooth thickness) is the depth axis giving way to a radial force that the phase error changes. With the
    # cutting force alone the tool spindle carried the torque, the drift was 43 um and the two agreed within 2 %;
    # with the thrust the work spindle carries most of it (docs/forces.md), the drift is a quarter, and 1.2 um of
    # the helix change is not the recorded drift's (not yet explained: the work spindle's wind-up behind its
    # encoder is the suspect)
    opposite, alike = helix_parts(free, base)
    assert opposite == pytest.approx(predicted, abs=1.5), (change, predicted)
    assert abs(alike) < 3.0, alike
    assert free["iso1328"]["class"]["overall"] is None or free["iso1328"]["class"]["overall"] >= 9  # measured 9


def test_ideal_stiff_machine_cuts_the_ideal_kinematics_gear(scenario) -> None:
    """Every stage and the nut rigid, no backlash or friction, a 10x stiffer depth axis, fine pulses and encoders:
    the machine turns the exact setup ratios (mean sync error ~0), so it cuts the gear of the ideal kinematics.
    What remains is the servo loops' lag under the cutting load, which changes while the cutter crosses the face:
    the helix tilts by exactly that recorded drift (2.03 um predicted, 2.14 measured), opposite on the flanks.
    Tolerances: 0.25 um on the helix parts, 0.5 um on pitch and runout (measured within 0.05 um), 1 um on the
    profile form (0.31), a class no worse. The ideal cut's own pitch and runout (F_p 1.7, F_r 1.2 um) are its feed
    marks: every space is cut f/z2 further along the face than the one before, so the marks meet the measuring
    plane at a phase that turns once per revolution; they fall with the feed squared (test_cut_measurement.py).
    The drift also tilts both profiles alike (+2.8 / +1.9 um of f_Halpha here, as the lead screw's drift does):
    F_alpha is not compared."""
    job, rec, doc = scenario("ideal_machine")
    ideal = ideal_cut_of_baseline()
    stats = rec.sync_stats("cut")
    assert abs(stats["mean_um"]) < 0.5, stats
    drift = drift_um_per_mm(rec, job.gear.face_width)
    assert abs(drift) < 1.5, drift  # the servos alone hold the load: a small lag, no ratio error
    opposite, alike = helix_parts(doc, ideal)
    assert opposite == pytest.approx(-drift * base_tangent_length(job, doc), abs=0.25), (opposite, drift)
    assert abs(alike) < 0.3, alike
    for name in ("F_p", "f_p", "F_r"):
        assert abs(measured_change(doc, ideal, name)) < 0.5, name
    assert abs(measured_change(doc, ideal, "f_falpha")) < 1.0
    assert doc["iso1328"]["class"]["overall"] <= ideal["iso1328"]["class"]["overall"]


def test_mechanical_change_gear_error_tilts_the_helix_by_the_sheets_amount(scenario) -> None:
    """S1 without a 17-tooth change gear realises ix = 1.7 as 65/41 * 89/83 (eps = -1.73e-5): the work lags
    eps pi d2 = 1.12 um of arc per work turn, -5.6 um per mm of carriage, and the helix tilts by that drift over
    L_beta, opposite on the flanks (18.9 um here; measured 19.1); the load barely adds to it. Tolerance 5 %."""
    job, rec, doc = scenario("mechanical_change_gears")
    ideal = ideal_cut_of_baseline()
    ix = setup_sheet(job, "mechanical").settings["ix"]
    assert ix.realisation["gears"]["a_b_c_d"] == [65, 41, 89, 83] and ix.relative_error == pytest.approx(
        -1.73e-5, rel=0.01
    )
    predicted = ix.effect["pitch_um_per_work_rev"] / job.process.axial_feed  # um of arc per mm of carriage
    assert drift_um_per_mm(rec, job.gear.face_width) == pytest.approx(predicted, rel=0.05)
    opposite, alike = helix_parts(doc, ideal)
    assert opposite == pytest.approx(-predicted * base_tangent_length(job, doc), rel=0.05), (opposite, predicted)
    assert abs(alike) < 2.5  # the realistic depth axis under the radial force (1.4 um, as on the baseline)
    assert abs(measured_change(doc, ideal, "F_p")) < 0.5  # every tooth is cut in the same carriage band
    # the tilt alone takes F_beta to class 9-10 (the helix's own class 9 here since the chip of the moment's load)
    assert doc["iso1328"]["class"]["overall"] is None or doc["iso1328"]["class"]["overall"] >= 9


def test_hydraulic_shaft_without_differential_tilts_the_helix_by_its_divider_error(scenario) -> None:
    """S3 makes the helix through kx = (z2/z0)(1 + dir2 s/T) = 1.177440, which the coding disc realises as 4239
    windows of 3600 steps = 1.1775 (eps = +5.1e-5: the work lags eps 2 pi r2 = 3.3 um per turn, 16.6 um per mm).
    The simulated machine turns exactly the realised ratio; the oil column of the stepping motor (stiffness k,
    leakage c) adds the tool's lag T / k and its creep c T per second, which change over the face as the cutter's
    load T at GShD (1:1 to the tool) does: (dT/ds / k + c T / (ds/dt)) (z0/z2) r2 more drift per mm (the tool's
    angle as the work's arc on the reference circle; -3.3 um/mm from the recorded torque, measured 24 % more drift in
    all). The helix tilts by the recorded drift (70 um), opposite on the flanks. Tolerances: the ratio within 1e-5;
    the drift and the helix within 5 % of theory."""
    from virtual_machine.setting.machine_layout import machine_params

    job, rec, doc = scenario("hydraulic_shaft")
    ideal = ideal_cut_of_baseline()
    kx = setup_sheet(job, "hydraulic-shaft").settings["kx"]
    g, feed = job.gear, job.skiving.axial_feed
    exact = g.z / job.cutter.z * (1 + feed * math.sin(g.beta) / (math.pi * g.mn * g.z))  # T = pi mn z2 / sin beta2
    eps = round(3600 * exact) / (3600 * exact) - 1  # a disc of 3600 steps: whole windows
    assert kx.value == pytest.approx(exact, rel=1e-12) and kx.realised == round(3600 * exact) / 3600
    b1, b2 = rec.q[rec.cutting, 0], rec.q[rec.cutting, 1]
    assert abs(np.polyfit(b2, b1, 1)[0]) == pytest.approx(kx.realised, rel=1e-5)
    sheet = -kx.effect["pitch_um_per_work_rev"] / feed  # S3: kx is cutter turns per work turn
    assert sheet == pytest.approx(-eps * 2 * math.pi * g.reference_radius * 1e3 / feed, rel=1e-9)
    drift = drift_um_per_mm(rec, g.face_width)
    params = machine_params(job)
    over = rec.cutting & (np.abs(rec.q[:, 2]) < g.face_width / 2)
    s, torque = rec.q[over, 2], rec.torque[over, list(rec.actuators).index("GShD")]
    speed = np.polyfit(rec.t[over], s, 1)[0]  # ds/dt [mm/s]
    to_arc = job.cutter.z / g.z * g.reference_radius * 1e3  # um of arc on the work's reference circle per tool rad
    lag = np.polyfit(s, torque, 1)[0] / params.hydraulic_stiffness + params.hydraulic_leakage * torque.mean() / speed
    assert drift == pytest.approx(sheet + lag * to_arc, rel=0.05), (drift, sheet, lag * to_arc)
    opposite, _ = helix_parts(doc, ideal)
    assert opposite == pytest.approx(-drift * base_tangent_length(job, doc), rel=0.05), (opposite, drift)
    assert doc["iso1328"]["class"]["overall"] is None  # 70 um of helix slope: beyond class 11


def test_hydraulic_shaft_with_differential_keeps_the_helix(scenario) -> None:
    """S2 adds the helix through the differential from the feed (ky, -4.9e-6 off) and leaves kx = z0/z2 exact:
    no ratio drift, so the helix stays within what the load's lag makes on any machine (3.7 um here since the thrust
    put most of the cut's torque on the work spindle, 1.85 um with the cutting force alone; 70 um without the
    differential; the recorded drift predicts it within 10 %: 3.43 um, where it was within 0.1 um with the cutting
    force alone; the rest is not yet explained, as in test_adaptive_correction_holds_the_phase_under_the_cutting_load)
    and the gear grades within a class of the ideal cut (7 against 6: the thrust's deflection adds profile form)."""
    job, rec, doc = scenario("hydraulic_differential")
    ideal = ideal_cut_of_baseline()
    sheet = setup_sheet(job, "hydraulic-differential").settings
    assert sheet["kx"].relative_error == 0.0 and abs(sheet["ky"].relative_error) < 1e-5
    drift = drift_um_per_mm(rec, job.gear.face_width)
    assert abs(drift) < 1.5, drift
    opposite, _ = helix_parts(doc, ideal)
    assert abs(opposite) < 4.5 and opposite == pytest.approx(-drift * base_tangent_length(job, doc), rel=0.1)
    # the profile form is the feed marks' and the deflection under the thrust: within 2 um of the ideal cut's
    # (measured 1.12; 0.15 with the cutting force alone: the thrust normal to the flank bends it)
    assert abs(measured_change(doc, ideal, "f_falpha")) < 2.0
    assert doc["iso1328"]["class"]["overall"] <= ideal["iso1328"]["class"]["overall"] + 1


def test_work_drive_backlash_stays_out_of_the_gear(scenario) -> None:
    """Ten times the work drive's backlash (200 arcsec): the work motor M2's torque does reverse while cutting
    (the servo answers each engagement's torque pulse), so the play can be crossed; but the encoder sits on the
    spindle B2 (the play is inside the position loop) and the spindle with table and blank (0.15 kg m^2, 9x the
    motor's inertia referred to it) moves by only T t^2 / 2J while the motor crosses. Theory: the gear is the
    baseline's, every ISO parameter within 0.3 um, and the sync error the same within 0.1 um RMS."""
    _, rec, doc = scenario("work_backlash")
    _, base_rec, base = scenario("helical_mechatronic")
    m2 = rec.torque[rec.cutting, rec.actuators.index("M2")]
    assert m2.min() < 0.0 < m2.max(), (m2.min(), m2.max())
    assert abs(rec.sync_stats("cut")["rms_um"] - base_rec.sync_stats("cut")["rms_um"]) < 0.1
    for name, value in doc["iso1328"]["measured"].items():
        assert abs(value - base["iso1328"]["measured"][name]) < 0.3, name


def test_soft_tool_spindle_twists_inside_the_correction_loop(scenario) -> None:
    """A belt 10x softer (2e3 N m/rad, 142 Hz with the spindle): the mean cutting torque twists it by T/k, many
    micrometres at the cutter, but the encoder sits on the spindle B1, so the correction holds the mean phase
    (the mean sync error stays within 0.3 um). What it cannot hold is the dynamics: the load's changes ring the
    softer stage, the sync error's peak-to-peak and RMS grow by more than a tenth, and the helix moves by the change of
    the recorded drift (0.47 um predicted, 0.53 measured; within 0.1 um)."""
    job, rec, doc = scenario("soft_tool_spindle")
    _, base_rec, base = scenario("helical_mechatronic")
    k = job.machine.model["tool_drive"]["stiffness"]
    torque = abs(float(np.mean(rec.torque[rec.cutting, rec.actuators.index("M1")])))
    twist_um = torque / k * job.skiving.cutter.reference_diameter / 2 * 1e3  # at the cutter's reference circle
    stats, base_stats = rec.sync_stats("cut"), base_rec.sync_stats("cut")
    assert twist_um > 10 * abs(stats["mean_um"] - base_stats["mean_um"]) and twist_um > 3.0, twist_um
    assert abs(stats["mean_um"] - base_stats["mean_um"]) < 0.3
    # (the teeth entering and leaving change the load each tick: +16 % peak-to-peak, +19 % RMS about the mean)
    assert stats["peak_to_peak_um"] > 1.1 * base_stats["peak_to_peak_um"]
    assert stats["rms_about_mean_um"] > 1.1 * base_stats["rms_about_mean_um"]
    opposite, _ = helix_parts(doc, base)
    assert opposite == pytest.approx(predicted_helix_change(job, doc, rec, base_rec), abs=0.1)
