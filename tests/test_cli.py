"""The skive command line: the default job, JSON output and clear failures."""

import json
from pathlib import Path

from click.testing import CliRunner

from virtual_machine.cli import main

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"


def test_setup_default_job_prints_the_sheet():
    res = CliRunner().invoke(main, ["setup"])
    assert res.exit_code == 0, res.output
    assert "default.toml" in res.output and "z2 = 20 external" in res.output
    assert "structure: mechatronic" in res.output and "kx  = 2360" in res.output
    assert "cutting speed 58.3 m/min" in res.output


def test_setup_json_for_every_structure():
    for structure in ("mechanical", "hydraulic-differential", "hydraulic-shaft", "mechatronic"):
        res = CliRunner().invoke(
            main, ["setup", str(JOBS / "helical_internal.toml"), "--structure", structure, "--json"]
        )
        assert res.exit_code == 0, res.output
        data = json.loads(res.output)
        assert data["structure"] == structure
        assert data["geometry"]["shaft_angle_deg"] == 20.0
    spur = json.loads(CliRunner().invoke(main, ["setup", str(JOBS / "spur_external.toml"), "--json"]).output)
    assert spur["geometry"]["gear"]["lead_mm"] is None  # infinite lead of a spur gear is null in JSON


def test_setup_reports_bad_jobs_and_exits_2(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text((JOBS / "spur_external.toml").read_text().replace("teeth = 40", "teeth = 0"))
    res = CliRunner().invoke(main, ["setup", str(bad)])
    assert res.exit_code == 2
    assert "gear.teeth = 0" in res.output and "must be >= 5" in res.output
    res = CliRunner().invoke(main, ["setup", str(tmp_path / "missing.toml")])
    assert res.exit_code == 2 and "no such file" in res.output
    res = CliRunner().invoke(main, ["setup", str(JOBS / "thread_m12.toml"), "--structure", "hydraulic-shaft"])
    assert res.exit_code == 2 and "thread group" in res.output


def test_run_of_a_thread_job_measures_the_lead_the_lathe_cut(tmp_path):
    """skive run on seed 001's thread job: the lathe's stroke, and measurement.json with the lead of the thread the
    carriage's path cuts (master-slave: the slave lags its master by about one pulse, a constant lead offset)."""
    res = CliRunner().invoke(main, ["run", str(JOBS / "thread_m12.toml"), "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    doc = json.loads((tmp_path / "measurement.json").read_text())
    lead = doc["thread"]
    assert lead["lead_mm"] == 1.75 and lead["form"] == "master-slave"
    assert 0 < lead["peak_to_peak_um"] < 1.0 and abs(lead["drift_um"]) < 0.1  # a steady lead
    assert abs(lead["mean_um"]) < 10.0  # the slave's lag of about a pulse
