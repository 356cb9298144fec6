"""Setting formulas of seeds 000 and 001, each against a case worked by hand.

Machine constants used by hand (the job defaults): c1 = 1, i_sigma = 0.5, c2 = 1/24 (mechanical and
hydraulic structures) or 1 (mechatronic), c3 = 0.5, c4 = 0.5 mm, t_TV = 10 mm, n_M = 1450 rpm,
f_ref = 1 GHz, p = 10000 pulses/rev, q = 3600 steps/rev.
"""

import json
import math
from pathlib import Path

import pytest

from virtual_machine.job import load_job, with_machine
from virtual_machine.setting.sheet import ratio_error_effect, setup_sheet

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"
T_HELICAL = math.pi * 2 * 60 / math.sin(math.radians(20))  # lead of the z = 60 internal gear, 1102.2483 mm


@pytest.fixture(scope="module")
def spur():
    return load_job(JOBS / "spur_external.toml")


@pytest.fixture(scope="module")
def helical():
    return load_job(JOBS / "helical_internal.toml")


def test_s1_mechanical_by_hand(spur, helical):
    sh = setup_sheet(spur, "mechanical")
    assert sh.to_json()["structure"] == "mechanical"
    assert set(sh.settings) == {"ix", "iy", "iv", "is"}
    assert sh.settings["ix"].value == pytest.approx(23 / (1 * 0.5 * 40))  # 1.15
    assert sh.settings["iy"].value == 0.0  # spur: clutch 12 open
    assert sh.settings["iv"].value == pytest.approx(2500 / (0.5 * 1450))  # 3.44828
    assert sh.settings["is"].value == pytest.approx(0.2 / 0.5)
    hs = setup_sheet(helical, "mechanical")
    assert hs.settings["ix"].value == pytest.approx(25 / (0.5 * 60))  # 0.83333
    assert hs.settings["iy"].value == pytest.approx(10 / (T_HELICAL * (1 / 24) * 0.5))  # 0.435474
    assert hs.settings["iy"].value == pytest.approx(0.435474, abs=1e-6)
    # guitars: exact ratios found exactly; iy to within 1e-5 by the standard set
    assert sh.settings["ix"].relative_error == 0 and sh.settings["is"].relative_error == 0
    assert abs(hs.settings["iy"].relative_error) < 1e-5
    gears = hs.settings["iy"].realisation["gears"]["a_b_c_d"]
    a, b, c, d = gears
    assert a * c / (b * d) == pytest.approx(hs.settings["iy"].realised, rel=1e-15)


def test_s2_hydraulic_differential_by_hand(helical):
    sh = setup_sheet(helical, "hydraulic-differential")
    assert set(sh.settings) == {"kx", "ky", "iv", "is"}
    kx, ky = sh.settings["kx"], sh.settings["ky"]
    assert kx.value == pytest.approx(0.833333333) and kx.realisation["disc_windows"] == 3000  # 3000 / 3600
    assert ky.value == pytest.approx(0.435474, abs=1e-6)
    assert ky.realisation["disc_windows"] == round(0.4354736 * 3600) == 1568
    assert ky.realised == pytest.approx(1568 / 3600)
    # lead error of the coarse disc: eps T
    assert ky.effect["lead_um"] == pytest.approx(ky.relative_error * T_HELICAL * 1e3)
    assert sh.settings["iv"].realisation["gears"]["a_b"][0] / sh.settings["iv"].realisation["gears"]["a_b"][1] == (
        pytest.approx(sh.settings["iv"].realised)
    )


def test_s3_hydraulic_shaft_by_hand(spur, helical):
    assert setup_sheet(spur, "hydraulic-shaft").settings["kx"].value == pytest.approx(40 / 23)
    # feed down (s_z = -0.2) on a right-hand lead: kx = (z2/z0)(1 + s_z/T) / c1
    kx = setup_sheet(helical, "hydraulic-shaft").settings["kx"]
    assert kx.value == pytest.approx(60 / 25 * (1 - 0.2 / T_HELICAL), abs=1e-12)
    assert kx.value == pytest.approx(2.3995645, abs=1e-7)


def test_s4_mechatronic_by_hand(spur, helical):
    sh = setup_sheet(spur, "mechatronic")
    kv, kx, ks, ky = (sh.settings[k] for k in ("kv", "kx", "ks", "ky"))
    assert kv.value == pytest.approx(60 * 1e9 / (1e4 * 2500))  # 2400
    # kv is the multiple of 23 nearest 2400 so that kx = c1 kv z2 / z0 is an integer
    assert kv.realisation["integer"] == 2392 and kx.realisation["integer"] == 2392 * 40 // 23 == 4160
    assert kx.relative_error == 0
    n0 = 60 * 1e9 / (1e4 * 2392)
    n_screw = 0.2 * n0 * 23 / 40 / 10
    assert ks.value == pytest.approx(60 * 1e9 / (1e4 * n_screw))
    assert ky.value == 0  # spur: divider 22 off
    hs = setup_sheet(helical, "mechatronic")
    ks_h, ky_h = hs.settings["ks"], hs.settings["ky"]
    assert ky_h.value == pytest.approx(1.0 * ks_h.realisation["integer"] * T_HELICAL / 10)
    assert abs(ky_h.effect["lead_um"]) < 0.1  # a 4e7 divider sets the lead to far below a micrometre


def test_error_effect_of_a_ratio_error(spur):
    """eps = 1e-6 on z0/z2: pitch pi d eps = 0.2513 um per revolution; drift over the face 2 pi r_b eps b/s."""
    e = ratio_error_effect(spur, 1e-6)
    assert e["pitch_um_per_work_rev"] == pytest.approx(math.pi * 80 * 1e-3, abs=1e-9)
    assert e["helix_drift_um_over_face"] == pytest.approx(2 * math.pi * 37.5877048 * 20 / 0.2 * 1e-3, abs=1e-5)


def test_thread_group_by_hand():
    job = load_job(JOBS / "thread_m12.toml")  # P = 1.75 mm, t_TV = 10, i0 = i01 = 1
    mech = setup_sheet(job, "mechanical")
    assert mech.settings["ix"].value == pytest.approx(1.75 / 10) and mech.settings["ix"].relative_error == 0
    ms = setup_sheet(job)  # machine: mechatronic, master-slave
    assert ms.structure == "thread-master-slave"
    kx = ms.settings["kx"]
    assert kx.value == pytest.approx(0.175)
    # counter 7 / block 8: N/K = kx p / e = 0.175 * 10000 / 20000 = 7/80
    assert (kx.realisation["block_N"], kx.realisation["counter_K"]) == (7, 80) and kx.relative_error == 0
    eq = setup_sheet(with_machine(job, synchronization="equal-coordinates"))
    n = 1000 * 90 / (math.pi * 12)
    assert eq.settings["kv"].value == pytest.approx(60 * 1e9 / (1e4 * n))
    kv = eq.settings["kv"].realisation["integer"]
    assert eq.settings["kx"].value == pytest.approx(1 * 10 * kv / 1.75) and eq.settings["kx"].relative_error == 0
    with pytest.raises(ValueError, match="thread group"):
        setup_sheet(job, "hydraulic-shaft")


def test_json_names_are_the_seeds(spur):
    for structure, names in (("mechanical", ["ix", "iy", "iv", "is"]), ("mechatronic", ["kv", "kx", "ks", "ky"])):
        data = json.loads(json.dumps(setup_sheet(spur, structure).to_json(), default=str))
        assert data["structure"] == structure and list(data["settings"]) == names
    consts = setup_sheet(spur, "mechanical").to_json()["constants"]
    assert {"c1", "c2", "c3", "c4", "i_sigma", "t_tv", "n_m"} <= set(consts)
    assert consts["c2"] == pytest.approx(1 / 24)
    sanity = setup_sheet(spur, "mechatronic").to_json()["sanity"]
    assert sanity["cutting_speed_m_min"] == pytest.approx(131.496, abs=1e-3)


def test_unreachable_guitar_ratio_names_the_setting(helical):
    from cutting.errors import InputError

    job = with_machine(helical, c2=1e-4)
    with pytest.raises(InputError, match="outside the range") as info:
        setup_sheet(job, "mechanical")
    assert info.value.keys == ["setting.iy"] and "machine.c1..c4" in str(info.value)
