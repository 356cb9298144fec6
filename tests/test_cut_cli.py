"""skive cut on a small job: files written, chips accounted, the gear measured."""

import json
import math

import pytest
import trimesh
from click.testing import CliRunner
from small_jobs import small_job

from virtual_machine.cli import main

SMALL_JOB = small_job()


def test_cut_writes_the_gear_and_its_measurement(tmp_path):
    job = tmp_path / "small.toml"
    job.write_text(SMALL_JOB)
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["cut", str(job), "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert (out / "gear.stl").stat().st_size > 10_000
    doc = json.loads((out / "measurement.json").read_text())
    c = doc["cut"]
    assert c["edge"] == "involute" and c["passages"] == len(c["chips"]) > 100
    assert 0 < c["sweep_error_um"] <= 4.0
    # the chips add up to the blank minus the gear: pi r_a^2 b - V(gear.stl), r_a = 10 mm, b = 2 mm (measured: 127.56
    # mm^3 of chips against 127.64, 0.07 %: the dexel quadrature and gear.stl's simplification)
    removed = sum(ch["volume_mm3"] for ch in c["chips"])
    balance = math.pi * 10.0**2 * 2.0 - trimesh.load(out / "gear.stl").volume
    assert removed > 100.0 and removed == pytest.approx(balance, rel=0.002)
    assert doc["thickness"]["span"]["W_k_mm"] > doc["thickness"]["span"]["W_k_nominal_mm"]  # chords leave material
    assert "4 <= b <= 1200" in res.output  # a 2 mm face is outside ISO 1328-1: said, not graded
