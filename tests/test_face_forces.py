"""Cutting forces on the face-contour machine (seed 004): the chip and Kienzle's force against a hand-worked value, the
layer of the spark-out slot by slot, the force held over a tick with its true impulse, the refusal of a feed the
head motor cannot cut, and the known answer of the feedback: on a machine whose head and work drives have known
torsional stiffnesses (everything else rigid), run slowly, the slot spacing changes by the drives' twists under the
cutting torques, work twist - head twist / m, from slot to slot where the spark-out's layers differ; on a soft
infeed nut the thrust lifts the slot bottom by F_p / k; the run's forces section. Lengths in mm unless the name
says um."""

from __future__ import annotations

import math
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from cutting.errors import InputError
from cutting.face_contour.forces import THRUST_RATIO, FaceLoad, chip, element_forces
from cutting.face_contour.slots import FaceCoupling, path_velocity, setting_angle
from cutting.materials import material
from machine_models.face_contour_machine import FaceMachineParams
from machine_models.parameters import ARCSEC
from metrology.face_slots import slot_spacing
from virtual_machine.job import parse_job
from virtual_machine.processes.face_contour.cnc import measure_recorded, pass_window, simulate_face_contour
from virtual_machine.processes.face_contour.stages import cutting_load, machine_params
from virtual_machine.reach.face import CUT_TORQUE_SHARE, check_cutting_load

STEEL = material("16MnCr5")  # kc1.1 = 2100 N/mm^2, mc = 0.26
ASSET = Path(__file__).resolve().parent.parent / "assets" / "jobs" / "face_coupling.toml"


def test_chip_and_kienzle_force_at_m_match_the_hand_worked_values() -> None:
    """Plunge pass 500 of S = 0.005 (fixed control): the head has come down f = 500 S = 2.5 mm, the pass over the
    same slot one workpiece revolution before (pass 476) 2.38 mm, so at M the layer is m S = 0.12 mm under a tip 2.5
    mm below the face; V is horizontal there (theta = 0). By hand: tip edge 2 mm x 0.12 mm, kc = 2100 x 0.12^-0.26
    -> 874.7 N; each flank h = 0.12 sin 20 deg = 0.04104 mm over (2.5 - 0.06) / cos 20 deg = 2.5966 mm -> 513.4 N;
    F_c = 1901.4 N along -V, thrust 0.4 F_c up; head torque R F_c cos lambda (V radial at M, the tool plane at
    lambda), no torque on the work (the force's line passes through the axis)."""
    c = FaceCoupling(S=0.005)
    phi = 2 * math.pi * 500
    ch = chip(c, phi)
    assert float(ch.layer) == pytest.approx(0.12, rel=1e-9) and float(ch.d) == pytest.approx(2.5, rel=1e-9)
    h_flank = 0.12 * math.sin(math.radians(20))
    b_flank = (2.5 - 0.06) / math.cos(math.radians(20))
    tip = 2100 * 2.0 * 0.12**0.74
    flank = 2100 * b_flank * h_flank**0.74
    hand = tip + 2 * flank
    assert hand == pytest.approx(1901.4, abs=0.1)  # the hand-worked figure above
    f = element_forces(c, STEEL, phi)
    assert float(f.F_c) == pytest.approx(hand, rel=0.01)
    assert float(f.F_p) == pytest.approx(THRUST_RATIO * hand, rel=0.01)
    v = path_velocity(c, phi)
    assert np.allclose(f.force, -float(f.F_c) * v / np.linalg.norm(v) + [0, 0, float(f.F_p)], rtol=0, atol=1e-6)
    assert float(f.head_torque) == pytest.approx(c.R * 1e-3 * hand * math.cos(setting_angle(c)), rel=0.01)
    assert abs(float(f.work_torque)) < 1e-6 * float(f.head_torque)
    # the section's area: the trapezoid between the two passes, layer (w + (2 d - layer) tan kappa)
    assert float(ch.area) == pytest.approx(0.12 * (2.0 + (5.0 - 0.12) * math.tan(math.radians(20))), rel=1e-12)


def test_the_spark_out_layer_falls_by_s_per_slot_and_the_element_cuts_only_the_face() -> None:
    """The plunge reaches the depth at turn D = depth / S = 600; the pass at turn D + k (slot (D + k) mod m) removes
    what the pass m turns earlier left: S (m - k) at M, down to nothing after one workpiece revolution. Off the
    annulus (the tip's radius outside inner..outer radius) nothing is cut."""
    c = FaceCoupling(S=0.005)
    for k in (0, 1, 5, 23, 24, 30):
        assert float(chip(c, 2 * math.pi * (600 + k)).layer) == pytest.approx(c.S * max(c.m - k, 0), abs=1e-12)
    phi = 2 * math.pi * 601 + np.linspace(-0.2, 0.2, 401)
    f = element_forces(c, STEEL, phi)
    radius = np.linalg.norm(f.tip[:, :2], axis=-1)
    assert np.all(f.F_c[(radius < c.inner_radius) | (radius > c.outer_radius)] == 0)
    assert np.all(f.F_c[(radius > c.inner_radius + 0.1) & (radius < c.outer_radius - 0.1)] > 0)


def test_the_held_force_carries_the_ticks_impulse_across_the_entry() -> None:
    """FaceLoad.at(phi, dphi): the mean over the tick's head angles, also across the step where the tip enters the
    face at the inner radius (checked against a fine average of the model, within 0.5 %)."""
    c = FaceCoupling(S=0.005)
    load = FaceLoad(c, STEEL, pass_window(c, 0.0))
    turn = 601
    phi = 2 * math.pi * turn + np.linspace(-0.1, 0.0, 2001)
    fc = element_forces(c, STEEL, phi).F_c
    entry = phi[np.argmax(fc > 0)]
    dphi = 1e-3
    start = entry - 0.3 * dphi  # the tick starts before the entry and ends after it
    fine = np.linspace(start, start + dphi, 4001)
    mean = element_forces(c, STEEL, fine).force.mean(axis=0)
    held = load.at(start, dphi)[0]
    assert np.linalg.norm(held - mean) < 0.005 * np.linalg.norm(mean)
    assert load.at(2 * math.pi * turn + 1.0, dphi) is None  # between the passes: no force


def test_a_feed_the_head_motor_cannot_cut_is_refused_and_the_shipped_job_is_cuttable() -> None:
    """The old shipped feed, 0.05 mm per tool revolution (a 1.2 mm layer per pass on 24 slots), needs over 200 N m
    at MH (the heaviest pass's head torque, ~1300 N m, through the 1:6 stage): refused before the run, naming the
    motor, the torque and the feed that would do; that feed passes. The shipped job's feed keeps every motor within
    CUT_TORQUE_SHARE of its peak."""
    c = replace(FaceCoupling(), control="eccentric", e=FaceCoupling().flat_bottom_eccentricity())
    load = FaceLoad(c, STEEL, pass_window(c, 0.0))
    params = FaceMachineParams()
    with pytest.raises(InputError, match=r"coupling.feed.*of MH, beyond 80% of its 30 N m peak") as err:
        simulate_face_contour(c, params, slots=(0,), load=load)
    text = str(err.value)
    needed = float(text.split("needs ")[1].split(" N m")[0])
    local = np.linspace(*load.window, 801)
    heaviest = max(float(np.max(element_forces(c, STEEL, 2 * math.pi * t + local).head_torque)) for t in (59, 60, 61))
    assert needed == pytest.approx(heaviest * params.head_drive.ratio, abs=0.1)  # the head torque at MH
    assert needed > 5 * params.h_motor_torque
    feed = float(text.split("a feed of ")[1].split(" mm")[0])
    assert 0 < feed < c.S
    ok = replace(c, S=feed * 0.999)
    check_cutting_load(ok, FaceLoad(ok, STEEL, load.window), params)

    job = parse_job(tomllib.loads(ASSET.read_text()), str(ASSET))
    size = check_cutting_load(job.coupling, cutting_load(job), machine_params(job))
    assert size["MH"]["needed_N_m"] <= CUT_TORQUE_SHARE * size["MH"]["peak_N_m"]
    assert size["MH"]["F_c_N"] > 100  # the shipped job does cut: several hundred newtons


def _spacing_um(record, c: FaceCoupling) -> np.ndarray:
    return slot_spacing(c, measure_recorded(record)) * c.L * 1e3


def test_the_drives_twists_under_the_cutting_torques_give_the_slot_spacing() -> None:
    """The known answer of the feedback. A machine with a soft head drive (k_h = 2000 N m/rad, damped near
    critically so the entry's step does not ring) and a soft work drive (k_w = 5e4 N m/rad), everything else rigid
    and frictionless; S = 0.002, 10 rpm (quasi-static: the tip crosses the face in 0.11 s), the final passes over
    slots 1-3 in the spark-out (turns 1513-1515: layers 11 S, 10 S, 9 S at M). Slot k is cut where the head's real
    angle passes 2 pi k; its twist then is -T_h / k_h (T_h the cutting torque against its turning), the work's
    -T_w / k_w (A turns about -z, T_w about +z), so the work stands at a = (2 pi k + T_h / k_h) / m - T_w / k_w: the
    slot is shifted by T_h / (k_h m) - T_w / k_w, and the spacing from slot k to k + 1 changes by the difference
    (T_w is ~0 at M: V is radial there by the setting angle, so the force's line passes through the work's axis).
    Predicted from the force model at M, measured (metrology.face_slots on the recorded motion) as the spacing with
    the forces less the spacing without them on the same machine: within 10 %."""
    c = FaceCoupling(S=0.002)
    k_h, k_w = 2000.0, 5.0e4
    params = (
        FaceMachineParams()
        .stiff()
        .with_overrides(
            {
                "head_drive.stiffness": k_h,
                "head_drive.damping": 35.0,
                "work_drive.stiffness": k_w,
                "h_motor_torque": 200.0,
            }
        )
    )
    slots, rpm = (1, 2, 3), 10.0
    load = FaceLoad(c, STEEL, pass_window(c, 0.0))
    loaded = simulate_face_contour(c, params, slots, rpm, load=load)
    free = simulate_face_contour(c, params, slots, rpm)
    assert [p.turn for p in loaded.passes] == [1513, 1514, 1515]
    at_m = [element_forces(c, STEEL, 2 * math.pi * p.turn) for p in loaded.passes]
    assert [float(f.chip.layer) for f in at_m] == pytest.approx([11 * c.S, 10 * c.S, 9 * c.S], abs=1e-9)
    shift = np.array([float(f.head_torque) / (k_h * c.m) - float(f.work_torque) / k_w for f in at_m])
    predicted = np.diff(shift) * c.L * 1e3  # um at radius L
    measured = _spacing_um(loaded, c) - _spacing_um(free, c)
    assert np.all(np.abs(_spacing_um(free, c)) < 1e-3)  # without forces the spacing is 2 pi / m
    assert np.all(predicted < -5.0)  # each slot's layer is S thinner: the head lags less, the slot moves back
    assert measured == pytest.approx(predicted, rel=0.10)
    # the twists as recorded when the tip passes M: the head's within 3 % of T_h / k_h; the work's is the brief's
    # (F_t,k+1 - F_t,k) r / k_w with the tangential force F_t = 0 at M, so it adds nothing to the spacing there
    # (below 1 % of the head's share). Along the pass T_w grows as V turns (+-0.15 N m at the slot's ends): over the
    # pass's second half (a ramp, after the entry's transient) the work twist follows -T_w / k_w with slope 1 within
    # 5 % (the work stage's lag, ~2 ms at 48 Hz, only offsets it): k_w and the sign of the work's share.
    for p, f in zip(loaded.passes, at_m, strict=True):
        i = int(np.argmin(np.abs(p.phi - 2 * math.pi * p.turn)))
        assert p.twist[i, 1] == pytest.approx(-float(f.head_torque) / k_h, rel=0.03)
        assert abs(p.twist[i, 0]) < 0.01 * abs(p.twist[i, 1]) / c.m
        along = element_forces(c, STEEL, p.phi)
        cut = np.flatnonzero(along.F_c > 0)
        late = cut[len(cut) // 2 :]
        slope = np.polyfit(-along.work_torque[late] / k_w, p.twist[late, 0], 1)[0]
        assert slope == pytest.approx(1.0, abs=0.05)


def test_the_runs_forces_section_reports_the_layers_forces_twists_and_spacing_change(tmp_path: Path) -> None:
    """`skive run` of the shipped job (the default machine, feed 0.002): measurement.json's forces section has per
    slot the spark-out layer at M (12 S, 11 S, 10 S for slots 0-2: turns 1512-1514, 1500 + 12 turns into the
    spark-out), F_c and thrust (thrust / F_c = THRUST_RATIO), the drives' twists; the spacing with the forces and
    without them (2 pi / m on the same machine cutting air), their difference the spacing change; the report page
    shows the section."""
    from virtual_machine.processes.face_contour.stages import run_face_job

    job = parse_job(tomllib.loads(ASSET.read_text()), str(ASSET))
    doc = run_face_job(job, ASSET, tmp_path)
    f = doc["forces"]
    c = job.coupling
    assert [s["turn"] for s in f["slots"]] == [1512, 1513, 1514]
    assert [s["layer_um"] for s in f["slots"]] == pytest.approx([12e3 * c.S, 11e3 * c.S, 10e3 * c.S], abs=1e-6)
    for s in f["slots"]:
        assert s["thrust_peak_N"] == pytest.approx(THRUST_RATIO * s["F_c_peak_N"], rel=1e-9)
        assert s["F_c_peak_N"] > s["F_c_mean_N"] > 100
        assert s["head_drive_twist_arcsec"] < 0  # the head lags its motor under the cut
    assert np.all(np.abs(f["spacing_without_forces_arcsec"]) < 1e-3)
    assert f["spacing_with_forces_arcsec"] == doc["spacing_arcsec"]
    change = (np.array(f["spacing_with_forces_arcsec"]) - f["spacing_without_forces_arcsec"]) * ARCSEC * c.L * 1e3
    assert f["spacing_change_um_at_L"] == pytest.approx(change.tolist(), rel=1e-9)
    assert np.all(np.array(f["spacing_change_um_at_L"]) < 0)  # thinner layers slot by slot: less lag
    assert "Cutting forces (16MnCr5)" in (tmp_path / "report.html").read_text()


def test_the_thrust_on_a_soft_nut_lifts_the_slot_bottom_by_f_p_over_k() -> None:
    """The depth's known answer: a machine whose only compliance is the infeed nut (k = 2e7 N/m, damped near
    critically), fixed control, S = 0.002, 10 rpm: the thrust F_p = THRUST_RATIO F_c pushes the head up by F_p / k
    while the tip crosses M, so the slot bottom at M is that much shallower than on the same machine cutting air,
    slot by slot with the spark-out's layers (11 S and 10 S: about 11.6 and 10.7 um), within 5 %."""
    c = FaceCoupling(S=0.002)
    k = 2.0e7
    params = FaceMachineParams().stiff().with_overrides({"nut_stiffness": k, "nut_damping": 1.5e5})
    load = FaceLoad(c, STEEL, pass_window(c, 0.0))
    bottoms = []
    for ld in (load, None):
        record = simulate_face_contour(c, params, (1, 2), 10.0, load=ld, run_in=1)
        bottoms.append([float(np.interp(c.L, m.radii, m.bottom)) for m in measure_recorded(record)])
    shallower = (np.array(bottoms[0]) - bottoms[1]) * 1e3
    predicted = np.array([float(element_forces(c, STEEL, 2 * math.pi * p.turn).F_p) for p in record.passes]) / k * 1e6
    assert predicted == pytest.approx([11.6, 10.7], abs=0.1)
    assert shallower == pytest.approx(predicted, rel=0.05)


def test_slaves_on_the_heads_encoder_keep_the_slots_where_the_head_really_is() -> None:
    """The shipped job's cut on the default machine: an element crossing a slot (7.6 ms, ~80 N m at the head) slows
    the head and twists its drive, so slaves that follow the head's *command* (seed 000's equal coordinates) move the
    slots by the head's lag: -5.1 arcsec spacing, bottoms -61 um convex (measured). Slaves on the cutter spindle's
    encoder (seed 001's master-slave) copy what the head does: the spacing error falls below a third of that (-1.0
    arcsec measured) and the bottoms' convexity below half (-23 um); what is left is the slaves' tracking of the
    head's jerk (their 40-60 Hz speed loops). Without forces both masters cut the same flat slots (0.8 um)."""
    c = FaceCoupling(S=0.002, control="eccentric")
    c = replace(c, e=c.flat_bottom_eccentricity())  # the setting sheet's e, as the shipped job takes it
    load = FaceLoad(c, STEEL, pass_window(c, 0.0))
    got = {}
    for master in ("generator", "head"):
        rec = simulate_face_contour(c, FaceMachineParams(), slots=(0, 1), tool_rpm=150.0, load=load, master=master)
        ms = measure_recorded(rec)
        got[master] = (np.abs(slot_spacing(c, ms)).max() / ARCSEC, min(m.form for m in ms))
    (gen_spacing, gen_form), (head_spacing, head_form) = got["generator"], got["head"]
    assert gen_spacing > 3.0 and gen_form < -0.04
    assert head_spacing < gen_spacing / 3 and head_form > gen_form / 2
    free = simulate_face_contour(c, FaceMachineParams(), slots=(0,), tool_rpm=150.0, master="head")
    assert abs(measure_recorded(free)[0].form) < 2e-3
