"""The Process registry and the Python API: every job kind has its process, the API and the CLI give the same
setting sheets, a stage a process does not have says which to use, and the package says what is public."""

from __future__ import annotations

import importlib
import json

import pytest
from checks import JOBS
from click.testing import CliRunner

import virtual_machine
from cutting.errors import InputError
from virtual_machine import PROCESSES, load_job, process_for, setup
from virtual_machine.cli import main

SHIPPED = sorted(JOBS.glob("*.toml")) + sorted((JOBS / "scenarios").glob("*.toml"))


def test_every_shipped_job_has_its_process() -> None:
    kinds = {load_job(p).kind for p in SHIPPED}
    assert kinds == {"skiving", "thread", "form_milling", "face_contour", "turning"} == set(PROCESSES)
    for kind, process in PROCESSES.items():
        assert process.kind == kind and process.title


@pytest.mark.parametrize("path", [JOBS / f"{n}.toml" for n in ("default", "thread_m12", "form_milled_crowned")])
def test_the_api_and_the_cli_give_the_same_setting_sheet(path) -> None:
    res = CliRunner().invoke(main, ["setup", str(path), "--json"])
    assert res.exit_code == 0, res.output
    sheet = setup(path)  # a path or a parsed job
    assert json.loads(res.output) == json.loads(sheet.json())
    assert setup(load_job(path)).data == sheet.data
    assert sheet.text.strip() and sheet.stage == "setup" and sheet.files == []
    with pytest.raises(AttributeError, match="no measurement"):
        _ = sheet.measurement


@pytest.mark.parametrize(
    ("job", "stage", "hint"),
    [
        ("thread_m12", "cut", "skive run"),
        ("vibration_turning", "cut", "skive run"),
        ("form_milled_crowned", "simulate", "skive run"),
    ],
)
def test_a_stage_the_process_does_not_have_names_the_one_to_use(tmp_path, job, stage, hint) -> None:
    j = load_job(JOBS / f"{job}.toml")
    with pytest.raises(InputError, match=hint):
        getattr(process_for(j), stage)(j, tmp_path)
    assert not any(tmp_path.iterdir())  # nothing written
    res = CliRunner().invoke(main, [stage, str(JOBS / f"{job}.toml"), "--out", str(tmp_path / "o")])
    assert res.exit_code == 2 and hint in res.output


def test_check_grades_only_gears(tmp_path) -> None:
    res = CliRunner().invoke(main, ["check", str(JOBS / "vibration_turning.toml"), "--max-class", "7"])
    assert res.exit_code == 2 and "grades gears by ISO 1328-1" in res.output


def test_the_package_says_what_is_public() -> None:
    # each public name is the API's own object, not a stand-in of the same name
    api = importlib.import_module("virtual_machine.api")
    for name in ("load_job", "setup", "simulate", "cut", "run", "measure", "study"):
        assert name in virtual_machine.__all__ and getattr(virtual_machine, name) is getattr(api, name)
    assert "PROCESSES" in virtual_machine.__all__
    assert virtual_machine.PROCESSES is importlib.import_module("virtual_machine.processes").PROCESSES
    for module in ("runtime.machine_run", "processes.skiving.run", "studies.pipeline"):  # the API keeps its names
        importlib.import_module(f"virtual_machine.{module}")
    assert callable(virtual_machine.run) and callable(virtual_machine.simulate) and callable(virtual_machine.study)


def test_a_bad_job_path_is_an_input_error() -> None:
    with pytest.raises(InputError, match="no such file"):
        setup(JOBS / "no_such_job.toml")
