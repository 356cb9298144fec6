"""The skive command line: the default job, JSON output and clear failures."""

import json
import math
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


def test_setup_json_for_every_structure(tmp_path: Path) -> None:
    """Every structure's sheet of the helical internal job (z2 = 60, beta2 = +20 deg, spur cutter: Sigma = 20 deg) as
    JSON, and a spur gear's infinite lead as null. `setup` maps the cutter's working angles on every pass (seconds
    per pass of a full-size gear), which neither claim depends on: helical_internal.toml runs in one full-depth pass
    instead of four, and the spur gear is the default job's (z2 = 20, mn 1) instead of spur_external.toml's."""
    text = (JOBS / "helical_internal.toml").read_text()
    assert "passes = [2.0, 1.5, 0.8, 0.2]" in text
    job = tmp_path / "helical_internal.toml"
    job.write_text(text.replace("passes = [2.0, 1.5, 0.8, 0.2]", "passes = [4.5]"))  # 2.25 mn: the same depth
    for structure in ("mechanical", "hydraulic-differential", "hydraulic-shaft", "mechatronic"):
        res = CliRunner().invoke(main, ["setup", str(job), "--structure", structure, "--json"])
        assert res.exit_code == 0, res.output
        data = json.loads(res.output)
        assert data["structure"] == structure
        assert data["geometry"]["shaft_angle_deg"] == 20.0
    spur = json.loads(CliRunner().invoke(main, ["setup", str(JOBS / "default.toml"), "--json"]).output)
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
    carriage's path cuts (master-slave: the slave lags its master by a constant offset, a phase of the thread).

    Bounds from the setting sheet and the lathe: kx is realised exactly, so the lead drifts by eps x travel = 0 up to
    one count of the master's encoder (P / counts = 1.75 mm / 20000 = 0.09 um); the correction module holds the
    slave within one command pulse of its reference (t_TV / (i0 p) = 10 mm / 10000 = 1 um), so the lead error varies
    by less than that; the slave's encoder sits on the screw, so its lag is what that loop cannot see or resolve:
    half the nut's play (2.5 um), the nut's and the screw's give under the ways' friction (0.40 + 0.07 um), a command
    pulse and a count of its encoder (1 + 0.5 um): 4.5 um (measured 3.9 um; 1.0 um on the stiff lathe)."""
    from machine_models.thread_lathe import ThreadLatheParams

    res = CliRunner().invoke(main, ["run", str(JOBS / "thread_m12.toml"), "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    doc = json.loads((tmp_path / "measurement.json").read_text())
    lead = doc["thread"]
    assert lead["lead_mm"] == 1.75 and lead["form"] == "master-slave"
    sheet = json.loads(CliRunner().invoke(main, ["setup", str(JOBS / "thread_m12.toml"), "--json"]).output)
    kx, k = sheet["realisation"]["kx"], sheet["constants"]
    pulse_um = k["t_tv"] / (k["i0"] * k["p_cmd"]) * 1e3  # carriage per command pulse of M2
    count_um = lead["lead_mm"] / kx["encoder_counts_per_rev"] * 1e3  # carriage per count of the master's encoder
    travel = doc["run"]["travel_mm"]
    assert abs(lead["drift_um"] - kx["relative_error"] * travel * 1e3) < count_um  # a steady lead
    assert 0 < lead["peak_to_peak_um"] < pulse_um
    lathe = ThreadLatheParams()
    screw_count_um = k["t_tv"] / (4 * k["n_enc"]) * 1e3
    screw = k["t_tv"] * 1e-3 / (2 * math.pi)  # m of carriage per radian of the screw
    give_um = lathe.ways_friction * (1 / lathe.nut_stiffness + screw**2 / lathe.feed_drive.stiffness) * 1e6
    assert 0 < lead["mean_um"] < lathe.nut_backlash * 1e6 / 2 + give_um + pulse_um + screw_count_um
