"""`skive check --confidence` (virtual_machine/studies/population.py; issue 43): a verdict for a population of
machines drawn from a size's geometric tolerances (machine_models/geometry_tolerances.py) and cutters from a class."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from small_jobs import small_job

from cutting.errors import InputError
from machine_models.geometry_tolerances import PHASED, SIGNED, geometry_tolerances
from virtual_machine.cli import main
from virtual_machine.studies.design import cases, design
from virtual_machine.studies.population import wilson_lower
from virtual_machine.studies.spec import load_study


def test_wilsons_lower_bound_is_the_hand_worked_one() -> None:
    """p = 0.5 over 100 samples, z = 1.645: (0.5 + z^2/200 - z sqrt(0.25/100 + z^2/40000)) / (1 + z^2/100) = 0.4188
    (worked by hand); all 59 of 59: 0.955 (59 is the classic sample for 95 % at 95 %); none: 0."""
    assert wilson_lower(0.5, 100) == pytest.approx(0.4188, abs=1e-4)
    assert wilson_lower(1.0, 59) == pytest.approx(59 / (59 + 1.6449**2), rel=1e-9)
    assert wilson_lower(0.0, 10) == 0.0


def test_a_study_draws_machines_within_a_sizes_tolerances(tmp_path: Path) -> None:
    """machine_tolerances = "medium": every signed error uniform within +-its tolerance, every once-per-turn one's
    amplitude in [0, tolerance] at any phase; the same seed draws the same machines; a size that is not one, or a
    study that is not a Monte Carlo, is refused."""
    (tmp_path / "job.toml").write_text(small_job(edge=None, face_width=4.0))
    (tmp_path / "s.toml").write_text('base = "job.toml"\nmethod = "monte-carlo"\nsamples = 200\nseed = 3\n'
                                     'machine_tolerances = "medium"\nstage = "cut"\n')  # fmt: skip
    study = load_study(tmp_path / "s.toml")
    rows = design(study)
    t = geometry_tolerances("medium")
    assert t["work_spindle_radial_error"] == pytest.approx(1.25 * 0.002)
    for name in SIGNED:
        v = np.array([r[f"machine.model.geometry.{name}"] for r in rows])
        assert np.abs(v).max() <= t[name] and v.min() < -0.8 * t[name] and v.max() > 0.8 * t[name], name
    for name, phase in PHASED.items():
        v = np.array([r[f"machine.model.geometry.{name}"] for r in rows])
        p = np.array([r[f"machine.model.geometry.{phase}"] for r in rows])
        assert 0 <= v.min() and v.max() <= t[name] and 0 <= p.min() and p.max() < 360, name
    assert [c.job_text for c in cases(study)] == [c.job_text for c in cases(load_study(tmp_path / "s.toml"))]
    assert study.stage == "cut"
    for bad, words in [('machine_tolerances = "huge"\nmethod = "monte-carlo"', "unknown machine size"),
                       ('machine_tolerances = "small"\nmethod = "grid"', "Monte-Carlo")]:  # fmt: skip
        (tmp_path / "b.toml").write_text(f'base = "job.toml"\nsamples = 4\n{bad}\n')
        with pytest.raises(InputError, match=words):
            load_study(tmp_path / "b.toml")


def test_check_answers_for_a_population_and_fails_it_below_the_confidence(tmp_path: Path) -> None:
    """`skive check JOB --max-class 6 --confidence 0.9 --samples 2 --stage cut`: both cut gears (small machines
    within their tolerances, the job's cutter) are class 7 (its feed marks), so P(class <= 6) = 0 < 0.9: exit 1, the
    JSON's population (samples, P, its lower bound, the class counts) and the JUnit report's failure say so."""
    job = tmp_path / "job.toml"
    job.write_text(small_job(edge=None, face_width=4.0))
    result = CliRunner().invoke(
        main, ["check", str(job), "--max-class", "6", "--confidence", "0.9", "--samples", "2", "--stage", "cut",
               "--workers", "0", "--out", str(tmp_path / "o"), "--json", "--junit", str(tmp_path / "j.xml")],
    )  # fmt: skip
    assert result.exit_code == 1, result.output
    doc = json.loads(result.output)
    pop = doc["population"]
    assert pop["samples"] == 2 and pop["p_at_most"] == 0.0 and not doc["pass"]
    assert sum(pop["class_counts"].values()) == 2 and all(int(c) > 6 for c in pop["class_counts"])
    assert math.isclose(pop["p_lower_95"], 0.0)
    junit = (tmp_path / "j.xml").read_text()
    assert 'failures="1"' in junit and "P(class &lt;= 6) = 0.00 over 2 machines and cutters" in junit
    assert (tmp_path / "o" / "population" / "results.csv").is_file()
