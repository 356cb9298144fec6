"""The cutter's tolerance classes (cutting/skiving/cutter_classes.py): DIN 3968's figures by class and module, as the
cited catalogue prints them (known answers read off its table)."""

from __future__ import annotations

from pathlib import Path

import pytest

from cutting.skiving.cutter_classes import cutter_tolerances


@pytest.mark.parametrize(
    ("cls", "module", "expected"),
    [
        ("AA", 2.0, {"radial_runout": 12, "axial_runout": 3, "pitch": 12, "profile": 6}),  # > 1.6-2.5 (spur_external)
        ("A", 1.0, {"radial_runout": 12, "axial_runout": 3, "pitch": 12, "profile": 10}),  # > 0.63-1 (upper edge)
        ("B", 6.3, {"radial_runout": 63, "axial_runout": 6, "pitch": 63, "profile": 32}),  # > 4-6.3
        ("A", 6.31, {"radial_runout": 40, "axial_runout": 8, "pitch": 40, "profile": 20}),  # > 6.3-10
    ],
)
def test_the_tolerances_are_the_tables(cls: str, module: float, expected: dict) -> None:
    got = cutter_tolerances(cls, module)
    assert got == pytest.approx({k: v * 1e-3 for k, v in expected.items()})


def test_a_class_or_module_outside_the_table_is_refused() -> None:
    with pytest.raises(ValueError, match="use one of AA, A, B"):
        cutter_tolerances("C1", 2.0)
    with pytest.raises(ValueError, match=r"covers 0\.63-40 mm"):
        cutter_tolerances("AA", 0.5)


def test_a_monte_carlo_study_draws_its_cutters_from_a_class(tmp_path) -> None:
    """`cutter_class = "A"` in a Monte-Carlo study: every case's cutter within class A's tolerances for the base
    job's module (the default job, mn 1: runout 12 um, axial 3 um, pitch +-12 um, profile 10 um), each deviation a
    part of the budget with its tolerance; the same seed, the same cutters; refused outside a Monte-Carlo study."""
    import tomllib

    from cutting.errors import InputError
    from virtual_machine.job import parse_job
    from virtual_machine.studies.design import cases
    from virtual_machine.studies.spec import load_study

    base = Path(__file__).resolve().parent.parent / "assets" / "jobs" / "default.toml"
    path = tmp_path / "study.toml"
    path.write_text(f'base = "{base}"\nmethod = "monte-carlo"\nsamples = 6\nseed = 3\ncutter_class = "A"\n')
    study = load_study(path)
    tol = {v.key.split(".")[-1]: v.tolerance for v in study.varies}
    assert tol["radial_runout"] == pytest.approx(0.012) and tol["axial_runout"] == pytest.approx(0.003)
    assert tol["profile_slope_left"] == pytest.approx(0.005) and tol["profile_form_right"] == pytest.approx(0.005)
    made = cases(study)
    assert len(made) == 6 and [c.job_text for c in made] == [c.job_text for c in cases(load_study(path))]
    teeth = set()
    for case in made:
        job = parse_job(tomllib.loads(case.job_text))
        e = job.skiving.cutter_errors
        assert 0 <= e.radial_runout <= 0.012 and 0 <= e.axial_runout <= 0.003
        assert len(e.pitch) == job.cutter.teeth and max(map(abs, e.pitch)) <= 0.012 + 1e-12
        assert abs(sum(e.pitch)) < 1e-9 and all(abs(s) <= 0.005 for s in e.profile_slope)
        teeth.add(e.pitch)
    assert len(teeth) == 6  # a fresh random cutter each case
    path.write_text(f'base = "{base}"\ncutter_class = "A"\n[[vary]]\nkey = "machine.encoder_lines"\nvalues = [4000]\n')
    with pytest.raises(InputError, match="Monte-Carlo"):
        load_study(path)
