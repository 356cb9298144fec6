"""skive measure: file formats, JSON schema, charts, [measurement] options and clear failures."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from cutting.gear import Gear
from metrology.reference_gear import reference_gear_mesh
from virtual_machine.cli import main

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"
SPUR = Gear(40, 2.0, math.radians(20), 0.0, 20.0)  # the gear of spur_external.toml


@pytest.fixture(scope="module")
def slope_mesh():
    """Left flanks with +3 um profile slope over the default evaluation range of the spur job's gear."""
    from metrology.measure import MeasureOptions, profile_range

    L0, L1 = profile_range(SPUR, MeasureOptions())
    return reference_gear_mesh(
        SPUR, lambda s, t, L, z: 3e-3 * (L - L0) / (L1 - L0) if s == "left" else 0 * L, flank_points=100, rotation=0.05
    )


@pytest.mark.parametrize("ext", ["stl", "ply", "glb", "obj"])
def test_measure_every_format(tmp_path, slope_mesh, ext):
    path = tmp_path / f"gear.{ext}"
    slope_mesh.export(path)
    res = CliRunner().invoke(main, ["measure", str(path), "--job", str(JOBS / "spur_external.toml"), "--json"])
    assert res.exit_code == 0, res.output
    doc = json.loads(res.output)
    assert doc["profile"]["left"]["f_Halpha"] == pytest.approx(3.0, abs=0.2)  # float32 formats: ~0.1 um noise
    assert abs(doc["profile"]["right"]["f_Halpha"]) < 0.2
    for key in ("evaluation", "profile", "helix", "pitch", "runout", "thickness", "iso1328"):
        assert key in doc
    assert set(doc["pitch"]["left"]) >= {"f_p", "F_p", "F_pk", "k", "f_pi", "F_pi"}
    assert set(doc["thickness"]["span"]) >= {"k", "W_k_mm", "W_k_nominal_mm"}
    assert set(doc["iso1328"]["class"]) >= {
        "f_p",
        "F_p",
        "F_alpha",
        "f_Halpha",
        "f_falpha",
        "F_beta",
        "f_Hbeta",
        "f_fbeta",
        "F_r",
        "overall",
    }


def test_measure_writes_json_and_charts(tmp_path, slope_mesh):
    path = tmp_path / "gear.stl"
    slope_mesh.export(path)
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["measure", str(path), "--job", str(JOBS / "spur_external.toml"), "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "ISO 1328-1:2013 class of the gear" in res.output
    for name in ("measurement.json", "profile.png", "helix.png", "pitch.png", "topography.png"):
        assert (out / name).stat().st_size > 1000
    doc = json.loads((out / "measurement.json").read_text())
    # f_Halpha = 3 um is class 4 for this gear (fHaT class 4 = 3.5 um, class 3 = 2.5 um)
    assert doc["iso1328"]["class"]["f_Halpha"] == 4


def test_measurement_section_sets_the_evaluation(tmp_path, slope_mesh):
    path = tmp_path / "gear.stl"
    slope_mesh.export(path)
    job = tmp_path / "job.toml"
    job.write_text(
        (JOBS / "spur_external.toml").read_text()
        + "\n[measurement]\nsector_teeth = 3\nspan_teeth = 4\nball_diameter = 3.25\n"
    )
    doc = json.loads(CliRunner().invoke(main, ["measure", str(path), "--job", str(job), "--json"]).output)
    assert doc["pitch"]["left"]["k"] == 3
    assert doc["thickness"]["span"]["k"] == 4
    assert doc["runout"]["ball_diameter_mm"] == 3.25


def test_measure_refuses_bad_input(tmp_path, slope_mesh):
    path = tmp_path / "gear.stl"
    slope_mesh.export(path)
    wrong = tmp_path / "wrong.toml"
    wrong.write_text((JOBS / "spur_external.toml").read_text().replace("teeth = 40", "teeth = 41"))
    res = CliRunner().invoke(main, ["measure", str(path), "--job", str(wrong)])
    assert res.exit_code == 2 and "z = 41 teeth" in res.output
    res = CliRunner().invoke(main, ["measure", str(tmp_path / "none.stl"), "--job", str(JOBS / "spur_external.toml")])
    assert res.exit_code == 2 and "no such file" in res.output
    broken = tmp_path / "broken.stl"
    broken.write_text("solid x\nendsolid x\n")
    res = CliRunner().invoke(main, ["measure", str(broken), "--job", str(JOBS / "spur_external.toml")])
    assert res.exit_code == 2 and "mesh" in res.output
