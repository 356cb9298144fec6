"""The face-contour machine's reach (virtual_machine/reach/face.py): the shipped
coupling job is within it; a head speed above the head's top speed and a coupling larger than the table takes are
refused before the run, naming both figures and the [machine.model] key for a real machine's own."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest

from cutting.errors import InputError, MachineLimitError
from cutting.face_contour.slots import FaceCoupling
from machine_models.face_contour_machine import FaceMachineParams
from virtual_machine.job import load_job
from virtual_machine.processes.face_contour.cnc import simulate_face_contour
from virtual_machine.reach.face import check_face_reach

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"


def test_the_shipped_coupling_is_within_reach() -> None:
    job = load_job(JOBS / "face_coupling.toml")
    check_face_reach(job.coupling, FaceMachineParams(), job.process.tool_speed)  # no error
    assert FaceMachineParams().head_speed_limit == pytest.approx(500 * 2 * math.pi / 60, rel=1e-3)


def test_a_head_speed_above_the_top_speed_is_refused_before_the_run() -> None:
    with pytest.raises(InputError) as err:
        simulate_face_contour(FaceCoupling(), tool_rpm=600.0)  # before any model is built
    (problem,) = err.value.problems
    assert isinstance(err.value, MachineLimitError)  # the limit's key and figure, as every machine's reach says it
    assert problem.key == "machine.model.head_speed_limit"
    assert problem.value == pytest.approx(500 * 2 * math.pi / 60, rel=1e-3)
    assert "turns at 600 rpm, above its top speed 500 rpm" in problem.reason
    assert "a lower process.tool_speed" in problem.hint
    assert f"machine.model.head_speed_limit >= {600 * 2 * math.pi / 60:.3g} (rad/s)" in problem.hint
    faster = dataclasses.replace(FaceMachineParams(), head_speed_limit=70.0)
    check_face_reach(FaceCoupling(), faster, 600.0)  # the real machine's own limit holds it


def test_a_coupling_larger_than_the_table_takes_is_refused() -> None:
    # the default coupling (outer radius 60 mm: 120 mm) on a machine whose table takes 100 mm
    small = dataclasses.replace(FaceMachineParams(), workpiece_diameter_limit=0.1)
    with pytest.raises(InputError) as err:
        check_face_reach(FaceCoupling(), small, 150.0)
    (problem,) = err.value.problems
    assert problem.key == "machine.model.workpiece_diameter_limit"
    assert "120 mm exceeds what the table takes, 100 mm" in problem.reason and "coupling.outer_radius" in problem.hint
    assert "machine.model.workpiece_diameter_limit >= 0.12 (m)" in problem.hint
