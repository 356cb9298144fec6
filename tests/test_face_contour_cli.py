"""A face coupling job (seed 004) through skive setup / cut / run, and its bad input."""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest
from checks import oblique_factors
from click.testing import CliRunner
from rerun.chunk import RrdReader
from scipy.optimize import brentq

from cutting.errors import InputError
from cutting.materials import material
from metrology.face_slots import FLAT_TOLERANCE
from virtual_machine.cli import main
from virtual_machine.job import parse_job

ASSET = Path(__file__).resolve().parent.parent / "assets" / "jobs" / "face_coupling.toml"


def _job_coupling(text: str | None = None):
    return parse_job(tomllib.loads(text or ASSET.read_text()), "face.toml").coupling


def flat_bottom_e(c, cyclic: bool = False) -> float:
    """The eccentricity [mm] that puts the slot bottom at the middle radius on the line through the bottom at the
    inner and outer radius, from the seed's formulas alone (eq. 1, 5, 14): the tip runs along the tool plane, turned by
    lambda = arcsin(L / ((R - N e) m)) from the radial line OM, at s = R sin phi - e sin N phi from M and at the height
    e cos N phi - e - R cos phi (+ a constant); the point at radius r on the slot's centre line is under the tip's
    (horizontal) edge where r cos(a - lambda) = L cos lambda + s, the workpiece at a = phi / m, less A (1 - cos q phi)
    with the cyclic ratio on (A = 2 R cos(lambda_0) / (m L q^2), lambda_0 = arcsin(L / (R m)): the straight slot)."""
    m, L, R, N, q = c.m, c.L, c.R, c.eccentric_ratio, c.ratio_cycles
    A = 2 * R * math.cos(math.asin(L / (R * m))) / (m * L * q**2) if cyclic else 0.0

    def bottom(e: float, r: float) -> float:
        lam = math.asin(L / ((R - N * e) * m))

        def under(f: float) -> float:
            a = f / m - A * (1 - math.cos(q * f))
            return r * math.cos(a - lam) - L * math.cos(lam) - (R * math.sin(f) - e * math.sin(N * f))

        f = brentq(under, -0.5, 0.5, xtol=1e-15)
        return e * math.cos(N * f) - e - R * math.cos(f)

    def middle(e: float) -> float:
        ends = bottom(e, c.inner_radius) + bottom(e, c.outer_radius)
        return bottom(e, 0.5 * (c.inner_radius + c.outer_radius)) - 0.5 * ends

    return brentq(middle, 0.1 * R / N**2, 0.9 * R / N, xtol=1e-12)


def test_setup_prints_the_setting_sheet():
    res = CliRunner().invoke(main, ["setup", str(ASSET)])
    assert res.exit_code == 0, res.output
    assert "setting angle lambda" in res.output and "flat slot bottom" in res.output
    doc = json.loads(CliRunner().invoke(main, ["setup", str(ASSET), "--json"]).output)
    c = _job_coupling()
    e = flat_bottom_e(c)  # 7.87514 mm (the code solves it on its exact bottom to 1e-9 mm)
    assert doc["flat_bottom_e_mm"] == pytest.approx(e, abs=1e-6)
    # eq. 1 on the tip's radius of speed at M, R - N e (eq. 15 at phi = 0):
    # arcsin(52.5 / ((125 - 4 x 7.87514) x 24)) = 1.3406 deg (arcsin(52.5 / (125 x 24)) = 1.0027 deg without the e)
    lam = math.degrees(math.asin(c.L / ((c.R - c.eccentric_ratio * e) * c.m)))
    assert lam == pytest.approx(1.3406, abs=1e-4) and doc["setting_angle_deg"] == pytest.approx(lam, abs=1e-9)


@pytest.mark.parametrize("command", ["cut", "run"])
def test_cut_and_run_make_flat_slots_with_the_setting_sheets_e(command, tmp_path):
    """The job's eccentric takes the setting sheet's e: the bottoms come out flat within 2 um on the ideal
    kinematics, and on the simulated machine without cutting forces (the run's comparison run); the solid agrees with
    the exact measure within its sweep error. Under the cut's forces the run reports what they do: the oblique
    model's force at M, and the head slowing and lagging while an element crosses a slot, so the bottoms come out
    convex and the spacing moves, less with the slaves on the head's encoder than on its command (measured:
    -18..-12 um and -1.0 arcsec against -54..-45 um and -4.9 arcsec)."""
    res = CliRunner().invoke(main, [command, str(ASSET), "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    doc = json.loads((tmp_path / "measurement.json").read_text())
    assert len(doc["slots"]) == 3 and (tmp_path / "coupling.stl").stat().st_size > 10_000
    assert doc["mesh"]["bottom_form_difference_um"] < 1.0
    if command == "cut":
        for s in doc["slots"]:
            assert s["bottom_shape"] == "flat" and abs(s["bottom_form_um"]) < 2.0
        assert all(abs(v) < 0.5 for v in doc["spacing_arcsec"])  # 2 pi / m between the slots
        return
    assert doc["run"]["job"]["kind"] == "face_contour" and (tmp_path / "report.html").is_file()
    f = doc["forces"]
    assert all(abs(s["bottom_form_without_forces_um"]) < 2.0 for s in f["slots"])
    assert all(abs(v) < 0.5 for v in f["spacing_without_forces_arcsec"])
    assert f["spacing_with_forces_arcsec"] == pytest.approx(doc["spacing_arcsec"], abs=1e-9)
    # the oblique model at M by hand (the spark-out's layers: the plunge reaches the depth at turn 3 / 0.0017 =
    # 1764.7, slots 0-2 are finished at turns 1776-1778 over what turns 1752-1754 left, h = 3 - 0.0017 (turn - 24) =
    # 21.6, 19.9, 18.2 um; the tip 3 mm deep, V horizontal and radial, the tool plane at the setting angle lambda =
    # 1.3406 deg to it): the tip edge, 2 cos(lambda) mm wide, at rake 0 and inclination lambda; each flank, h sin 20
    # deg thick over (3 - h / 2) / cos 20 deg x cos(lambda_f), at rake +-atan(tan(lambda) cos 20) = +-1.2598 deg
    # and inclination lambda_f = +-asin(sin 20 sin(lambda)) = +-0.4585 deg; F = f_c tau_s(h) (h - 3 um) b + 10 N/mm
    # b (cutting/oblique.py's formulas, beta_a 30 deg, tau_s = 2100 h^-0.26 / 3.07973): 558.02, 514.09, 468.77 N.
    # Their mean over the cut within 1 %: the eccentric keeps the tip's path flat while the plate turns with the
    # head, so the tip edge's working rake runs from -4 to +4 deg across the slot and F_c by -+5 % about M's.
    steel = material("16MnCr5")
    assert (steel.kc11, steel.mc) == (2100.0, 0.26)
    kappa, lam = math.radians(20.0), math.asin(52.5 / ((125.0 - 4 * flat_bottom_e(_job_coupling())) * 24))
    lam_f = math.asin(math.sin(kappa) * math.sin(lam))
    gam_f = math.degrees(math.atan(math.tan(lam) * math.cos(kappa)))

    def segment(h: float, b: float, gamma: float, incl: float) -> float:
        tau = 2100 * h**-0.26 / oblique_factors(6.0, 0.0)[0]
        return oblique_factors(gamma, math.degrees(incl))[0] * tau * (h - 0.003) * b + 10 * b

    hands = []
    for k, s in enumerate(f["slots"]):
        h = 3.0 - 0.0017 * (1752 + k)
        h_flank, b_flank = h * math.sin(kappa), (3.0 - h / 2) / math.cos(kappa) * math.cos(lam_f)
        hand = segment(h, 2 * math.cos(lam), 0.0, lam) + sum(segment(h_flank, b_flank, g, i * lam_f) for g, i in
                                                             ((gam_f, 1), (-gam_f, -1)))  # fmt: skip
        assert s["layer_um"] == pytest.approx(h * 1e3, abs=1e-6) and s["F_c_mean_N"] == pytest.approx(hand, rel=0.01)
        assert hand < s["F_c_peak_N"] < 1.1 * hand
        hands.append(hand)
    assert hands == pytest.approx([558.02, 514.09, 468.77], abs=0.01)
    # under the forces the head lags while an element crosses a slot, less slot by slot as the layer thins: the
    # spacing moves back and the bottoms come out convex (beyond the flat tolerance); slaves that follow the head's
    # encoder copy what the head does, so they cut closer to the ideal slot than slaves on its command (the same
    # job with master = "generator"): that is the bound on both (nothing else bounds the servos' response)
    assert all(v < 0 for v in f["spacing_change_um_at_L"])
    assert all(s["bottom_shape"] == "convex" and s["bottom_form_um"] < -FLAT_TOLERANCE * 1e3 for s in doc["slots"])
    command_master = tmp_path / "generator"
    text = ASSET.read_text().replace("slots_cut = 3", 'slots_cut = 3\nmaster = "generator"')
    (tmp_path / "generator.toml").write_text(text)
    res = CliRunner().invoke(main, ["run", str(tmp_path / "generator.toml"), "--out", str(command_master)])
    assert res.exit_code == 0, res.output
    gen = json.loads((command_master / "measurement.json").read_text())
    assert max(map(abs, doc["spacing_arcsec"])) < min(map(abs, gen["spacing_arcsec"]))
    assert min(s["bottom_form_um"] for s in doc["slots"]) > max(s["bottom_form_um"] for s in gen["slots"])


def test_simulate_reports_the_gearbox_synchronisation_and_run_records(tmp_path):
    res = CliRunner().invoke(main, ["simulate", str(ASSET), "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    doc = json.loads((tmp_path / "simulation.json").read_text())
    process = tomllib.loads(ASSET.read_text())["process"]
    # the head turns at least once per slot cut: 3 tool revolutions at 150 rpm = 1.2 s
    assert doc["machine_time_s"] >= process["slots_cut"] * 60 / process["tool_speed"]
    sync = doc["synchronisation_peak_to_peak"]  # the eccentric's gearbox reports its own (control "eccentric")
    assert all(math.isfinite(sync[k]) and sync[k] > 0 for k in ("work_arcsec", "eccentric_arcsec", "infeed_um"))
    args = ["run", str(ASSET), "--out", str(tmp_path / "run"), "--rrd", str(tmp_path / "r.rrd")]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 0, res.output
    # the run drives the same machine (the same figures), and its recording holds those series and the coupling
    run = json.loads((tmp_path / "run" / "measurement.json").read_text())["run"]
    assert run["synchronisation_peak_to_peak"] == sync
    chunks = RrdReader(tmp_path / "r.rrd").stream().to_chunks()
    assert {c.entity_path for c in chunks} >= {"/coupling", "/machine/axes", "/machine/synchronisation"}
    recorded = np.array(
        [v for c in chunks if c.entity_path == "/machine/synchronisation" and not c.is_static
         for v in c.to_record_batch().column("Scalars:scalars").to_pylist()]
    )  # fmt: skip
    ptp = [sync["work_arcsec"], sync["eccentric_arcsec"], sync["infeed_um"]]
    assert np.ptp(recorded, axis=0) == pytest.approx(ptp, rel=1e-6)


def test_a_setting_angle_that_cannot_be_is_refused_by_its_key():
    text = ASSET.read_text().replace("L = 52.5", "L = 3500.0")
    with pytest.raises(InputError) as info:
        parse_job(tomllib.loads(text), "bad.toml")
    assert "coupling.L" in str(info.value)


def test_combined_controls_and_the_held_head_speed_parse_with_the_setting_sheets_values():
    """control = "eccentric+cyclic_ratio" takes the straight-slot amplitude and the e that keeps the bottom flat with
    the ratio's cycle on; head_speed = "held" asks for eq. 16; an unknown head speed is refused by its key."""
    text = ASSET.read_text().replace('control = "eccentric"', 'control = "eccentric+cyclic_ratio"')
    text = text.replace("slots_cut = 3", 'slots_cut = 3\nhead_speed = "held"')
    job = parse_job(tomllib.loads(text), "both.toml")
    c = job.coupling
    assert c.eccentric_on and c.cyclic_on and job.process.head_speed == "held"
    assert c.ratio_amplitude == pytest.approx(c.straight_slot_amplitude(), rel=1e-12)
    assert c.e == pytest.approx(flat_bottom_e(c, cyclic=True), abs=1e-6)  # the flat-bottom e with the cycle on
    with pytest.raises(InputError) as info:
        parse_job(tomllib.loads(text.replace('head_speed = "held"', 'head_speed = "fast"')), "bad.toml")
    assert "process.head_speed" in str(info.value)
