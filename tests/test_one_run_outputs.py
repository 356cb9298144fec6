"""A stage's outputs are all of one run: written into a staging folder and moved into place when complete, so a run
killed half-way leaves the previous outputs as they were; measurement.json names the SHA-256 of the solid it
measured; a folder holds one stage's files (the previous stage's manifest says which to remove)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from checks import ROOT
from click.testing import CliRunner
from small_jobs import small_job

from virtual_machine.cli import main
from virtual_machine.output.json_file import json_text
from virtual_machine.output.staging import MANIFEST, StagedOutputs, sha256_of


def _consistent(out: Path) -> dict:
    """measurement.json of ``out``, asserting it belongs to the gear.stl beside it."""
    doc = json.loads((out / "measurement.json").read_text())
    assert doc["solid_sha256"] == {"gear.stl": sha256_of(out / "gear.stl")}
    return doc


def test_staged_outputs_replace_the_previous_stage_and_name_their_final_place(tmp_path: Path) -> None:
    out = tmp_path / "out"
    with StagedOutputs(out) as first:
        (first.folder / "charts").mkdir()
        (first.folder / "charts" / "old.png").write_bytes(b"png")
        (first.folder / "gear.stl").write_bytes(b"solid one")
        (first.folder / "measurement.json").write_text(json.dumps({"mesh": str(first.folder / "gear.stl")}))
        data, text, files = first.publish({"mesh": str(first.folder / "gear.stl")}, f"wrote {first.folder}")
    assert data["mesh"] == str(out / "gear.stl") and text == f"wrote {out}"
    assert data["solid_sha256"]["gear.stl"] == sha256_of(out / "gear.stl")
    published = (out / "measurement.json").read_text()
    assert json.loads(published)["mesh"] == str(out / "gear.stl")
    assert published == json_text(json.loads(published))  # the format every JSON file has (indented, no NaN)
    assert sorted(f.name for f in files) == ["gear.stl", "measurement.json", "old.png"]
    (out / "notes.txt").write_text("the user's own file")
    with StagedOutputs(out) as second:
        (second.folder / "gear.stl").write_bytes(b"solid two")
        second.publish({}, "")
    assert not (out / "charts" / "old.png").exists() and not (out / "measurement.json").exists()
    assert (out / "gear.stl").read_bytes() == b"solid two" and (out / "notes.txt").is_file()
    assert json.loads((out / MANIFEST).read_text()) == ["gear.stl"]
    with pytest.raises(RuntimeError), StagedOutputs(out) as failed:  # a stage that fails publishes nothing
        (failed.folder / "gear.stl").write_bytes(b"half")
        raise RuntimeError("killed")
    assert (out / "gear.stl").read_bytes() == b"solid two" and not failed.folder.exists()


@pytest.mark.slow
def test_a_run_killed_during_its_measurement_leaves_the_previous_outputs(
    tmp_path: Path, tmp_path_factory: pytest.TempPathFactory
) -> None:
    """`skive cut` into o1, then `skive run` into o1 ended by SIGTERM while it measures: o1 still holds the cut's
    complete outputs (measurement.json of the gear.stl beside it), and no staging folder is left. The job is the
    tests' small one (z2 18, b 2 mm, one pass, coarse feed): what a stage leaves does not depend on the gear, and
    its cut and its run up to the measurement take about half the default job's time. The cut only makes the
    previous outputs: it runs in this process (the run, the one killed, in its own)."""
    out = tmp_path / "o1"
    job = tmp_path_factory.mktemp("job") / "small.toml"  # not in tmp_path: o1 is to be all it holds at the end
    job.write_text(small_job(sweep_error=0.02, axial_feed=0.4))
    done = CliRunner().invoke(main, ["cut", str(job), "--out", str(out)])
    assert done.exit_code == 0, done.output
    before = _consistent(out)
    env = {**os.environ, "CI": "1"}  # a line per stage on stderr
    cli = [sys.executable, "-m", "virtual_machine.cli"]
    run = subprocess.Popen(
        [*cli, "run", str(job), "--out", str(out)],
        env=env,
        cwd=ROOT,
        stderr=subprocess.PIPE,
        text=True,
    )
    for line in run.stderr:  # the stage lines: "measurement ..." once the machine has cut the gear
        if line.startswith("measurement"):
            time.sleep(0.2)
            run.send_signal(signal.SIGTERM)
            break
    assert run.wait(timeout=120) == 128 + signal.SIGTERM
    after = _consistent(out)
    assert after == before and "cut" in after and "run" not in after
    assert not (out / "report.html").exists()
    assert [p.name for p in tmp_path.iterdir()] == ["o1"]  # the staging folder went with the run
