"""Cutting forces of vibration turning (seed 004) on the lathe of seed 001: the uncut chip of the
round nose against the sampled envelope, the oblique model's forces of plain turning against the hand-worked values
and the thrust's direction, the force falling to zero where the vibration breaks the chip, the carriage's deflection
under the feed force against F_f / k_axial, the crests with and without forces, the spindle motor's refusal and bad
inputs.

Tolerances: the closed-form chip section against a 10 nm sampled integral 1e-8 mm^2 (measured ~5e-12); the forces
1 % (the brief), on the model and on the lathe; the nut's stretch 10 % of F_f / k_axial, the carriage's path 10 %
(the feed servo's share)."""

from __future__ import annotations

import dataclasses
import math
import tomllib

import numpy as np
import pytest
from checks import oblique_factors
from small_jobs import turning_job

from cutting.errors import InputError
from cutting.materials import material
from cutting.turning.forces import (
    NoseGeometry,
    TurningForces,
    chip_arc,
    chip_area,
    chip_section,
    path_forces,
    reach_turns,
)
from cutting.turning.vibration import TWO_PI, FeedVibration, TurningSetup, crest_height
from machine_models.thread_lathe import ThreadLatheParams
from metrology.turned_surface import roughness
from virtual_machine.job import parse_job
from virtual_machine.processes.turning.stages import simulate_summary, simulate_turning

S0, R_EPS, DEPTH, R0 = 0.2, 0.8, 0.3, 20.0
PLAIN = TurningSetup(R0, S0, R_EPS, DEPTH)
HARD = dataclasses.replace(PLAIN, vibration=FeedVibration(0.2, 2.25, 3.0, "hard"))
NOSE = NoseGeometry(R0, R_EPS, DEPTH)
STEEL = material("16MnCr5")

VIBRATION = '[vibration]\namplitude = 0.2\ncycles_per_rev = 2.25\nxi = 3.0\nform = "hard"\n'


def job(vibration: str = "", revs: int = 8, model: str = "", material: str = "16MnCr5"):
    text = turning_job(vibration, revs, process=f'material = "{material}"', machine=model)
    return parse_job(tomllib.loads(text), "turning.toml")


def hand_worked() -> tuple[float, float, float, float]:
    """Plain turning by hand with the oblique model. The chip: A = S0 a_p less the crest's scallop,
    int_{-S0/2}^{S0/2} u^2 / (2 r_eps) du = S0^3 / (24 r_eps) (the parabola of the nose); the engaged arc from the
    crest (u_1 = -S0 / 2 from the nose's centre, asin(S0 / 2 r_eps) behind the tip) to r0 (u_2 = u0 =
    sqrt(r_eps^2 - (r_eps - a_p)^2) ahead, acos(1 - a_p / r_eps)), b = r_eps (acos(1 - a_p / r_eps) + asin(S0 / 2
    r_eps)); h = A / b. 16MnCr5 (kc1.1 2100 N/mm^2, mc 0.26): A = 0.0595833 mm^2, b = 0.816794 mm, h = 72.948 um,
    kc(h) = 2100 h^-0.26 = 4147.97 N/mm^2.

    The model (cutting/oblique.py's formulas, beta_a 30 deg): the table's tool (rake 6 deg, lambda 0) has
    phi_n = 33 deg, K_c / tau = cos 24 / (sin 33 cos 57) = 3.07973, so tau_s = 4147.97 / 3.07973 = 1346.86 N/mm^2;
    the nose (rake 0, lambda 0): phi_n = 30 deg, f_c = cos 30 / (sin 30 cos 60) = 3.46410, f_t = sin 30 /
    (sin 30 cos 60) = 2, f_p = 0. Edge 10 um (the default): h_min = 3 um, K_ce = 10, K_te = 17 N/mm.
    F_c = (tau f_c (h - h_min) + K_ce) b = (1346.86 x 3.46410 x 0.069948 + 10) x 0.816794 = 274.73 N; the thrust
    per unit arc q = tau f_t (h - h_min) + K_te = 205.42 N/mm, its axial sum F_f = q (sqrt(r_eps^2 - u_1^2) -
    sqrt(r_eps^2 - u_2^2)) = q (0.793725 - 0.5) = 60.34 N (against the feed), its radial sum F_p = q (u_2 - u_1) =
    q x 0.724500 = 148.83 N (off the work). Returns (F_c, F_f, F_p [N], A [mm^2])."""
    area = S0 * DEPTH - S0**3 / (24 * R_EPS)
    edge = R_EPS * (math.acos(1 - DEPTH / R_EPS) + math.asin(S0 / (2 * R_EPS)))
    h = area / edge
    tau = STEEL.kc11 * h ** (-STEEL.mc) / oblique_factors(6.0, 0.0)[0]
    f_c, f_t, _ = oblique_factors(0.0, 0.0)
    h_min, k_ce, k_te = 0.3 * 0.010, 10.0, 17.0
    q = tau * f_t * (h - h_min) + k_te
    u1, u2 = -S0 / 2, math.sqrt(R_EPS**2 - (R_EPS - DEPTH) ** 2)
    f_f = q * (math.sqrt(R_EPS**2 - u1**2) - math.sqrt(R_EPS**2 - u2**2))
    return (tau * f_c * (h - h_min) + k_ce) * edge, f_f, q * (u2 - u1), area


def hand_worked_fc() -> float:
    return hand_worked()[0]


def sampled_area(z: float, previous: list[float], dz: float = 1e-5) -> float:
    """The chip by brute force: the surface min(r0, every earlier nose circle) less the new nose circle, where
    positive, summed every ``dz`` [mm] (10 nm)."""
    zz = np.arange(z - R_EPS, z + R_EPS, dz)
    rc = R0 - DEPTH + R_EPS

    def circle(c: float) -> np.ndarray:
        u = zz - c
        return np.where(np.abs(u) < R_EPS, rc - np.sqrt(np.maximum(R_EPS**2 - u * u, 0.0)), np.inf)

    surface = np.full(len(zz), R0)
    for c in previous:
        surface = np.minimum(surface, circle(c))
    return float(np.clip(surface - circle(z), 0.0, None).sum() * dz)


# --- the model --------------------------------------------------------------------------------------------


def test_chip_section_is_the_area_between_the_nose_and_the_earlier_surface():
    """Random noses and earlier passes (behind, ahead, coincident, none): the closed form against the sampled
    envelope, the loop's scalar form against the vectorised one."""
    rng = np.random.default_rng(28)
    for _ in range(60):
        z = float(rng.uniform(-0.3, 0.3))
        prev = list(rng.uniform(-1.2, 0.8, size=int(rng.integers(0, 5))))
        if rng.random() < 0.3:
            prev.append(z - S0)
        if rng.random() < 0.1:
            prev.append(z)  # the nose on an earlier pass: no chip
        grid = np.array(prev if prev else [np.nan])[None, :]
        section = chip_section(NOSE, np.array([z]), grid)
        assert section.area[0] == pytest.approx(sampled_area(z, prev), abs=1e-8)
        behind = max((p for p in prev if p <= z), default=-math.inf)
        ahead = min((p for p in prev if p > z), default=math.inf)
        area, edge = chip_area(NOSE, z, behind, ahead)
        assert area == pytest.approx(section.area[0], abs=1e-12) and edge == pytest.approx(section.edge[0], abs=1e-12)
        if z in prev:
            assert area == 0.0


def test_plain_turning_forces_are_the_oblique_models_on_the_hand_worked_chip():
    fc, ff, fp, area = hand_worked()
    assert (fc, ff, fp) == pytest.approx((274.73, 60.34, 148.83), abs=0.01)  # the figures worked above
    theta = np.linspace(0.0, TWO_PI, 37) + TWO_PI * reach_turns(PLAIN)
    model = TurningForces(NOSE, STEEL)
    section, forces = path_forces(PLAIN, model, theta)
    assert section.area == pytest.approx(np.full(37, area), rel=1e-3)
    assert forces == pytest.approx(np.tile([fc, ff, fp], (37, 1)), rel=0.01)
    assert model.scalar(*chip_arc(NOSE, 0.0, -S0, math.inf)) == pytest.approx(forces[0], rel=1e-12)  # the loop's
    assert model.spindle_torque(fc) == pytest.approx(fc * (R0 - DEPTH / 2) * 1e-3)


def test_the_thrust_pushes_the_nose_off_the_work_normal_to_the_chord_of_its_engaged_arc():
    """The thrust of every element of the nose points from the cut surface to the nose's centre: against the feed
    (F_f > 0) and radially off the work (F_p > 0), their resultant at the angle (psi_1 + psi_2) / 2 from the radial
    direction (normal to the chord of the engaged arc, psi = asin(u / r_eps)); the model has no passive component
    along the edge here (no inclination). A deeper cut engages the nose further up its side and turns the thrust
    towards the feed axis; a sharp edge (no ploughing) takes less thrust for the same chip."""
    theta = TWO_PI * (reach_turns(PLAIN) + np.array([0.0, 0.5]))
    turn = []
    for depth in (0.1, 0.3, 0.6):
        setup, nose = dataclasses.replace(PLAIN, depth=depth), NoseGeometry(R0, R_EPS, depth)
        section, f = path_forces(setup, TurningForces(nose, STEEL), theta)
        assert np.all(f[:, 1] > 0) and np.all(f[:, 2] > 0)
        mid = (np.arcsin(section.start / R_EPS) + np.arcsin(section.end / R_EPS)) / 2
        assert f[:, 1] / f[:, 2] == pytest.approx(np.tan(mid), rel=1e-9)
        turn.append(math.degrees(mid[0]))
    # (-asin(0.125) + acos(1 - a_p / r_eps)) / 2: (-7.18 + 28.96) / 2, (-7.18 + 51.32) / 2, (-7.18 + 75.52) / 2 deg
    assert turn == pytest.approx([10.89, 22.07, 34.17], abs=0.01)
    sharp = path_forces(PLAIN, TurningForces(NOSE, STEEL, edge_radius=0.0), theta)[1]
    honed = path_forces(PLAIN, TurningForces(NOSE, STEEL), theta)[1]
    assert np.all(sharp[:, 2] < honed[:, 2])


def test_the_force_drops_to_zero_where_the_vibration_breaks_the_chip():
    """Hard xi = 3 at 2.25 cycles/rev breaks the chip 2.25 times a turn (cutting/turning/vibration.py): at each break
    the nose meets the foremost earlier pass, its cell is empty, A = 0; while it runs behind that pass it only
    shaves the crest between the two earlier passes it lies between, A <= h(Delta) Delta."""
    model = TurningForces(NOSE, STEEL)
    breaks = HARD.chip_breaks(24)
    assert breaks.per_rev == pytest.approx(2.25, abs=0.05)
    section, forces = path_forces(HARD, model, breaks.angles)
    assert np.all(section.area < 1e-9) and np.all(forces[:, 0] < 1e-3)  # [mm^2], [N]: zero to the roots' 1e-12 rad
    theta = TWO_PI * (8 + np.arange(4 * 3600) / 3600)
    section, forces = path_forces(HARD, model, theta)
    behind = np.asarray(HARD.uncut_thickness(theta)) <= 0
    assert 0.1 < behind.mean() < 0.3  # a fifth of the time behind the foremost pass
    delta_max = HARD.spacing_range()[1]
    assert section.area[behind].max() <= crest_height(delta_max, R_EPS, DEPTH) * delta_max
    assert forces[behind, 0].max() < 0.1 * forces[:, 0].mean()
    assert forces[~behind, 0].min() >= 0.0 and forces[:, 0].max() > 1.3 * hand_worked_fc()  # thicker chips too


# --- on the lathe -------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def plain_run():
    return simulate_summary(job())


def test_the_lathe_cuts_plain_turning_with_the_hand_worked_force(plain_run):
    doc, rec, _ = plain_run
    f = doc["forces"]
    fc, ff, fp, _ = hand_worked()
    assert f["F_c_N"]["mean"] == pytest.approx(fc, rel=0.01)
    assert f["F_c_N"]["peak"] == pytest.approx(fc, rel=0.01)  # steady: the carriage keeps S0 a turn
    assert f["F_f_N"]["mean"] == pytest.approx(ff, rel=0.01) and f["F_p_N"]["mean"] == pytest.approx(fp, rel=0.01)
    torque = fc * (R0 - DEPTH / 2) * 1e-3
    assert f["spindle_torque_Nm"]["mean"] == pytest.approx(torque, rel=0.01)
    assert f["torque_share_of_motor_peak"] == pytest.approx(
        f["spindle_torque_Nm"]["peak"] / ThreadLatheParams().spindle_motor_torque
    )
    assert rec.force is not None and np.all(rec.force[rec.t < ThreadLatheParams().runup_time] == 0)  # engages after
    assert f["F_c_N"]["min"] == pytest.approx(fc, rel=0.01) and f["crest_shaving_share"] == 0.0


def test_the_forces_load_the_motors(plain_run):
    """Fed back through mj_applyFT: the spindle motor M1 (belt 1:1) carries F_c (r0 - a_p / 2) = 5.45 N m more than
    without the cut, the feed motor M2 (screw 1:1) F_f t_TV / (2 pi) = 60 N x 1.59 mm/rad = 0.096 N m more (both
    steady means after the run-up; the feed runs towards -z, so M2's torque grows negative)."""
    from virtual_machine.setting.thread_layout import thread_layout

    _, rec, _ = plain_run
    rec0, _ = simulate_turning(job(), forces=False)
    cut = rec.t > ThreadLatheParams().runup_time + 0.1
    fc, ff = rec.force[cut, 0].mean(), rec.force[cut, 1].mean()
    extra = rec.torque[cut].mean(axis=0) - rec0.torque[cut].mean(axis=0)
    lay = thread_layout(job(), ThreadLatheParams())
    assert extra[0] == pytest.approx(fc * (R0 - DEPTH / 2) * 1e-3, rel=0.01)
    assert extra[1] == pytest.approx(lay.hand_sign * ff * lay.screw_lead, rel=0.02)


def test_the_carriage_yields_to_the_feed_force_by_its_axial_stiffness(plain_run):
    """The feed servo holds the lead screw's angle (its encoder 12 sits on the screw), so what yields between it and
    the tool is the nut stage (nut, screw, thrust bearing: k_axial = nut_stiffness, 2e8 N/m): the carriage stays
    F_f / k_axial = 60 N / 200 N/um = 0.30 um further back than without the cut."""
    doc, _, _ = plain_run
    c = doc["forces"]["carriage"]
    expected = doc["forces"]["F_f_N"]["mean"] / ThreadLatheParams().nut_stiffness * 1e6
    assert c["F_f_over_k_axial_um"] == pytest.approx(expected)
    assert c["nut_deflection_um"] == pytest.approx(expected, rel=0.10)
    assert c["path_deflection_um"] == pytest.approx(expected, rel=0.10)


def test_a_steady_deflection_leaves_the_plain_crests_alone(plain_run):
    """Every pass pushed back alike: the paths keep S0 apart, the crests stay h(S0) = 6.275 um."""
    cr = plain_run[0]["forces"]["crests_um"]
    h = crest_height(S0, R_EPS, DEPTH) * 1e3
    assert cr["with_forces"]["Rt_max"] == pytest.approx(h, abs=0.05)
    assert abs(cr["difference"]["Rt_max"]) < 0.01 and abs(cr["difference"]["mean"]) < 0.01


def test_vibration_crests_with_forces_differ_by_what_the_run_reports():
    """The force follows the vibration (0 where the chip breaks, up to 1.5 F_c of plain turning), so the nut's
    stretch differs from pass to pass and so do the paths' distances Delta; the crests change by dh/dDelta =
    Delta / (4 sqrt(r_eps^2 - Delta^2 / 4)) times that, at most Delta_max / (4 r_eps) (2 max |dz|) (dz the path's
    change by the forces). The report's difference is the crests of the two paths measured apart."""
    hard = job(VIBRATION, revs=12)
    doc, _, path = simulate_summary(hard)
    f = doc["forces"]
    assert f["F_c_N"]["peak"] > 1.3 * f["F_c_N"]["mean"] and f["F_c_N"]["min"] < 0.01 * f["F_c_N"]["peak"]
    assert 0.1 < f["crest_shaving_share"] < 0.3
    _, free = simulate_turning(hard, forces=False)
    n = min(12, path.revolutions)
    with_f, without = roughness(path, 72, n), roughness(free, 72, n)
    d = f["crests_um"]["difference"]
    assert d["Rt_max"] == pytest.approx((with_f.rt_max - without.rt_max) * 1e3, abs=1e-9)
    assert d["mean"] == pytest.approx((with_f.crest_mean - without.crest_mean) * 1e3, abs=1e-9)
    assert f["crests_um"]["with_forces"]["Rt_max"] == pytest.approx(doc["machine"]["Rt_max_um"], abs=1e-9)
    dz = float(np.max(np.abs(np.interp(path.theta, free.theta, free.z) - path.z))) * 1e3  # [um]
    bound = HARD.spacing_range()[1] / (4 * R_EPS) * 2 * dz
    assert 0.0 < abs(d["Rt_max"]) <= bound, (d, dz, bound)


def test_a_spindle_motor_too_weak_for_the_cut_refuses_the_job_before_the_run(monkeypatch):
    """Plain turning needs F_c (r0 - a_p / 2) = 5.45 N m at the spindle, 6.45 N m at M1 with the bearings' 1 N m."""
    import virtual_machine.runtime.lathe_run as thread_run

    def no_run(*args, **kwargs):
        raise AssertionError("the lathe ran")

    monkeypatch.setattr(thread_run, "simulate_thread", no_run)
    with pytest.raises(InputError) as info:
        simulate_summary(job(model="[machine.model]\nspindle_motor_torque = 4.0\n"))
    need = hand_worked_fc() * (R0 - DEPTH / 2) * 1e-3 + ThreadLatheParams().spindle_friction
    text = str(info.value)
    assert info.value.keys == ["machine.model.spindle_motor_torque"]
    assert "M1" in text and f"{need:.1f} N m" in text and f">= {math.ceil(need)}" in text


def test_bad_inputs_name_what_is_wrong():
    with pytest.raises(InputError) as info:
        simulate_summary(job(material="unobtainium"))
    assert info.value.keys == ["process.material"] and "16MnCr5" in str(info.value)
    with pytest.raises(ValueError, match="beyond the nose"):
        NoseGeometry(R0, 0.8, 0.9)
    with pytest.raises(ValueError, match="rake"):
        TurningForces(NOSE, STEEL, rake=2.0)
    with pytest.raises(ValueError, match="edge_radius"):
        TurningForces(NOSE, STEEL, edge_radius=-0.01)
