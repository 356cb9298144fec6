"""Tests of virtual_machine.job: every invalid job gets an InputError naming the key, the value, why and what is valid.

Each case starts from a shipped job (spur_external.toml or helical_internal.toml, read with tomllib), changes
one thing and checks the error: the key is in ``err.keys``, ``"<key> = <value!r>"`` appears in the message,
and words of the reason / hint appear too.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import tomllib
from pathlib import Path
from typing import Any

import pytest

from cutting.errors import InputError
from cutting.gear import Gear, check_gear
from virtual_machine.job import (
    CUTTER_KEYS,
    GEAR_KEYS,
    KINDS,
    MACHINE_KEYS,
    PROCESS_KEYS,
    THREAD_KEYS,
    FaceContourJob,
    FormMillingJob,
    Job,
    SkivingJob,
    ThreadJob,
    TurningJob,
    default_job_path,
    load_job,
    parse_job,
)

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"
SOURCE = "test_job.toml"
DELETE = object()  # marker: remove the key
_MISSING = object()  # marker: do not check the value


def _read(name: str) -> dict[str, Any]:
    with (JOBS / name).open("rb") as f:
        return tomllib.load(f)


_SPUR = _read("spur_external.toml")
_INTERNAL = _read("helical_internal.toml")
_THREAD = _read("thread_m12.toml")


def spur(**changes: Any) -> dict[str, Any]:
    """spur_external.toml with changes given as section__key=value (DELETE removes the key)."""
    return _changed(_SPUR, changes)


def internal(**changes: Any) -> dict[str, Any]:
    """helical_internal.toml (z2 = 60, beta2 = +20 deg, internal; cutter z0 = 25 spur) with changes."""
    return _changed(_INTERNAL, changes)


def internal_spur(**changes: Any) -> dict[str, Any]:
    """Internal spur gear z2 = 60 with a 20 deg helical cutter (Sigma = beta2 - beta0 = -20 deg), z0 = 25."""
    base = {"gear__helix_angle": 0.0, "cutter__helix_angle": 20.0}
    return _changed(_INTERNAL, base | changes)


def thread(**changes: Any) -> dict[str, Any]:
    return _changed(_THREAD, changes)


def _changed(base: dict[str, Any], changes: dict[str, Any]) -> dict[str, Any]:
    data = copy.deepcopy(base)
    for dotted, value in changes.items():
        section, key = dotted.split("__")
        if value is DELETE:
            data[section].pop(key)
        else:
            data.setdefault(section, {})[key] = value
    return data


def refused(data: dict[str, Any], key: str, value: Any = _MISSING, words: tuple[str, ...] = ()) -> InputError:
    """parse_job must raise InputError naming ``key`` (and ``value``), whose message contains every word."""
    with pytest.raises(InputError) as info:
        parse_job(data, SOURCE)
    err = info.value
    text = str(err)
    assert key in err.keys, text
    assert SOURCE in text, text
    if value is not _MISSING:
        assert any(p.key == key and p.value == value for p in err.problems), text
        assert f"{key} = {value!r}" in text, text
    for word in words:
        assert word.lower() in text.lower(), f"{word!r} not in\n{text}"
    return err


def problem(err: InputError, key: str):
    (p,) = [p for p in err.problems if p.key == key]
    return p


# ----------------------------------------------------------------------------------------------------
# the bases themselves are valid (otherwise every "change one thing" test below proves nothing)
# ----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("make", [spur, internal, internal_spur, thread], ids=lambda f: f.__name__)
def test_bases_are_valid(make):
    data = make()
    job = parse_job(data, SOURCE)
    assert isinstance(job, Job)
    assert job.kind == ("thread" if make is thread else "skiving")
    if make is thread:  # the file's thread, key by key (a mapping or the typed section)
        t = job.thread
        assert all((t[k] if isinstance(t, dict) else getattr(t, k)) == v for k, v in data["thread"].items())
        return
    # the job holds the file's gear and cutter, and the shaft angle of the crossing (signed helix angles, right hand
    # positive): external Sigma = beta2 + beta0, internal Sigma = beta2 - beta0
    g, c = data["gear"], data["cutter"]
    assert (job.gear.z, job.gear.mn, job.gear.internal) == (g["teeth"], g["normal_module"], g.get("internal", False))
    assert job.cutter.z == c["teeth"]
    beta2, beta0 = math.radians(g["helix_angle"]), math.radians(c["helix_angle"])
    assert (job.gear.helix_angle, job.cutter.helix_angle) == pytest.approx((beta2, beta0), abs=1e-12)
    sigma = beta2 - beta0 if job.gear.internal else beta2 + beta0
    assert job.skiving.shaft_angle == pytest.approx(sigma, abs=1e-12)


def test_spur_base_tooth_depth_is_4_5_mm():
    job = parse_job(spur(), SOURCE)
    assert job.skiving.full_depth == pytest.approx(4.5, abs=1e-9)
    assert sum(job.process.passes) == pytest.approx(4.5)


# ----------------------------------------------------------------------------------------------------
# unknown keys and sections
# ----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("make", "dotted", "value", "suggestion"),
    [
        (spur, "gear.teeths", 40, "teeth"),
        (spur, "gear.normal_modul", 2.0, "normal_module"),
        (spur, "cutter.helix", 20.0, "helix_angle"),
        (spur, "process.pass", [1.0], "passes"),
        (spur, "machine.structures", "mechatronic", "structure"),
        (thread, "thread.leads", 1.75, "lead"),
    ],
)
def test_unknown_key_names_key_value_and_suggests(make, dotted, value, suggestion):
    section, key = dotted.split(".")
    err = refused(make(**{f"{section}__{key}": value}), dotted, value, ("unknown key", "valid keys"))
    assert err.keys == [dotted]  # the misspelt key is the only problem when the right one is also there
    assert f"did you mean {suggestion!r}?" in problem(err, dotted).hint


@pytest.mark.parametrize(
    ("section", "keys"),
    [("gear", GEAR_KEYS), ("cutter", CUTTER_KEYS), ("process", PROCESS_KEYS), ("machine", MACHINE_KEYS)],
)
def test_unknown_key_lists_every_valid_key(section, keys):
    err = refused(spur(**{f"{section}__colour": "blue"}), f"{section}.colour", "blue", ("unknown key",))
    hint = problem(err, f"{section}.colour").hint
    assert "did you mean" not in hint
    assert all(k in hint for k in keys)


def test_misspelt_required_key_reports_unknown_and_missing():
    data = spur()
    data["gear"]["teeths"] = data["gear"].pop("teeth")
    err = refused(data, "gear.teeths", 40, ("unknown key", "did you mean 'teeth'", "missing required key"))
    assert sorted(err.keys) == ["gear.teeth", "gear.teeths"]


@pytest.mark.parametrize("name", ["gears", "tool", "thread_"])
def test_unknown_section(name):
    data = spur()
    data[name] = {"teeth": 40}
    err = refused(data, name, words=("unknown section", "[gear]", "[cutter]", "[process]", "[machine]"))
    assert err.keys == [name]
    assert f"{name} = " in str(err)


def test_cutter_section_in_a_thread_job_is_unknown():
    data = thread()
    data["cutter"] = copy.deepcopy(_SPUR["cutter"])
    err = refused(data, "cutter", words=("unknown section", "[thread]"))
    assert err.keys == ["cutter"]


@pytest.mark.parametrize("section", ["gear", "process", "machine"])
def test_section_that_is_not_a_table(section):
    data = spur()
    data[section] = 5
    refused(data, section, 5, ("must be a table", f"[{section}]"))


# ----------------------------------------------------------------------------------------------------
# missing required keys
# ----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("dotted", "type_word"),
    [
        ("gear.teeth", "an integer"),
        ("gear.normal_module", "a number, mm"),
        ("gear.face_width", "a number, mm"),
        ("cutter.teeth", "an integer"),
        ("cutter.helix_angle", "a number, deg"),
        ("process.tool_speed", "a number, rpm"),
        ("process.axial_feed", "a number, mm/rev"),
        ("process.passes", "a list, mm"),
    ],
)
def test_missing_required_key(dotted, type_word):
    section, key = dotted.split(".")
    err = refused(spur(**{f"{section}__{key}": DELETE}), dotted, None, ("missing required key",))
    assert err.keys == [dotted]
    assert problem(err, dotted).hint == f"add {key} = <{type_word}>"


@pytest.mark.parametrize(("make", "dotted"), [(thread, "thread.lead"), (thread, "thread.diameter")])
def test_thread_job_missing_key(make, dotted):
    section, key = dotted.split(".")
    err = refused(make(**{f"{section}__{key}": DELETE}), dotted, None, ("missing required key", f"add {key} ="))
    assert err.keys == [dotted]


def test_missing_section_reports_each_required_key():
    data = spur()
    del data["cutter"]
    err = refused(data, "cutter.teeth", None, ("missing required key",))
    assert sorted(err.keys) == ["cutter.helix_angle", "cutter.teeth"]


def test_optional_keys_get_their_defaults():
    data = spur()
    for key in ("pressure_angle", "helix_angle", "profile_shift"):
        del data["gear"][key]
    del data["machine"]
    job = parse_job(data, SOURCE)
    assert math.degrees(job.gear.alpha_n) == pytest.approx(20.0)
    assert job.gear.beta == 0.0
    assert job.gear.x == 0.0
    assert job.gear.internal is False
    assert job.machine.structure == "mechatronic"


# ----------------------------------------------------------------------------------------------------
# wrong types
# ----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("dotted", "value", "expected"),
    [
        ("gear.teeth", "40", "expected an integer"),
        ("gear.teeth", 40.5, "expected an integer"),
        ("gear.teeth", 40.0, "expected an integer"),
        ("gear.teeth", True, "expected an integer"),
        ("gear.normal_module", "2", "expected a number"),
        ("gear.normal_module", True, "expected a number"),
        ("gear.normal_module", math.inf, "expected a finite number"),
        ("gear.face_width", [20.0], "expected a number"),
        ("gear.internal", "yes", "expected true or false"),
        ("gear.internal", 1, "expected true or false"),
        ("cutter.teeth", 23.0, "expected an integer"),
        ("cutter.helix_angle", False, "expected a number"),
        ("cutter.edge", 1, "expected a string"),
        ("process.passes", "2.0", "expected a list"),
        ("process.passes", 4.5, "expected a list"),
        ("process.tool_speed", True, "expected a number"),
        ("process.axial_feed", "0.2", "expected a number"),
        ("process.feed_direction", 3, "expected a string"),
        ("machine.adaptive_correction", "true", "expected true or false"),
        ("machine.encoder_lines", 5000.0, "expected an integer"),
    ],
)
def test_wrong_type(dotted, value, expected):
    section, key = dotted.split(".")
    err = refused(spur(**{f"{section}__{key}": value}), dotted, value, (expected,))
    assert err.keys == [dotted]
    assert problem(err, dotted).reason == expected


def test_nan_is_refused():
    err = refused(spur(gear__face_width=math.nan), "gear.face_width", words=("expected a finite number", "nan"))
    assert err.keys == ["gear.face_width"]


def test_integers_are_accepted_where_numbers_are():
    job = parse_job(spur(gear__normal_module=2, process__tool_speed=2500, process__passes=[2, 1.5, 0.8, 0.2]), SOURCE)
    assert job.gear.mn == 2.0
    assert isinstance(job.process.tool_speed, float)


@pytest.mark.parametrize(
    ("passes", "reason"),
    [
        ([], "needs at least one pass"),
        (["2.0", 1.5], "must be a list of numbers"),
        ([2.0, True], "must be a list of numbers"),
        ([2.0, [1.5]], "must be a list of numbers"),
    ],
)
def test_passes_not_a_list_of_numbers(passes, reason):
    refused(spur(process__passes=passes), "process.passes", passes, (reason,))


@pytest.mark.parametrize(
    ("dotted", "value", "valid"),
    [
        ("process.feed_direction", "sideways", "'down', 'up'"),
        ("cutter.edge", "hob", "'conjugate', 'involute'"),
        ("machine.structure", "steam", "'mechatronic'"),
        ("machine.synchronization", "manual", "'master-slave'"),
        ("thread.hand", "both", "'right', 'left'"),
    ],
)
def test_value_not_one_of_the_options(dotted, value, valid):
    section, key = dotted.split(".")
    make = thread if section == "thread" else spur
    refused(make(**{f"{section}__{key}": value}), dotted, value, ("not a known value", valid))


# ----------------------------------------------------------------------------------------------------
# non-positive sizes and out-of-range values
# ----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("dotted", "value"),
    [
        ("gear.normal_module", 0.0),
        ("gear.normal_module", -2.0),
        ("gear.face_width", 0.0),
        ("gear.face_width", -20.0),
        ("gear.tip_diameter", -1.0),
        ("gear.tip_diameter", 0.0),
        ("gear.root_diameter", -1.0),
        ("cutter.tip_diameter", -1.0),
        ("process.tool_speed", 0.0),
        ("process.tool_speed", -2500.0),
        ("process.axial_feed", -0.1),
        ("process.axial_feed", 0),
        ("machine.c1", 0.0),
        ("machine.lead_screw_pitch", -10.0),
    ],
)
def test_non_positive_size(dotted, value):
    section, key = dotted.split(".")
    err = refused(spur(**{f"{section}__{key}": value}), dotted, value, ("must be > 0", "positive"))
    assert err.keys == [dotted]


@pytest.mark.parametrize(
    ("dotted", "value"), [("thread.lead", 0.0), ("thread.diameter", -12.0), ("process.cutting_speed", 0.0)]
)
def test_non_positive_size_thread(dotted, value):
    section, key = dotted.split(".")
    refused(thread(**{f"{section}__{key}": value}), dotted, value, ("must be > 0",))


@pytest.mark.parametrize("passes", [[2.0, -0.5, 1.5], [0], [0.0, 2.0], [-1.0]])
def test_pass_of_zero_first_or_negative(passes):
    err = refused(spur(process__passes=passes), "process.passes", passes, ("must be > 0 mm", "spring pass"))
    assert err.keys == ["process.passes"]


def test_a_spring_pass_repeats_the_final_centre_distance():
    """A 0 increment after the first pass is a spring pass: the cutter goes over the finished flanks again at the same
    centre distance (shops finish so); the job's depth and its passes' centre distances are those without it."""
    with_spring = parse_job(spur(process__passes=[2.25, 0.0]), "spring.toml").skiving
    plain = parse_job(spur(process__passes=[2.25]), "plain.toml").skiving
    assert with_spring.pass_centre_distances == (plain.pass_centre_distances[0],) * 2


@pytest.mark.parametrize(
    ("dotted", "value", "words"),
    [
        ("gear.teeth", 4, ("must be >= 5", "at least 5")),
        ("gear.teeth", 0, ("must be >= 5",)),
        ("gear.teeth", -40, ("must be >= 5",)),
        ("cutter.teeth", 7, ("must be >= 8", "at least 8")),
        ("cutter.teeth", 0, ("must be >= 8",)),
        ("process.clearance", -1.0, ("must be >= 0",)),
        ("machine.encoder_lines", 0, ("must be >= 1",)),
        ("machine.change_gears", [20, 30], ("at least 4 tooth counts",)),
        ("machine.change_gears", [20, 30, 40, 250], ("integers 12..200",)),
    ],
)
def test_value_below_its_minimum(dotted, value, words):
    section, key = dotted.split(".")
    refused(spur(**{f"{section}__{key}": value}), dotted, value, words)


@pytest.mark.parametrize(
    ("dotted", "value"),
    [
        ("gear.helix_angle", 45.0),
        ("gear.helix_angle", -45.0),
        ("gear.helix_angle", -50.0),
        ("gear.helix_angle", 90),
        ("cutter.helix_angle", 45.0),
        ("cutter.helix_angle", -50.0),
    ],
)
def test_helix_45_deg_or_more(dotted, value):
    section, key = dotted.split(".")
    err = refused(spur(**{f"{section}__{key}": value}), dotted, value, ("must be below 45 deg", "between -45 and +45"))
    assert err.keys == [dotted]


@pytest.mark.parametrize("value", [5.0, 9.9, 35.5, 0.0, -20.0])
def test_pressure_angle_out_of_range(value):
    refused(spur(gear__pressure_angle=value), "gear.pressure_angle", value, ("outside 10..35 deg", "20 deg"))


# ----------------------------------------------------------------------------------------------------
# gears that cannot be made: undercut, pointed, impossible diameters
# ----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("x", [0.0, 0.29, -0.5])
def test_undercut_gear(x):
    err = refused(spur(gear__teeth=12, gear__profile_shift=x), "gear.profile_shift", x, ("undercut", "z = 12"))
    assert err.keys == ["gear.profile_shift"]
    p = problem(err, "gear.profile_shift")
    assert "+0.298" in p.reason  # x_min = 1 - 12 sin^2(20 deg) / 2 (rack with its tip fillet)
    assert "profile_shift >= +0.298" in p.hint


def test_undercut_limit_is_about_0_298_for_12_teeth():
    assert check_gear(Gear(12, 2.0, math.radians(20), 0.0, 20.0, profile_shift=0.29)) != []
    assert check_gear(Gear(12, 2.0, math.radians(20), 0.0, 20.0, profile_shift=0.30)) == []
    assert check_gear(Gear(12, 2.0, math.radians(20), 0.0, 20.0, profile_shift=0.35)) == []


@pytest.mark.parametrize(
    "changes",
    [
        {"gear__teeth": 12, "gear__profile_shift": 0.35},
        {"gear__teeth": 12, "gear__profile_shift": 0.35, "cutter__teeth": 17},
        {"gear__profile_shift": 0.3},
        {"gear__profile_shift": -0.2},
        {"cutter__profile_shift": 0.1},
    ],
    ids=["z12_x0.35", "z12_x0.35_z0_17", "z40_x0.3", "z40_x-0.2", "x0_0.1"],
)
def test_profile_shifted_gear_is_a_valid_job(changes):
    job = parse_job(spur(**changes), SOURCE)
    assert job.gear.x == changes.get("gear__profile_shift", 0.0)


@pytest.mark.parametrize(
    ("changes", "tip"),
    [
        ({"gear__teeth": 12, "gear__profile_shift": 1.2}, 32.8),
        ({"gear__tip_diameter": 90.0}, 90.0),
        ({"gear__tip_diameter": 87.0}, 87.0),
    ],
    ids=["z12_x1.2", "tip_90", "tip_87"],
)
def test_pointed_gear(changes, tip):
    err = refused(spur(**changes), "gear.tip_diameter", tip, ("pointed", "s_an", "reduce the tip diameter"))
    assert err.keys == ["gear.tip_diameter"]


def test_slightly_larger_tip_diameter_is_still_valid():
    job = parse_job(spur(gear__tip_diameter=85.0), SOURCE)
    assert job.gear.tip_diameter_value == 85.0


def test_tip_below_root_external():
    refused(spur(gear__tip_diameter=70.0), "gear.tip_diameter", 70.0, ("must exceed the root diameter", "75.0000"))


def test_internal_tip_inside_base_circle():
    err = refused(internal(gear__tip_diameter=110.0), "gear.tip_diameter", 110.0, ("base circle", "not be involute"))
    assert err.keys == ["gear.tip_diameter"]


def test_internal_root_not_beyond_tip():
    refused(internal(gear__root_diameter=120.0), "gear.root_diameter", 120.0, ("must exceed its tip diameter",))


def test_cutter_with_too_few_teeth_is_undercut_itself():
    err = refused(spur(cutter__teeth=12), "cutter.profile_shift", 0.0, ("cutter's own teeth", "undercut", "z0 = 12"))
    assert "more cutter teeth" in problem(err, "cutter.profile_shift").hint


# ----------------------------------------------------------------------------------------------------
# cutters that cannot cut the gear
# ----------------------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("make", "cutter_helix", "need"),
    [
        (spur, 0.0, "a helical cutter"),  # spur gear, spur cutter: Sigma = 0 + 0
        (spur, 1.5, "a helical cutter"),  # |Sigma| = 1.5 deg < 2 deg
        (internal, 20.0, "a cutter helix other than +20.0 deg"),  # internal: Sigma = beta2 - beta0 = 20 - 20
    ],
    ids=["spur_spur", "spur_1.5deg", "internal_20_20"],
)
def test_shaft_angle_zero(make, cutter_helix, need):
    err = refused(make(cutter__helix_angle=cutter_helix), "cutter.helix_angle", cutter_helix, ("shaft angle", need))
    assert err.keys == ["cutter.helix_angle"]


def test_external_helical_with_opposite_cutter_helix_has_no_shaft_angle():
    # external: Sigma = beta2 + beta0 = 20 - 20
    err = refused(spur(gear__helix_angle=20.0, cutter__helix_angle=-20.0), "cutter.helix_angle", -20.0)
    assert "Sigma = +0.00 deg" in str(err)


def test_cutter_tip_interference_with_internal_gear():
    err = refused(internal_spur(cutter__teeth=50), "cutter.teeth", 50, ("interference", "internal gear"))
    assert err.keys == ["cutter.teeth"]
    assert "fewer cutter teeth" in problem(err, "cutter.teeth").hint


def test_smaller_cutter_in_internal_gear_is_valid():
    job = parse_job(internal_spur(cutter__teeth=40), SOURCE)
    assert job.cutter.z == 40
    # through the common rack, unshifted: a = r2 - r0 = mn z2 / 2 - mn z0 / (2 cos beta0) = 60 - 42.567 mm
    assert (job.gear.x, job.cutter.x) == (0.0, 0.0)
    r2, r0 = 2.0 * 60 / 2, 2.0 * 40 / (2 * math.cos(math.radians(20.0)))
    assert job.skiving.final_centre_distance == pytest.approx(r2 - r0, abs=1e-9)


@pytest.mark.parametrize("z0", [62, 60, 58])
def test_cutter_too_large_for_internal_spur_gear(z0):
    err = refused(internal_spur(cutter__teeth=z0), "cutter.teeth", z0, ("too large", "internal gear", "fewer teeth"))
    assert err.keys == ["cutter.teeth"]


@pytest.mark.parametrize(
    "z0",
    [
        62,
        61,
        60,
        58,
    ],
)
def test_cutter_too_large_for_internal_helical_gear(z0):
    err = refused(internal(cutter__teeth=z0), "cutter.teeth", z0)
    assert "too large" in str(err) or "interference" in str(err)


def test_infeed_deeper_than_the_tooth():
    passes = [2.0, 1.5, 1.0, 0.5]  # 5.0 mm on the 4.5 mm tooth
    err = refused(spur(process__passes=passes), "process.passes", passes, ("deeper than the tooth", "5.0000"))
    assert err.keys == ["process.passes"]
    assert "4.5000" in problem(err, "process.passes").hint


def test_infeed_deeper_than_the_tooth_internal():
    passes = [3.0, 2.0]
    err = refused(internal(process__passes=passes), "process.passes", passes, ("deeper than the tooth",))
    assert "at most 4.5000" in problem(err, "process.passes").hint


def test_infeed_exactly_the_tooth_depth_or_less_is_valid():
    assert parse_job(spur(process__passes=[4.5]), SOURCE).process.passes == [4.5]
    assert parse_job(spur(process__passes=[2.0, 1.0]), SOURCE).process.passes == [2.0, 1.0]


# ----------------------------------------------------------------------------------------------------
# several problems, thread jobs, files
# ----------------------------------------------------------------------------------------------------


def test_several_problems_are_all_reported():
    data = spur(gear__teeth="40", cutter__helix_angle=50.0, process__tool_speed=0.0)
    err = refused(data, "gear.teeth", "40")
    assert sorted(err.keys) == ["cutter.helix_angle", "gear.teeth", "process.tool_speed"]
    assert "(3 problems)" in str(err)
    assert "cutter.helix_angle = 50.0" in str(err)
    assert "process.tool_speed = 0.0" in str(err)


def test_problems_in_every_section_are_all_reported():
    data = spur(gear__colour="red", cutter__teeth=DELETE, process__feed_direction=3, machine__c1=-1.0)
    err = refused(data, "gear.colour", "red")
    assert sorted(err.keys) == ["cutter.teeth", "gear.colour", "machine.c1", "process.feed_direction"]


def test_undercut_reported_together_with_an_unrelated_bad_key():
    err = refused(spur(gear__teeth=12, process__tool_speed=0.0), "process.tool_speed", 0.0)
    assert "gear.profile_shift" in err.keys


def test_thread_job_with_a_gear_section_is_refused():
    data = thread()
    data["gear"] = copy.deepcopy(_SPUR["gear"])
    err = refused(data, "thread", "[thread] and [gear]", ("either a gear or a thread", "remove one"))
    assert err.keys == ["thread"]


def test_thread_job_values():
    job = parse_job(thread(), SOURCE)
    assert job.thread["lead"] == 1.75
    assert job.thread["length"] == 30.0
    assert set(job.thread) == set(THREAD_KEYS)
    assert not hasattr(job, "skiving") and not hasattr(job, "gear")  # a thread job has no gear and no skiving setup


def test_load_job_missing_file(tmp_path):
    path = tmp_path / "nope.toml"
    with pytest.raises(InputError) as info:
        load_job(path)
    err = info.value
    assert err.keys == ["job"]
    assert str(path) in str(err)
    assert "no such file" in str(err)
    assert ".toml job file" in str(err)


def test_load_job_directory_is_not_a_job(tmp_path):
    with pytest.raises(InputError, match="no such file"):
        load_job(tmp_path)


@pytest.mark.parametrize("text", ["[gear\nteeth = 40\n", "[gear]\nteeth = = 40\n", "[gear]\nteeth = 40\nteeth = 41\n"])
def test_load_job_broken_toml(tmp_path, text):
    path = tmp_path / "broken.toml"
    path.write_text(text, encoding="utf-8")
    with pytest.raises(InputError) as info:
        load_job(path)
    err = info.value
    assert err.keys == ["job"]
    assert err.source == str(path)
    assert str(path) in str(err)
    assert "not valid TOML" in str(err)
    assert "line" in str(err)


def test_load_job_reports_problems_with_the_file_name(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text((JOBS / "spur_external.toml").read_text(encoding="utf-8").replace("teeth = 40", "teeth = 12"))
    with pytest.raises(InputError) as info:
        load_job(path)
    assert info.value.keys == ["gear.profile_shift"]
    assert f"invalid input in {path}" in str(info.value)


SHIPPED = sorted(p.name for p in JOBS.glob("*.toml"))


@pytest.mark.parametrize("name", SHIPPED)
def test_shipped_jobs_load(name):
    job = load_job(JOBS / name)
    assert job.source == str(JOBS / name)
    data = tomllib.loads((JOBS / name).read_text(encoding="utf-8"))
    if "thread" in data:
        assert job.kind == "thread" and not hasattr(job, "gear")
    elif "coupling" in data:  # a face coupling by continuous indexing (seed 004)
        assert job.kind == "face_contour" and job.coupling.m == data["coupling"]["slots"]
    elif "turning" in data:  # vibration turning (seed 004) on the lathe: its feed set up as a lead
        assert job.kind == "turning" and job.thread["lead"] == job.turning["feed"] and not hasattr(job, "gear")
    elif "mill" in data:  # the copying method (seed 003): a gear cut by a profiled disc mill, no skiving setup
        assert job.kind == "form_milling" and job.mill["diameter"] > 0
        assert not hasattr(job, "cutter") and not hasattr(job, "skiving")
    else:
        assert job.kind == "skiving"
        assert job.skiving.full_depth == pytest.approx(sum(job.process.passes), abs=1e-6)


def test_the_four_job_files_are_shipped():
    assert {"default.toml", "helical_internal.toml", "spur_external.toml", "thread_m12.toml"} <= set(SHIPPED)


def test_default_job_path_exists_and_loads():
    path = default_job_path()
    assert path.is_file()
    assert path.resolve() == (JOBS / "default.toml").resolve()
    job = load_job(path)
    assert job.gear.z == 20 and job.gear.face_width == 4.0  # small: skive run in about two minutes, ISO-gradable
    assert job.machine.structure == "mechatronic"


def test_cutter_body_and_holder_reach_the_setup():
    job = parse_job(spur(cutter__width=25.0, cutter__holder_diameter=30.0), SOURCE)
    assert job.skiving.cutter.face_width == 25.0 and job.skiving.holder_diameter_value == 30.0
    default = parse_job(spur(), SOURCE).skiving
    assert default.cutter.face_width == 20.0  # 10 mn
    assert default.holder_diameter_value == pytest.approx(default.cutter.reference_diameter / 2)
    refused(spur(cutter__holder_diameter=-5.0), "cutter.holder_diameter", -5.0)


# ----------------------------------------------------------------------------------------------------
# the package: a head every job has, the kind's own sections in its Job subclass, one parser per kind
# ----------------------------------------------------------------------------------------------------

JOB_CLASSES = {
    "skiving": SkivingJob,
    "thread": ThreadJob,
    "form_milling": FormMillingJob,
    "face_contour": FaceContourJob,
    "turning": TurningJob,
}
#: the sections some kinds have and others not
SECTION_NAMES = (
    "gear",
    "cutter",
    "cutter_options",
    "thread",
    "measurement",
    "modification",
    "mill",
    "turning",
    "vibration",
    "coupling",
)


def test_every_kind_has_a_parser_and_a_process():
    from virtual_machine.processes import PROCESSES

    assert set(KINDS) == set(JOB_CLASSES) == set(PROCESSES)


@pytest.mark.parametrize("name", SHIPPED)
def test_a_job_has_only_its_kinds_sections(name):
    """A job is its kind's class: the sections of its kind are its fields, those of other kinds are not there at all
    (no job.gear that is None for a thread job)."""
    job = load_job(JOBS / name)
    assert type(job) is JOB_CLASSES[job.kind] and job.kind == type(job).kind
    own = {f.name for f in dataclasses.fields(job)} - {"source", "machine", "process"}
    for section in SECTION_NAMES:
        assert hasattr(job, section) == (section in own), section


@pytest.mark.parametrize("name", SHIPPED)
def test_machine_and_process_are_parsed_once_into_typed_sections(name):
    """[machine] and [process] are frozen dataclasses with a field per declared key, the file's values (or the
    defaults) in the declared types: read as job.process.tool_speed, never as a string lookup."""
    path = JOBS / name
    job = load_job(path)
    raw = tomllib.loads(path.read_text())
    for section in ("machine", "process"):
        typed = getattr(job, section)
        assert dataclasses.is_dataclass(typed) and not isinstance(typed, dict)
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(typed, dataclasses.fields(typed)[0].name, None)
        for f in dataclasses.fields(typed):
            key = f.metadata.get("key")
            given = raw.get(section, {}).get(f.name)
            if key is None or given is None or isinstance(given, dict):
                continue
            value = getattr(typed, f.name)
            assert value == given and (not isinstance(key.kind, type) or isinstance(value, key.kind)), f.name


def test_the_skiving_setup_is_made_once():
    job = parse_job(spur(), SOURCE)
    assert job.skiving is job.skiving


def test_a_section_is_replaced_on_the_job():
    job = parse_job(thread(), SOURCE)
    longer = dataclasses.replace(job, thread={**job.thread, "length": 40.0})
    assert longer.thread["length"] == 40.0 and job.thread["length"] != 40.0 and longer.machine is job.machine
