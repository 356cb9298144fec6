"""The machine's thermal drift (cutting/skiving/thermal_drift.py, virtual_machine/job/thermal_section.py; issue 43):
the lumps' first-order response, the job's thermal state, and the drift's known answer on the gear."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from small_jobs import small_job

from cutting.errors import InputError
from cutting.skiving.edge import make_edge
from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.thermal_drift import Lump, ThermalDrift
from cutting.skiving.trajectory import ideal_passes
from metrology.measure import measure_gear
from virtual_machine.job import parse_job
from virtual_machine.output.model_scope import model_scope
from virtual_machine.runtime.machine_run import relative_pose


def job_with(machine: str = "", thermal: str = "", face_width: float = 8.0):
    """The small job (z 18, mn 1, one pass at 2000 rpm) with [machine] lines and [machine.model.thermal] lines."""
    text = small_job(edge=None, face_width=face_width) + f"\n[machine]\n{machine}\n"
    if thermal:
        text += f"\n[machine.model.thermal]\n{thermal}\n"
    return parse_job(tomllib.loads(text))


#: the tool head's drift along x alone, at the small job's tool speed
ONLY_X = """
tool_head_growth_x = {growth}
tool_head_time_constant = {tau_min}
tool_head_growth_axial = 0.0
tool_head_tilt = 0.0
tool_head_reference_speed = 2000.0
work_spindle_growth_axial = 0.0
work_spindle_growth_x = 0.0
structure_growth_x = 0.0
"""


def test_a_heat_step_grows_first_order_with_the_lumps_time_constant() -> None:
    """Known answer: a lump heated by a step from cold grows as G (1 - exp(-t / tau)); the time it takes to reach
    1 - 1/e of its growth is tau within 2 % (measured against a fine explicit integration of tau dtheta/dt = u - theta,
    independent of the model's closed form), and a heat pulse (on, then off) decays from where it stood."""
    tau, growth = 600.0, 0.012  # 10 min, 12 um
    pulse = ((0.0, (1.0,)), (900.0, (0.0,)))
    drift = ThermalDrift((Lump("head", tau, (growth, 0.0, 0.0, 0.0)),), (0.0,), pulse, (0.0,))
    t = np.linspace(0.0, 3000.0, 30001)
    x = drift.offsets(t)[:, 0]
    theta, integrated = 0.0, [0.0]  # explicit Euler at 0.1 s
    for k in range(1, len(t)):
        u = 1.0 if t[k - 1] < 900.0 else 0.0
        theta += (t[k] - t[k - 1]) / tau * (u - theta)
        integrated.append(theta * growth)
    assert np.abs(x - np.array(integrated)).max() < 1e-4 * growth
    reach = float(np.interp((1 - math.exp(-1)) * growth, x[t < 900.0], t[t < 900.0]))
    assert reach == pytest.approx(tau, rel=0.02)
    assert x[t == 900.0][0] == pytest.approx(growth * (1 - math.exp(-1.5)), rel=1e-9)
    assert x[-1] == pytest.approx(growth * (1 - math.exp(-1.5)) * math.exp(-2100.0 / tau), rel=1e-9)


def test_the_jobs_thermal_state_sets_the_start() -> None:
    """Cold: no drift at the start; warm: the steady state of running the job without end (the spindles' inputs,
    (n / n_ref)^p); hours since a cold start: 1 - exp(-h / tau) of it, lump by lump; no key, no table: no model (the
    setup bit for bit the exact machine's)."""
    cold = job_with('thermal_state = "cold"').skiving.thermal
    assert np.abs(cold.offsets(0.0)).max() == 0.0
    warm_job = job_with('thermal_state = "warm"', "structure_growth_x = 0.0")
    warm = warm_job.skiving.thermal
    u_tool, u_work = 2000.0 / 5000.0, warm_job.skiving.work_speed / 1000.0
    expected_x = (5.0 * u_tool + 3.0 * u_work) * 1e-3  # tool head's and work spindle's x at their defaults [mm]
    assert warm.offsets(0.0)[0, 0] == pytest.approx(expected_x, rel=1e-12)
    assert warm.offsets(0.0)[0, 3] == pytest.approx(50e-6 * u_tool, rel=1e-12)  # Grama et al.'s 50 urad at 5000 rpm
    hours = job_with("thermal_state = 0.5", "structure_growth_x = 0.0").skiving.thermal
    head, work = (1 - math.exp(-30.0 / 20.0)), (1 - math.exp(-30.0 / 40.0))
    assert hours.offsets(0.0)[0, 0] == pytest.approx((5.0 * u_tool * head + 3.0 * u_work * work) * 1e-3, rel=1e-12)
    assert job_with().skiving.thermal is None and job_with().thermal is None


@pytest.mark.parametrize(
    ("machine", "thermal", "key", "words"),
    [
        ('thermal_state = "hot"', "", "machine.thermal_state", "cold"),
        ("thermal_state = -2.0", "", "machine.thermal_state", ">= 0 hours"),
        ("", "tool_head_time_constant = 0.0", "machine.model.thermal.tool_head_time_constant", "> 0"),
        ("", "cutting_heat_share = 1.5", "machine.model.thermal.cutting_heat_share", "[0, 1]"),
        ("", "tool_head_growth = 5.0", "machine.model.thermal.tool_head_growth", "did you mean"),
    ],
)
def test_a_bad_thermal_model_is_refused_naming_the_key(machine: str, thermal: str, key: str, words: str) -> None:
    with pytest.raises(InputError) as err:
        job_with(machine, thermal)
    text = str(err.value)
    assert key in text and words in text, text


def test_the_run_adds_the_drift_at_each_instant_and_the_cut_per_pass() -> None:
    """The simulated machine's poses (relative_pose at machine times t) carry the drift at t; the ideal kinematics'
    pass carries it as its own geometry (the drift at the stroke's middle and its rate), within the linearisation's
    bound (the curve's bow over the stroke: T / (8 tau) of the drift's change over it)."""
    job = job_with('thermal_state = "cold"', ONLY_X.format(growth=200.0, tau_min=10.0 / 60.0))
    st = job.skiving
    motion = ideal_passes(st)[-1]
    t_stroke = np.linspace(0.0, motion.duration, 21)
    t_machine = st.thermal.pass_starts[-1] + t_stroke
    phi0, s = motion.cutter_angle(t_stroke), motion.carriage(t_stroke)
    q = np.stack(
        [phi0, st.speed_ratio * phi0 + st.differential_rotation_per_mm * s, s, np.full_like(s, motion.centre_distance)],
        -1,
    )
    exact = st.thermal.offsets(t_machine)
    _, still = relative_pose(st, q)
    _, moved = relative_pose(st, q, None, t_machine)
    turn = q[:, 1] + st.work_phase  # the drift is in the machine's axes; the poses in the turning blank's frame
    shift = np.stack([np.cos(turn) * exact[:, 0], -np.sin(turn) * exact[:, 0]], -1)
    assert np.abs(moved[:, :2] - still[:, :2] - shift).max() < 1e-12
    _, cut = motion.pose(t_stroke)
    bound = st.thermal.linearisation_um(motion.index, motion.duration) * 1e-3
    assert np.abs(cut - moved).max() <= bound + 1e-9
    t_over_tau = motion.duration / 10.0  # the stroke's time over tau: 0.21
    assert 0 < bound <= 1.05 * t_over_tau / 8 * (exact[-1, 0] - exact[0, 0])  # 1/8 T / tau of the change


def test_the_centre_distance_growing_through_the_finishing_pass_tapers_the_helix() -> None:
    """Known answer: the tool head drifting along x while the finishing stroke crosses the face moves each flank by
    sin(alpha_n) times the drift where the stroke generates it: a helix slope sin(alpha_n) (a(t_1) - a(t_0)) on both
    flanks (a taper), t_0 and t_1 the instants the carriage passes the helix evaluation range's ends, the drift from
    the model's own closed form. Within 10 % on the small spur job (tau 10 s against a 2.1 s stroke, 200 um at the
    job's speed: -6.64 um predicted, measured -6.72 / -6.71 um)."""
    job = job_with('thermal_state = "cold"', ONLY_X.format(growth=200.0, tau_min=10.0 / 60.0))
    st = job.skiving
    motion = ideal_passes(st)[-1]
    exact = SweptVolumes(st.gear, make_edge(st, "conjugate"), [motion])
    measured = measure_gear(exact, st.gear)
    lo, hi = measured["evaluation"]["helix_z_mm"]
    t0 = st.thermal.pass_starts[-1]
    at = [t0 + (z - motion.s_start) / motion.v_s for z in (lo, hi)]  # where the carriage is at z
    drift = st.thermal.offsets(np.array(at))[:, 0] * 1e3
    expected = math.sin(st.gear.alpha_n) * (drift[1] - drift[0])
    for side in ("left", "right"):
        slope = measured["helix"][side]["f_Hbeta_mean"]
        assert slope == pytest.approx(expected, rel=0.10), (side, slope, expected)
    assert abs(expected) > 3.0  # a slope well above the cut's own (0.1 um)


def test_the_scope_lists_the_thermal_model_and_its_drift() -> None:
    job = job_with("thermal_state = 2.0")
    scope = model_scope(job, kind="cut")
    keys = {it["key"] for it in scope["included"]}
    assert "machine.thermal_state" in keys and "machine.model.thermal.tool_head_time_constant" in keys
    assert not any("thermal drift" in it["source"] for it in scope["not_included"])
    bare = model_scope(job_with(), kind="cut")
    assert any("thermal drift" in it["source"] for it in bare["not_included"])


def test_the_thermal_keys_are_study_keys() -> None:
    """A study varies the thermal model like any job key: the base value is the figure's default (or the job's), the
    state's "cold"; a misspelt key names the valid ones."""
    from virtual_machine.studies.spec import base_value

    data = tomllib.loads(small_job(edge=None))
    assert base_value(data, "machine.model.thermal.tool_head_time_constant") == 20.0
    assert base_value(data, "machine.thermal_state") == "cold"
    with pytest.raises(InputError, match=r"machine\.model\.thermal\.tool_head_tilt"):
        base_value(data, "machine.model.thermal.tool_tilt")


def test_the_reports_thermal_chart_draws_the_drift_over_the_job(tmp_path) -> None:
    """report.html's chart of the drift (virtual_machine/output/report.py: thermal_chart) is drawn from the job's own
    drift over its program, the strokes shaded."""
    from virtual_machine.output.report import thermal_chart

    st = job_with('thermal_state = "cold"', ONLY_X.format(growth=200.0, tau_min=10.0 / 60.0)).skiving
    motion = ideal_passes(st)[-1]
    start = st.thermal.pass_starts[-1]
    png = thermal_chart(tmp_path / "thermal.png", st.thermal, [(start, start + motion.duration)], start + 3.0)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 5_000
