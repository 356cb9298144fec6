"""skive measure: file formats, JSON schema, charts, [measurement] options and clear failures."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from cutting.gear import Gear
from metrology.measure import MeasureOptions, profile_range
from metrology.reference_gear import reference_gear_mesh
from virtual_machine.cli import main

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"
SPUR = Gear(40, 2.0, math.radians(20), 0.0, 20.0)  # the gear of spur_external.toml


@pytest.fixture(scope="module")
def slope_mesh():
    """Left flanks with +3 um profile slope over the default evaluation range of the spur job's gear."""
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
    # the rest is what the mesh was made with, to the same float32 noise (0.2 um): the job's evaluation range; a pure
    # slope on the left profiles (F_alpha = f_Halpha, no form); no helix, pitch or runout deviation
    assert doc["evaluation"]["profile_roll_mm"] == pytest.approx(list(profile_range(SPUR, MeasureOptions())), abs=1e-9)
    left = doc["profile"]["left"]
    assert left["F_alpha"] == pytest.approx(3.0, abs=0.2) and left["f_falpha"] < 0.2
    for side in ("left", "right"):
        assert all(abs(doc["helix"][side][key]) < 0.2 for key in ("F_beta", "f_Hbeta", "f_fbeta"))
        pitch = doc["pitch"][side]
        assert pitch["k"] == 5 and len(pitch["f_pi"]) == len(pitch["F_pi"]) == SPUR.z  # k = z / 8 by default
        assert all(abs(pitch[key]) < 0.2 for key in ("f_p", "F_p", "F_pk"))
    assert 0 <= doc["runout"]["F_r"] < 0.2
    # span over k = round(z / 9 + 0.5) = 5 teeth (DIN 21773, spur 20 deg, x = 0): nominal
    # W_k = mn cos(alpha) [(k - 0.5) pi + z inv(alpha)]; the left slope adds at most its 3 um at the anvil's contact
    alpha = SPUR.pressure_angle
    span = doc["thickness"]["span"]
    nominal = 2.0 * math.cos(alpha) * (4.5 * math.pi + 40 * (math.tan(alpha) - alpha))
    assert span["k"] == 5 and span["W_k_nominal_mm"] == pytest.approx(nominal, abs=1e-9)
    assert 0 <= span["W_k_mm"] - nominal < (3.0 + 0.2) * 1e-3
    # the graded class's tolerances are ISO 1328-1's for this gear (d = 80 mm, mn 2, b 20 mm, z 40, k 5)
    iso = doc["iso1328"]
    assert iso["standard"] == "ISO 1328-1:2013" and iso["tolerances_class"] == iso["class"]["overall"] == 4
    assert iso["tolerances"] == pytest.approx(_iso1328_tolerances(4, d=80.0, mn=2.0, b=20.0, z=40, k=5), abs=1e-9)
    assert {key: iso["class"][key] for key in ("f_p", "F_p", "f_Halpha", "F_beta", "F_r")} == {
        "f_p": 1,
        "F_p": 1,
        "f_Halpha": 4,  # 3 um: fHaT is 2.5 um in class 3, 3.5 um in class 4
        "F_beta": 1,
        "F_r": 1,
    }


def _iso1328_tolerances(A: int, d: float, mn: float, b: float, z: int, k: int) -> dict[str, float]:
    """ISO 1328-1:2013 flank tolerances [um] of class A (metrology-notes): the class-5 value times sqrt(2)^(A - 5),
    rounded once (above 10 um to 1 um, 5..10 um to 0.5 um, below 5 um to 0.1 um)."""

    def rounded(x5: float) -> float:
        x = x5 * math.sqrt(2) ** (A - 5)
        step = 1.0 if x > 10 else 0.5 if x >= 5 else 0.1
        return round(x / step) * step

    fp = 0.001 * d + 0.4 * mn + 5
    Fp = 0.002 * d + 0.55 * math.sqrt(d) + 0.7 * mn + 12
    fHa, ffa = 0.4 * mn + 0.001 * d + 4, 0.55 * mn + 5
    fHb, ffb = 0.05 * math.sqrt(d) + 0.35 * math.sqrt(b) + 4, 0.07 * math.sqrt(d) + 0.45 * math.sqrt(b) + 4
    class5 = {
        "f_p": fp,
        "F_p": Fp,
        "F_pk": fp + 4 * k / z * (0.001 * d + 0.55 * math.sqrt(d) + 0.3 * mn + 7),
        "F_alpha": math.hypot(fHa, ffa),
        "f_Halpha": fHa,
        "f_falpha": ffa,
        "F_beta": math.hypot(fHb, ffb),
        "f_Hbeta": fHb,
        "f_fbeta": ffb,
        "F_r": 0.9 * Fp,
    }
    return {key: rounded(v) for key, v in class5.items()}


def test_measure_writes_json_and_charts(tmp_path, slope_mesh):
    path = tmp_path / "gear.stl"
    slope_mesh.export(path)
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["measure", str(path), "--job", str(JOBS / "spur_external.toml"), "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "ISO 1328-1:2013 class of the gear" in res.output
    for name in ("profile.png", "helix.png", "pitch.png", "topography.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
    doc = json.loads((out / "measurement.json").read_text())
    assert doc["profile"]["left"]["f_Halpha"] == pytest.approx(3.0, abs=0.2)  # the mesh's slope
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


def test_the_measurement_names_the_mesh_it_measured_and_its_files_appear_together(tmp_path, slope_mesh):
    """measurement.json records the SHA-256 of the mesh file it measured; its folder gets every file or none."""
    import hashlib

    from virtual_machine.api import measure

    path = tmp_path / "gear.stl"
    slope_mesh.export(path)
    out = tmp_path / "meas"
    doc = measure(path, JOBS / "spur_external.toml", out)
    assert doc["solid_sha256"] == {"gear.stl": hashlib.sha256(path.read_bytes()).hexdigest()}
    assert json.loads((out / "measurement.json").read_text())["solid_sha256"] == doc["solid_sha256"]
    assert {"measurement.json", "profile.png", "helix.png", "pitch.png"} <= {p.name for p in out.iterdir()}
    assert [p.name for p in tmp_path.iterdir() if "partial" in p.name] == []
