"""The lathe's reach (virtual_machine/reach/lathe.py): a thread or turning job whose spindle speed is above
the lathe's top speed, whose workpiece is over its swing, or whose stroke is beyond the carriage's travel is refused
before the stroke, naming the limit, both figures and what would hold it; a turning feed wider than the nose's cut
is refused with the job."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from small_jobs import job_from_text

from cutting.errors import InputError
from machine_models.parameters import RPM
from machine_models.thread_lathe import ThreadLatheParams
from virtual_machine.job import load_job
from virtual_machine.processes.turning.stages import lathe_params
from virtual_machine.reach.lathe import check_lathe_reach
from virtual_machine.runtime.lathe_run import simulate_thread
from virtual_machine.setting.thread_layout import thread_layout

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"
THREAD = (JOBS / "thread_m12.toml").read_text()
TURNING = (JOBS / "vibration_turning.toml").read_text()


def _refused(job) -> list:
    with pytest.raises(InputError) as err:
        simulate_thread(job)  # refused before the model is built
    return err.value.problems


def test_the_shipped_lathe_jobs_are_within_reach() -> None:
    for name in ("thread_m12", "vibration_turning"):
        job = load_job(JOBS / f"{name}.toml")
        params = lathe_params(job)
        check_lathe_reach(job, params, thread_layout(job, params), 1.0)  # no error
    lathe = ThreadLatheParams()
    assert lathe.spindle_speed_limit == pytest.approx(5000 * RPM, rel=1e-3)
    assert (lathe.swing_diameter, lathe.carriage_travel) == (0.32, 0.8)


def test_a_spindle_speed_above_the_top_speed_is_refused(tmp_path: Path) -> None:
    # M12 at 200 m/min: 200e3 / (pi 12) = 5305 rpm, above 5000 rpm
    job = job_from_text(tmp_path, THREAD.replace("cutting_speed = 90.0", "cutting_speed = 200.0"))
    (problem,) = _refused(job)
    assert problem.key == "machine.model.spindle_speed_limit"
    assert f"turns at {float(f'{200e3 / (math.pi * 12):.3g}'):,.0f} rpm" in problem.reason, problem.reason
    assert "above its top speed 5,000 rpm" in problem.reason
    assert problem.hint.startswith("use a lower process.cutting_speed")
    # the real lathe's own limit, in [machine.model], lets it run up to its stroke
    job = job_from_text(
        tmp_path,
        THREAD.replace("cutting_speed = 90.0", "cutting_speed = 200.0") + "\n[machine.model]\n"
        f"spindle_speed_limit = {6000 * RPM}\n",
    )
    params = lathe_params(job)
    check_lathe_reach(job, params, thread_layout(job, params), 0.1)


def test_a_workpiece_over_the_swing_and_a_stroke_beyond_the_travel_are_refused(tmp_path: Path) -> None:
    (problem,) = _refused(job_from_text(tmp_path, THREAD.replace("diameter = 12.0", "diameter = 400.0")))
    assert problem.key == "machine.model.swing_diameter"
    assert "400 mm diameter exceeds its swing 320 mm" in problem.reason and "thread.diameter" in problem.hint
    (problem,) = _refused(job_from_text(tmp_path, THREAD.replace("length = 30.0", "length = 900.0")))
    assert problem.key == "machine.model.carriage_travel"
    assert "exceeds the carriage's travel 800 mm" in problem.reason and "thread.length" in problem.hint
    longer = job_from_text(
        tmp_path, THREAD.replace("length = 30.0", "length = 900.0") + "\n[machine.model]\ncarriage_travel = 1.0\n"
    )
    params = lathe_params(longer)
    lay = thread_layout(longer, params)
    check_lathe_reach(longer, params, lay, 0.1)
    assert lay.length + 2 * lay.approach > 0.9  # the stroke it now holds


def test_a_turning_feed_wider_than_the_nose_cut_is_refused_with_the_job(tmp_path: Path) -> None:
    # r_eps 0.8, a_p 0.3: the nose's chord at the blank 2 sqrt(0.3 x 1.3) = 1.249 mm
    with pytest.raises(InputError) as err:
        job_from_text(tmp_path, TURNING.replace("feed = 0.2 ", "feed = 1.3 "))
    (problem,) = err.value.problems
    assert problem.key == "turning.feed" and problem.value == 1.3
    assert f"{2 * math.sqrt(0.3 * 1.3):.4g} mm" in problem.reason


def test_a_lathe_limit_must_be_positive(tmp_path: Path) -> None:
    with pytest.raises(InputError) as err:
        job_from_text(tmp_path, THREAD + "\n[machine.model]\nswing_diameter = 0.0\n")
    assert any("swing_diameter" in p.reason or "swing_diameter" in p.key for p in err.value.problems), err.value


def test_the_turning_report_says_when_the_solid_shows_no_crest() -> None:
    # a nose far wider than the feed leaves a surface without crests: the report said nothing and raised
    from virtual_machine.processes.turning.stages import solid_line

    solid = {"revolutions": 24, "sweep_error_um": 1.0, "Rt_max_um": 0.0}
    solid["largest_crest_difference_to_envelope_um"] = None
    assert solid_line(solid).endswith("Rt max 0.00 um, no crests to compare")
    solid["largest_crest_difference_to_envelope_um"] = 0.25
    assert solid_line(solid).endswith("crests within 0.25 um of the exact envelope")


def test_a_vibration_faster_than_the_servo_can_sample_is_refused(tmp_path: Path) -> None:
    # 40 mm at 25 m/min: 199 rpm, 3.32 rev/s; the 4 kHz servo samples 20 times a cycle up to 200 Hz: 60.3 per rev
    from virtual_machine.processes.turning.stages import simulate_turning

    job = job_from_text(tmp_path, TURNING.replace("cycles_per_rev = 2.25", "cycles_per_rev = 80.25"))
    with pytest.raises(InputError) as err:
        simulate_turning(job)
    (problem,) = err.value.problems
    assert problem.key == "vibration.cycles_per_rev" and "(at most 60.3 here)" in problem.hint, problem
