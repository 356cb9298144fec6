"""Inputs a new user gets wrong: each is refused with a clear error naming the file, the key and what to do, exit 2,
and nothing written. And a spring pass (a radial increment of 0) is a valid pass, not a bad input."""

from __future__ import annotations

from pathlib import Path

import pytest
from checks import JOBS
from click.testing import CliRunner

from cutting.errors import InputError
from virtual_machine.cli import main
from virtual_machine.job import load_job

DEFAULT = JOBS / "default.toml"


def _job(tmp_path: Path, text: str | bytes, name: str = "job.toml") -> Path:
    path = tmp_path / name
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text)
    return path


def _with_passes(passes: list[float]) -> str:
    """The default job's text with ``process.passes`` replaced."""
    text = DEFAULT.read_text()
    start = text.index("passes = [")
    end = text.index("]", start) + 1
    return text[:start] + f"passes = {passes}" + text[end:]


def _refused(args: list[str], *phrases: str) -> str:
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2, res.output
    assert res.exception is None or isinstance(res.exception, SystemExit), res.exception  # no traceback
    for phrase in phrases:
        assert phrase in res.output, res.output
    return res.output


def test_a_drive_stage_given_a_number_is_refused_before_the_run(tmp_path: Path) -> None:
    """[machine.model] work_drive = 5 used to pass `skive setup` and crash the run (AttributeError)."""
    job = _job(tmp_path, DEFAULT.read_text() + "\n[machine.model]\nwork_drive = 5\n")
    out = tmp_path / "out"
    for command in (["setup", str(job)], ["run", str(job), "--out", str(out)]):
        _refused(command, str(job), "machine.model.work_drive", "[machine.model.work_drive]", "ratio, stiffness")
    assert not out.exists()


def test_a_machine_parameter_of_the_wrong_type_is_refused_by_its_key(tmp_path: Path) -> None:
    job = _job(tmp_path, DEFAULT.read_text() + '\n[machine.model]\nwork_inertia = "heavy"\n')
    _refused(["setup", str(job)], "machine.model.work_inertia", "must be a number")


def test_a_job_that_is_not_utf8_names_the_file_and_the_line(tmp_path: Path) -> None:
    text = DEFAULT.read_bytes().split(b"\n")
    text[4] = text[4] + b" \xff"  # line 5
    job = _job(tmp_path, b"\n".join(text))
    out = tmp_path / "out"
    _refused(["run", str(job), "--out", str(out)], str(job), "not UTF-8", "line 5", "save the file as UTF-8")
    assert not out.exists()


def test_a_model_that_is_not_a_table_says_how_to_write_one(tmp_path: Path) -> None:
    job = _job(tmp_path, DEFAULT.read_text().replace("[machine]\n", "[machine]\nmodel = 5\n"))
    output = _refused(["setup", str(job)], str(job), "machine.model = 5", "expected a table", "[machine.model]")
    assert "<class" not in output


def test_a_trajectory_that_is_not_an_npz_is_refused_before_the_cut(tmp_path: Path) -> None:
    bad = _job(tmp_path, "not a trajectory\n", "trajectory.npz")
    out = tmp_path / "out"
    output = _refused(
        ["cut", str(DEFAULT), "--trajectory", str(bad), "--out", str(out)],
        "--trajectory",
        str(bad),
        "not an npz archive",
        "skive simulate",
    )
    assert "pickle" not in output and not out.exists()


def test_a_study_whose_base_is_missing_names_the_base_key(tmp_path: Path) -> None:
    study = _job(
        tmp_path, 'base = "no_such_job.toml"\n[[vary]]\nkey = "machine.encoder_lines"\nvalues = [1000]\n', "s.toml"
    )
    out = tmp_path / "study"
    _refused(["study", str(study), "--out", str(out)], str(study), "base = 'no_such_job.toml'", str(tmp_path))
    assert not out.exists()


@pytest.mark.parametrize("passes", [[0.0, 2.25], [2.25, -0.1]])
def test_a_first_pass_of_zero_or_a_negative_one_is_refused(tmp_path: Path, passes: list[float]) -> None:
    job = _job(tmp_path, _with_passes(passes))
    with pytest.raises(InputError) as err:
        load_job(job)
    assert err.value.keys == ["process.passes"] and "spring pass" in str(err.value)


def test_a_spring_pass_is_a_pass_at_the_final_centre_distance(tmp_path: Path) -> None:
    """passes = [..., 0.0]: one more pass at the finishing pass's centre distance."""
    plain = load_job(DEFAULT).skiving
    spring = load_job(_job(tmp_path, _with_passes([*plain.passes, 0.0]))).skiving
    assert spring.pass_centre_distances[:-1] == plain.pass_centre_distances
    assert spring.pass_centre_distances[-1] == plain.pass_centre_distances[-1]
