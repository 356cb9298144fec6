"""The machine's reach (virtual_machine/reach/skiving.py): a job whose tool spindle or table speed
is above its machine's top speed, or whose stroke is beyond the carriage's travel, is refused before the run, naming
the element, both figures and what would hold it; every shipped skiving job is within its default machine's reach."""

from __future__ import annotations

from pathlib import Path

import pytest
from small_jobs import job_from_text

from cutting.errors import InputError
from machine_models.parameters import RPM, SkivingMachineParams
from machine_models.sizes import SIZES
from virtual_machine.job import load_job
from virtual_machine.reach.skiving import check_skiving_reach, machine_reach
from virtual_machine.runtime.machine_run import MachineRun
from virtual_machine.setting.machine_layout import machine_params, machine_size

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"
DEFAULT = (JOBS / "default.toml").read_text()


def _skiving_jobs() -> list[Path]:
    out = []
    for path in sorted([*JOBS.glob("*.toml"), *(JOBS / "scenarios").glob("*.toml")]):
        job = load_job(path)
        if job.kind == "skiving":  # not thread, form milling, face, turning
            out.append(path)
    return out


def test_the_limits_of_each_size() -> None:
    # small: 6000 / 3000 rpm, 1 m; the others by 1/k and k (k = table / 300 mm), to three significant figures
    small = SkivingMachineParams()
    assert small.tool_speed_limit == pytest.approx(6000 * RPM, rel=1e-3)
    assert small.work_speed_limit == pytest.approx(3000 * RPM, rel=1e-3)
    assert small.carriage_travel == 1.0
    for size in SIZES.values():
        k = size.scale
        assert size.params.tool_speed_limit == pytest.approx(small.tool_speed_limit / k, rel=5e-3), size.name
        assert size.params.work_speed_limit == pytest.approx(small.work_speed_limit / k, rel=5e-3), size.name
        assert size.params.carriage_travel == pytest.approx(small.carriage_travel * k, rel=5e-3), size.name


def test_what_the_default_job_needs_by_hand() -> None:
    # tool 3000 rpm; spur table at z0 / z2 = 17 / 20 of it: 2550 rpm; the stroke is the setup's pass travel
    job = load_job(JOBS / "default.toml")
    workpiece, module, tool, work, stroke = machine_reach(job, machine_params(job))
    assert workpiece.need == pytest.approx(0.022, rel=1e-12) and module.need == pytest.approx(1e-3, rel=1e-12)  # d_a2
    assert tool.need == pytest.approx(3000 * RPM, rel=1e-12)
    assert work.need == pytest.approx(2550 * RPM, rel=1e-9)
    assert stroke.need == pytest.approx(max(job.skiving.pass_travel) / 1e3, rel=1e-12)
    assert 4.0 < stroke.need * 1e3 < 20.0  # the 4 mm face, the run-in and run-out


@pytest.mark.parametrize("path", _skiving_jobs(), ids=lambda p: p.stem)
def test_every_shipped_skiving_job_is_within_its_machine(path: Path) -> None:
    job = load_job(path)
    reach = check_skiving_reach(job, machine_params(job), machine_size(job))
    assert all(r.holds for r in reach)


def test_a_tool_speed_above_the_spindles_top_speed_is_refused_before_the_run(tmp_path: Path) -> None:
    # 8000 rpm: above the small tool spindle's 6000 rpm, and the table's 6800 rpm above its 3000; a larger machine
    # turns slower, so the hint is a lower speed or the real machine's own limit
    job = job_from_text(tmp_path, DEFAULT.replace("tool_speed = 3000.0", "tool_speed = 8000.0"))
    with pytest.raises(InputError) as err:
        MachineRun(job)
    tool, table = err.value.problems
    assert tool.key == table.key == "machine.size" and tool.value == "small"
    for words in ("tool spindle B1 of the small machine", "at 8,000 rpm", "top speed 6,000 rpm"):
        assert words in tool.reason, tool.reason
    assert "table (work spindle B2)" in table.reason and "at 6,800 rpm" in table.reason, table.reason
    assert "a lower process.tool_speed" in tool.hint and "no larger machine size reaches it" in tool.hint
    assert f"machine.model.tool_speed_limit >= {8000 * RPM:.3g} (rad/s)" in tool.hint
    # the real machine's own limits, given in [machine.model], let it run
    faster = DEFAULT.replace("tool_speed = 3000.0", "tool_speed = 8000.0") + (
        f"\n[machine.model]\ntool_speed_limit = {9000 * RPM}\nwork_speed_limit = {7000 * RPM}\n"
    )
    job = job_from_text(tmp_path, faster)
    assert all(r.holds for r in check_skiving_reach(job, machine_params(job), machine_size(job)))


def test_a_stroke_beyond_the_carriages_travel_is_refused_naming_the_size_that_holds_it(tmp_path: Path) -> None:
    # a 1.2 m face on the small machine (1 m of travel) at 2000 rpm: the medium machine's 1.33 m holds it (its table
    # turns the gear's 1700 rpm; at the default job's 3000 rpm its 2250 rpm table would not, and no size would do)
    text = (
        DEFAULT.replace("face_width = 4.0", "face_width = 1200.0")
        .replace('structure = "mechatronic"', 'structure = "mechatronic"\nsize = "small"')
        .replace("tool_speed = 3000.0", "tool_speed = 2000.0")
    )
    job = job_from_text(tmp_path, text)
    with pytest.raises(InputError) as err:
        MachineRun(job)
    (problem,) = err.value.problems
    stroke = max(job.skiving.pass_travel)
    assert f"stroke (the face, the cutter's run-in and run-out) of {float(f'{stroke:.3g}'):,.0f} mm" in problem.reason
    assert "exceeds the travel 1,000 mm" in problem.reason and "carriage P3" in problem.reason
    assert problem.hint.startswith('use machine.size = "medium", or a narrower gear.face_width')
    medium = job_from_text(tmp_path, text.replace('size = "small"', 'size = "medium"'))
    assert all(r.holds for r in check_skiving_reach(medium, machine_params(medium), "medium"))


def test_a_limit_must_be_positive(tmp_path: Path) -> None:
    with pytest.raises(InputError) as err:
        job_from_text(tmp_path, DEFAULT + "\n[machine.model]\ncarriage_travel = 0.0\n")
    assert any("carriage_travel = 0.0: must be > 0" in p.reason for p in err.value.problems), err.value
    # and at 3000 rpm the same face has no size: the hint says so
    job = job_from_text(tmp_path, DEFAULT.replace("face_width = 4.0", "face_width = 1200.0"))
    with pytest.raises(InputError) as err:
        check_skiving_reach(job, machine_params(job), "small")
    assert "(no larger machine size reaches it)" in err.value.problems[0].hint


def test_a_gear_beyond_its_machines_class_is_refused_naming_the_size_that_takes_it(tmp_path: Path) -> None:
    # spur_external (d_a2 84 mm, mn 2) put on the small machine (80 mm, mn 1.5): the medium machine takes it
    text = (JOBS / "spur_external.toml").read_text()
    job = job_from_text(
        tmp_path, text.replace('structure = "mechatronic"', 'structure = "mechatronic"\nsize = "small"')
    )
    with pytest.raises(InputError) as err:
        check_skiving_reach(job, machine_params(job), "small")
    workpiece, module = err.value.problems
    assert "workpiece's 84 mm diameter exceeds what it takes, 80 mm" in workpiece.reason, workpiece.reason
    assert "module 2 mm exceeds what it is built for, 1.5 mm" in module.reason, module.reason
    assert workpiece.hint.startswith('use machine.size = "medium", or a smaller gear')
    # a gear beyond the largest size: no size takes it, and the real machine's own class may be given
    large = text.replace("normal_module = 2.0", "normal_module = 9.0")
    job = job_from_text(tmp_path, large)
    with pytest.raises(InputError) as err:
        check_skiving_reach(job, machine_params(job), machine_size(job))
    modules = [p for p in err.value.problems if "module 9 mm" in p.reason]
    assert modules and "(no larger machine size reaches it)" in modules[0].hint
