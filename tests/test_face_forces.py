"""Cutting forces on the face-contour machine (seed 004): the chip and the oblique model's forces per edge segment
against hand-worked values, the thrust's directions, the layer of the spark-out slot by slot, the force held over a
tick with its true impulse, the refusal of a feed the head motor cannot cut, and the known answer of the feedback:
on a machine whose head and work drives have known torsional stiffnesses (everything else rigid), run slowly, the
slot spacing changes by the drives' twists under the cutting torques, work twist - head twist / m, from slot to slot
where the spark-out's layers differ; on a soft infeed nut the force out of the face lifts the slot bottom by that
force over k; the run's forces section. Lengths in mm unless the name says um."""

from __future__ import annotations

import math
import tomllib
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from checks import oblique_factors

from cutting.errors import InputError
from cutting.face_contour.forces import FaceLoad, chip, element_forces, segments
from cutting.face_contour.slots import FaceCoupling, path_velocity, setting_angle, tool_frame
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


def test_chip_and_the_oblique_forces_at_m_match_the_hand_worked_values() -> None:
    """Plunge pass 500 of S = 0.005 (fixed control): the head has come down f = 500 S = 2.5 mm, the pass over the
    same slot one workpiece revolution before (pass 476) 2.38 mm, so at M the layer is m S = 0.12 mm under a tip 2.5
    mm below the face; V is horizontal and radial there (theta = 0), r = cos(lambda) u + sin(lambda) n in the tool
    plane's frame (u along it, n the tool axis), lambda = asin(52.5 / 3000) = 1.00273 deg the setting angle.

    The segments' geometry by hand (the plate's face normal to the head's turning, g = u at M): the tip edge along n
    cuts at rake 0 and inclination lambda; the flanks, along cos(kappa) z +- sin(kappa) n (kappa = 20 deg), at rake
    +-atan(tan(lambda) cos(kappa)) = +-0.94227 deg and inclination +-asin(sin(kappa) sin(lambda)) = +-0.34294 deg.
    With w = sin(lambda) u - cos(lambda) n (horizontal, normal to V): the tip's cut-surface normal into the element
    is z, its passive direction -w; the +n flank's normal (sin(kappa) cos(lambda) z + cos(kappa) w) / cos(lambda_s),
    its passive direction (cos(kappa) z - sin(kappa) cos(lambda) w) / cos(lambda_s); the -n flank's with w's sign
    turned.

    The forces (cutting/oblique.py's formulas, beta_a 30 deg; a 10 um edge: h_min 3 um, K_ce 10, K_te 17 N/mm):
    tip: h = 0.12 mm, b = 2 cos(lambda) = 1.99969 mm, tau_s = kc(0.12) / 3.07973 = 1183.37 N/mm^2, factors
    (3.46392, 1.99954, 0.02563): F_c, F_t, F_p = 979.04, 587.60, 7.09 N. Flanks: h = 0.12 sin 20 = 0.041042 mm over
    b = (2.5 - 0.06) / cos 20 x cos(lambda_s) = 2.59655 mm, tau_s = 1564.11 N/mm^2; the +n flank (3.39922, 1.88866,
    0.00871): 551.15, 335.94, 1.35 N; the -n flank (3.53081, 2.11664, -0.00881): 571.48, 371.16, -1.36 N. Sums:
    F_c 2101.66 N along -V, F_t 1294.70 N; the force out of the face 587.60 + 0.34197 (335.94 + 371.16) = 829.43 N;
    head torque R F_c cos(lambda) = 262.7 N m. The work torque is small but no longer nil: the flanks' rakes differ by
    1.9 deg, so their thrusts across the slot differ by 35 N, and the tip's passive force lies along the tool axis
    (below 1 % of the head torque)."""
    c = FaceCoupling(S=0.005)
    phi = 2 * math.pi * 500
    ch = chip(c, phi)
    assert float(ch.layer) == pytest.approx(0.12, rel=1e-9) and float(ch.d) == pytest.approx(2.5, rel=1e-9)
    lam, kappa = setting_angle(c), c.flank_angle
    a = phi / c.m
    u = np.array([math.cos(a - lam), math.sin(a - lam), 0.0])
    n = np.array([-math.sin(a - lam), math.cos(a - lam), 0.0])
    z = np.array([0.0, 0.0, 1.0])
    r, w = math.cos(lam) * u + math.sin(lam) * n, math.sin(lam) * u - math.cos(lam) * n
    v = path_velocity(c, phi)
    assert v / np.linalg.norm(v) == pytest.approx(r, abs=1e-8)  # V radial at M (central differences)
    lam_f = math.asin(math.sin(kappa) * math.sin(lam))
    gam_f = math.degrees(math.atan(math.tan(lam) * math.cos(kappa)))
    h_tip, h_flank = 0.12, 0.12 * math.sin(kappa)
    b_flank = (2.5 - 0.06) / math.cos(kappa) * math.cos(lam_f)
    tau_tip, tau_flank = (STEEL.kc11 * h**-STEEL.mc / oblique_factors(6.0, 0.0)[0] for h in (h_tip, h_flank))

    def segment(h: float, b: float, tau: float, gamma: float, lam_s: float) -> np.ndarray:
        f = np.array(oblique_factors(gamma, math.degrees(lam_s)))
        return f * tau * (h - 0.003) * b + np.array([10.0, 17.0, 0.0]) * b

    tip = segment(h_tip, 2.0 * math.cos(lam), tau_tip, 0.0, lam)
    plus = segment(h_flank, b_flank, tau_flank, gam_f, lam_f)
    minus = segment(h_flank, b_flank, tau_flank, -gam_f, -lam_f)
    total = tip + plus + minus
    assert total == pytest.approx([2101.66, 1294.70, 7.08], abs=0.01)  # the figures worked above
    cl = math.cos(lam_f)
    normal = {s: (math.sin(kappa) * math.cos(lam) * z + s * math.cos(kappa) * w) / cl for s in (1, -1)}
    passive = {s: (math.cos(kappa) * z - s * math.sin(kappa) * math.cos(lam) * w) / cl for s in (1, -1)}
    on_tool = -total[0] * r + tip[1] * z + tip[2] * w
    for s, seg in ((1, plus), (-1, minus)):
        on_tool = on_tool + seg[1] * normal[s] - seg[2] * passive[s]
    assert on_tool[2] == pytest.approx(829.43, abs=0.01)
    f = element_forces(c, STEEL, phi)
    assert (float(f.F_c), float(f.F_t), float(f.F_p)) == pytest.approx(tuple(total), rel=0.01)
    assert np.allclose(f.force, on_tool, rtol=0, atol=0.01 * np.linalg.norm(on_tool))
    assert float(f.lift) == pytest.approx(on_tool[2], rel=0.01)
    assert float(f.head_torque) == pytest.approx(c.R * 1e-3 * total[0] * math.cos(lam), rel=0.01)
    assert abs(float(f.work_torque)) < 0.01 * float(f.head_torque)
    # the section's area: the trapezoid between the two passes, layer (w + (2 d - layer) tan kappa)
    assert float(ch.area) == pytest.approx(0.12 * (2.0 + (5.0 - 0.12) * math.tan(math.radians(20))), rel=1e-12)


def test_the_thrust_pushes_the_element_out_of_the_face_and_off_the_slots_sides() -> None:
    """Along a plunge pass (S = 0.005, pass 500): wherever the element cuts, its thrust lifts the head (the force on
    the tool out of the face, +z, from the tip edge and both flanks) and the flanks' thrusts push it off the slot's
    sides, towards its centre line (their components along the tool axis n oppose each other, each towards the
    other flank); the cutting force is against V. The passive forces (along the edges' parts normal to V) are
    nonzero where the edges are inclined to V: on the tip edge the setting angle's inclination."""
    c = FaceCoupling(S=0.005)
    phi = 2 * math.pi * 500 + np.linspace(-0.06, 0.06, 121)
    f = element_forces(c, STEEL, phi)
    cut = f.F_c > 0
    assert cut.sum() > 60
    assert np.all(f.lift[cut] > 0.3 * f.F_c[cut]) and np.all(f.F_t[cut] > 0)
    v = path_velocity(c, phi)
    along_v = np.einsum("ij,ij->i", f.force, v / np.linalg.norm(v, axis=1, keepdims=True))
    assert np.all(along_v[cut] < -0.9 * f.F_c[cut])
    n = np.concatenate([tool_frame(c, phi)[1], np.zeros((len(phi), 1))], axis=1)
    plus, minus = segments(c, phi)[1:]
    assert np.all(np.einsum("ij,ij->i", plus.n, n) < 0) and np.all(np.einsum("ij,ij->i", minus.n, n) > 0)
    assert np.all(np.abs(segments(c, phi)[0].inclination - setting_angle(c)) < math.radians(0.5))
    assert np.all(f.F_p[cut] > 0)


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
    at MH (the heaviest pass's head torque, ~1600 N m, through the 1:6 stage; 265 N m measured): refused before the
    run, naming the motor, the torque and the feed that would do (0.00184 mm); that feed passes. The shipped job's
    feed (0.0017: 22.5 N m, where 0.002 needs 25.7 N m with the oblique model at the plate's 0 deg rake) keeps every
    motor within CUT_TORQUE_SHARE of its peak."""
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
    (T_w is small at M: V is radial there by the setting angle, so the cutting force's line passes through the
    work's axis; the flanks' thrusts across the slot, unequal by their working rakes, and the tip edge's passive force
    along the tool axis add -0.2..-0.3 N m, 0.4 % of the head's share).
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
    # (F_t,k+1 - F_t,k) r / k_w with the small tangential force at M, so it adds next to nothing to the spacing there
    # (below 1 % of the head's share). Along the pass T_w changes as V turns: over the pass's second half (after the
    # entry's transient, before the exit's) the work twist follows -T_w / k_w with slope 1 within 10 % (measured
    # 0.94-0.96; the work stage's lag, ~2 ms at 48 Hz, only offsets it), T_w the moment of the forces the machine
    # applied at the tips where they were: the head's twist (0.035 rad here) leaves each tip ~4 mm behind its
    # nominal place, where the force's components across the slot have another arm: k_w and the sign of the
    # work's share.
    for p, f in zip(loaded.passes, at_m, strict=True):
        i = int(np.argmin(np.abs(p.phi - 2 * math.pi * p.turn)))
        assert p.twist[i, 1] == pytest.approx(-float(f.head_torque) / k_h, rel=0.03)
        assert abs(p.twist[i, 0]) < 0.01 * abs(p.twist[i, 1]) / c.m
        cut = np.flatnonzero(element_forces(c, STEEL, p.phi).F_c > 0)
        late = cut[len(cut) // 2 : -len(cut) // 10]
        tip, force = p.tip[0, late], p.force[0, late]
        work_torque = -1e-3 * (tip[:, 0] * force[:, 1] - tip[:, 1] * force[:, 0])
        slope = np.polyfit(-work_torque / k_w, p.twist[late, 0], 1)[0]
        assert slope == pytest.approx(1.0, abs=0.10)


def test_the_runs_forces_section_reports_the_layers_forces_twists_and_spacing_change(tmp_path: Path) -> None:
    """`skive run` of the shipped job (the default machine, feed 0.0017): measurement.json's forces section has per
    slot the spark-out layer at M (the plunge reaches the depth at turn 3 / 0.0017 = 1764.7; slots 0-2's final
    passes are turns 1776-1778, over what turns 1752-1754 left: depth - S (turn - m) = 21.6, 19.9, 18.2 um), F_c
    (its mean over the cut the model's at M within 1 %, its peak where the element enters: the eccentric keeps the
    tip's path flat while the plate turns with the head, so the tip edge's working rake runs from -4 to +4 deg across
    the slot) and the thrust out of the face (the model's, 0.46 F_c), the drives' twists; the spacing with the
    forces and without them (2 pi / m on the same machine cutting air), their difference the spacing change; the
    report page shows the section."""
    from virtual_machine.processes.face_contour.stages import run_face_job

    job = parse_job(tomllib.loads(ASSET.read_text()), str(ASSET))
    doc = run_face_job(job, ASSET, tmp_path)
    f = doc["forces"]
    c = job.coupling
    assert [s["turn"] for s in f["slots"]] == [1776, 1777, 1778]
    assert [s["layer_um"] for s in f["slots"]] == pytest.approx([21.6, 19.9, 18.2], abs=1e-6)
    for s in f["slots"]:
        at_m = element_forces(c, STEEL, 2 * math.pi * s["turn"])
        assert s["F_c_mean_N"] == pytest.approx(float(at_m.F_c), rel=0.01)
        assert float(at_m.F_c) < s["F_c_peak_N"] < 1.1 * float(at_m.F_c)
        lift = np.sum([x.lift for x in cutting_load(job).passes(s["turn"])], axis=0)
        assert s["thrust_peak_N"] == pytest.approx(float(lift.max()), rel=1e-9)
        assert 0.4 < s["thrust_mean_N"] / s["F_c_mean_N"] < 0.5
        assert s["head_drive_twist_arcsec"] < 0  # the head lags its motor under the cut
    assert np.all(np.abs(f["spacing_without_forces_arcsec"]) < 1e-3)
    assert f["spacing_with_forces_arcsec"] == doc["spacing_arcsec"]
    change = (np.array(f["spacing_with_forces_arcsec"]) - f["spacing_without_forces_arcsec"]) * ARCSEC * c.L * 1e3
    assert f["spacing_change_um_at_L"] == pytest.approx(change.tolist(), rel=1e-9)
    assert np.all(np.array(f["spacing_change_um_at_L"]) < 0)  # thinner layers slot by slot: less lag
    assert "Cutting forces (16MnCr5)" in (tmp_path / "report.html").read_text()


def test_the_thrust_on_a_soft_nut_lifts_the_slot_bottom_by_its_force_over_k() -> None:
    """The depth's known answer: a machine whose only compliance is the infeed nut (k = 2e7 N/m, damped near
    critically), fixed control, S = 0.002, 10 rpm: the force out of the face (the tip edge's thrust and the flanks'
    upward parts, :attr:`ElementForce.lift`) pushes the head up by lift / k while the tip crosses M, so the slot
    bottom at M is that much shallower than on the same machine cutting air, slot by slot with the spark-out's
    layers (11 S and 10 S: 258.6 and 240.9 N, 12.93 and 12.04 um), within 5 %."""
    c = FaceCoupling(S=0.002)
    k = 2.0e7
    params = FaceMachineParams().stiff().with_overrides({"nut_stiffness": k, "nut_damping": 1.5e5})
    load = FaceLoad(c, STEEL, pass_window(c, 0.0))
    bottoms = []
    for ld in (load, None):
        record = simulate_face_contour(c, params, (1, 2), 10.0, load=ld, run_in=1)
        bottoms.append([float(np.interp(c.L, m.radii, m.bottom)) for m in measure_recorded(record)])
    shallower = (np.array(bottoms[0]) - bottoms[1]) * 1e3
    predicted = np.array([float(element_forces(c, STEEL, 2 * math.pi * p.turn).lift) for p in record.passes]) / k * 1e6
    assert predicted == pytest.approx([12.93, 12.04], abs=0.01)
    assert shallower == pytest.approx(predicted, rel=0.05)


def test_slaves_on_the_heads_encoder_keep_the_slots_where_the_head_really_is() -> None:
    """The shipped job's cut on the default machine (feed 0.0017): an element crossing a slot (7.6 ms, ~70 N m at
    the head) slows the head and twists its drive, so slaves that follow the head's *command* (seed 000's equal
    coordinates) move the slots by the head's lag: -4.9 arcsec spacing, bottoms -54 um convex (measured). Slaves on
    the cutter spindle's encoder (seed 001's master-slave) copy what the head does: the spacing error falls below a
    third of that (-1.0 arcsec measured) and the bottoms' convexity below half (-18 um); what is left is the slaves'
    tracking of the head's jerk (their 40-60 Hz speed loops). Without forces both masters cut the same flat slots
    (0.8 um)."""
    c = FaceCoupling(S=0.0017, control="eccentric")
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
