"""The form-milling machine's reach (virtual_machine/reach/form_mill.py): the shipped jobs are within
it; a clearance that leaves no mill in the space, a stroke beyond the Z travel, a mill larger than the spindle
carries and a workpiece larger than the table takes are refused before the plan, naming what would hold them."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from small_jobs import job_from_text

from cutting.errors import InputError
from virtual_machine.job import load_job
from virtual_machine.processes.form_milling.stages import machine_params, plan_job
from virtual_machine.reach.form_mill import check_form_reach

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"
CROWNED = (JOBS / "form_milled_crowned.toml").read_text()


@pytest.mark.parametrize("name", ["form_milled_crowned", "form_milled_helical", "form_milled_internal"])
def test_the_shipped_form_milling_jobs_are_within_reach(name: str) -> None:
    job = load_job(JOBS / f"{name}.toml")
    check_form_reach(job, machine_params(job))  # no error


def test_a_finger_clearance_wider_than_the_space_is_refused(tmp_path: Path) -> None:
    # the job file refuses a disc's clearance past its form circle; the finger's is bounded here, before the plan
    job = load_job(JOBS / "form_milled_internal.toml")
    space = math.pi * job.gear.mn / math.cos(job.gear.helix_angle) / 2
    text = (JOBS / "form_milled_internal.toml").read_text()
    text = text.replace(f"clearance = {job.mill['clearance']:g}", f"clearance = {space + 0.1:.3f}")
    with pytest.raises(InputError) as err:
        plan_job(job_from_text(tmp_path, text))  # before any path is planned
    problem = err.value.problems[0]
    assert problem.key == "mill.clearance" and f"pi m_t / 2 = {space:.3f} mm" in problem.reason


def test_a_stroke_beyond_the_z_travel_and_an_oversize_mill_are_refused(tmp_path: Path) -> None:
    text = CROWNED.replace("face_width = ", "face_width = 9").replace("diameter = 50.0", "diameter = 300.0")
    job = job_from_text(tmp_path, text)
    with pytest.raises(InputError) as err:
        check_form_reach(job, machine_params(job))
    keys = {p.key: p for p in err.value.problems}
    assert set(keys) == {"machine.model.z_travel", "machine.model.mill_diameter_limit"}, err.value
    assert "exceeds the Z slide's travel 800 mm" in keys["machine.model.z_travel"].reason
    assert (
        "a mill of 300 mm exceeds what the spindle carries, 250 mm" in keys["machine.model.mill_diameter_limit"].reason
    )
    # the real machine's own figures, in [machine.model], hold it
    job = job_from_text(tmp_path, text + "\n[machine.model]\nz_travel = 2.0\nmill_diameter_limit = 0.3\n")
    check_form_reach(job, machine_params(job))
