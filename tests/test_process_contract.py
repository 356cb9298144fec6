"""Every registered process through the same checks (scikit-learn's check_estimator idea): its declaration, its
setting sheet, the stages it has, and the refusal of the stages it lacks and of the options its stages do not take,
each refused before anything is written."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
from checks import JOBS
from click.testing import CliRunner

from cutting.errors import InputError
from virtual_machine import PROCESSES, load_job
from virtual_machine.cli import main
from virtual_machine.processes.base import STAGES, Process
from virtual_machine.processes.options import StageOptions, option_flag

#: a shipped job of every kind
SHIPPED = {
    "skiving": "default.toml",
    "thread": "thread_m12.toml",
    "form_milling": "form_milled_crowned.toml",
    "face_contour": "face_coupling.toml",
    "turning": "vibration_turning.toml",
}
#: a value for every option any stage takes, to offer to the stages that do not take it
VALUES = {
    "structure": "mechanical",
    "balance_passes": True,
    "rrd": Path("run.rrd"),
    "duration": 0.1,
    "synchronization": "master-slave",
    "adaptive_correction": False,
    "edge": "involute",
    "workers": 2,
    "trajectory": Path("trajectory.npz"),
    "removal": "manifold",
    "mesh_tolerance": 5.0,
    "view": "rerun+http://127.0.0.1:9876/proxy",
}
CASES = sorted(PROCESSES.items())


def _all_options() -> set[str]:
    return {f.name for p in PROCESSES.values() for cls in p.stages.values() for f in dataclasses.fields(cls)}


def test_every_option_has_a_value_to_try() -> None:
    assert _all_options() == set(VALUES)


@pytest.mark.parametrize(("kind", "process"), CASES)
def test_the_process_declares_its_kind_stages_and_options(kind: str, process: Process) -> None:
    assert process.kind == kind and process.title and kind in SHIPPED
    assert set(process.stages) <= set(STAGES) and {"setup", "run"} <= set(process.stages)
    for stage, cls in process.stages.items():
        assert dataclasses.is_dataclass(cls) and issubclass(cls, StageOptions), (kind, stage)
        assert cls.__dataclass_params__.frozen
        # a stage it has is its own method, not the base's refusal
        assert getattr(type(process), stage) is not getattr(Process, stage), (kind, stage)
        assert process.options(stage) == cls()  # every option has a default


@pytest.mark.parametrize(("kind", "process"), CASES)
def test_the_setting_sheet_is_the_same_from_the_api_and_the_cli(kind: str, process: Process) -> None:
    path = JOBS / SHIPPED[kind]
    job = load_job(path)
    sheet = process.perform("setup", job)
    assert sheet.stage == "setup" and sheet.text.strip() and sheet.files == [] and sheet.out is None
    res = CliRunner().invoke(main, ["setup", str(path), "--json"])
    assert res.exit_code == 0, res.output
    assert json.loads(res.output) == json.loads(sheet.json())


@pytest.mark.parametrize(("kind", "process"), CASES)
def test_a_stage_the_process_lacks_is_refused_naming_what_to_use(kind: str, process: Process, tmp_path) -> None:
    job = load_job(JOBS / SHIPPED[kind])
    lacking = [s for s in STAGES if s not in process.stages]
    for stage in lacking:
        with pytest.raises(InputError) as err:
            process.perform(stage, job, tmp_path / "out")
        assert f"no `{stage}` stage" in str(err.value) and "skive " in str(err.value)
        res = CliRunner().invoke(main, [stage, str(JOBS / SHIPPED[kind]), "--out", str(tmp_path / "cli")])
        assert res.exit_code == 2 and f"no `{stage}` stage" in res.output
    assert not any(tmp_path.iterdir())  # nothing written


@pytest.mark.parametrize(("kind", "process"), CASES)
def test_an_option_a_stage_does_not_take_is_refused_naming_it_and_the_kind(
    kind: str, process: Process, tmp_path
) -> None:
    job = load_job(JOBS / SHIPPED[kind])
    for stage, cls in process.stages.items():
        taken = {f.name for f in dataclasses.fields(cls)}
        for option in sorted(set(VALUES) - taken):
            with pytest.raises(InputError) as err:
                process.perform(stage, job, tmp_path / "out", **{option: VALUES[option]})
            (problem,) = err.value.problems
            assert problem.key == option_flag(option) and repr(kind) in problem.reason and stage in problem.reason
    assert not any(tmp_path.iterdir())  # nothing written


def test_the_command_line_refuses_removal_on_a_turning_job(tmp_path) -> None:
    """`--removal manifold` on a turning job used to run as if it had not been said."""
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["run", str(JOBS / "vibration_turning.toml"), "--removal", "manifold", "--out", out])
    assert res.exit_code == 2 and "--removal" in res.output and "'turning'" in res.output
    assert not out.exists()


@pytest.mark.parametrize(
    ("stage", "bad", "key"), [("run", {"removal": "voxel"}, "--removal"), ("cut", {"edge": "x"}, "--edge")]
)
def test_an_option_value_no_stage_takes_is_refused(tmp_path, stage: str, bad: dict, key: str) -> None:
    job = load_job(JOBS / "default.toml")
    with pytest.raises(InputError) as err:
        PROCESSES["skiving"].perform(stage, job, tmp_path / "out", **bad)
    assert err.value.keys == [key] and not (tmp_path / "out").exists()
