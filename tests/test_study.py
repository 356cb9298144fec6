"""skive study: study files checked before anything runs, the designs, the error budget on cases with a known
answer, and studies run on Dask (a LocalCluster started here) against the scenarios' theory."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from dask.distributed import LocalCluster
from small_jobs import small_job

from cutting.errors import InputError
from metrology import tolerances as iso
from virtual_machine.cli import main
from virtual_machine.job import load_job
from virtual_machine.setting.sheet import setup_sheet
from virtual_machine.studies import pipeline
from virtual_machine.studies.budget import column_sensitivity, error_budget, graded
from virtual_machine.studies.design import cases, design
from virtual_machine.studies.spec import load_study

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "assets" / "jobs" / "scenarios"
DEFAULT = ROOT / "assets" / "jobs" / "default.toml"


def study_file(tmp: Path, text: str, base: Path = DEFAULT, name: str = "study.toml") -> Path:
    path = tmp / name
    path.write_text(f'base = "{base}"\n' + text)
    return path


# ---- study files: every problem before any case runs ------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "key", "words"),
    [
        (
            '[[vary]]\nkey = "machine.model.work_drive.backlsh"\nvalues = [1e-4]\n',
            "machine.model.work_drive.backlsh",
            "unknown drive stage field",
        ),
        ('[[vary]]\nkey = "machine.encoder_line"\nvalues = [1000]\n', "machine.encoder_line", "machine.encoder_lines"),
        (
            '[[vary]]\nkey = "machine.model.tool_drive.stiffness"\nrange = [4e4, 1e4]\nsteps = 3\n',
            "machine.model.tool_drive.stiffness.range",
            "empty range",
        ),
        (
            '[[vary]]\nkey = "machine.model.lead_screw_pitch_error"\nvalues = []\n',
            "machine.model.lead_screw_pitch_error.values",
            "empty",
        ),
        ('[[vary]]\nkey = "machine.encoder_lines"\nvalues = [1000, 0]\n', "machine.encoder_lines", "case c002"),
        ('[[vary]]\nkey = "machine.model.work_drive.backlash"\nvalues = [-1e-4]\n', "machine.model", "backlash"),
        ('method = "latin"\n[[vary]]\nkey = "machine.encoder_lines"\nvalues = [1000]\n', "method", "unknown method"),
        (
            '[[vary]]\nkey = "machine.encoder_lines"\ndistribution = "normal"\nstd = 10\n',
            "machine.encoder_lines.distribution",
            "only a Monte-Carlo study draws",
        ),
        (
            'method = "monte-carlo"\nsamples = 4\n[[vary]]\nkey = "machine.encoder_lines"\ndistribution = "normal"\n',
            "machine.encoder_lines.std",
            "std > 0",
        ),
        ("", "vary", "varies nothing"),
        (
            'method = "monte-carlo"\nsamples = 1\n[[vary]]\nkey = "machine.encoder_lines"\ndistribution = "uniform"\n'
            "lo = 1000\nhi = 5000\n",
            "samples",
            "samples >= 2",
        ),
        (
            '[[vary]]\nkey = "machine.encoder_lines"\nvalues = [1000]\n'
            '[[vary]]\nkey = "machine.encoder_lines"\nvalues = [2000]\n',
            "vary[1].key",
            "varied twice",
        ),
        (
            'method = "monte-carlo"\nsamples = 4\n[[vary]]\nkey = "machine.encoder_lines"\ndistribution = "uniform"\n'
            "lo = 5000\nhi = 5000\n",
            "machine.encoder_lines.lo",
            "lo < hi",
        ),
        ("# no base\n", "base", "missing"),
    ],
)
def test_bad_study_files_fail_before_any_case_runs(tmp_path, text, key, words) -> None:
    path = study_file(tmp_path, text)
    if text.startswith("# no base"):
        path.write_text('[[vary]]\nkey = "machine.encoder_lines"\nvalues = [1000]\n')
    with pytest.raises(InputError) as err:
        cases(load_study(path))
    assert key in err.value.keys, err.value
    assert words in str(err.value)
    out = tmp_path / "out"
    res = CliRunner().invoke(main, ["study", str(path), "--out", str(out)])
    assert res.exit_code == 2 and key in res.output, res.output
    assert not out.exists()  # nothing ran, nothing was written


def test_designs(tmp_path) -> None:
    """One-at-a-time: the base, then each part's values (the base value not twice); grid: every combination;
    Monte Carlo: the seed fixes the draws, integers stay integers."""
    oat = load_study(
        study_file(
            tmp_path,
            (
                '[[vary]]\nkey = "machine.encoder_lines"\nvalues = [1000, 5000, 2500]\n'
                '[[vary]]\nkey = "machine.adaptive_correction"\nvalues = [false]\n'
            ),
        )
    )
    rows = design(oat)
    assert rows[0] == {"machine.encoder_lines": 5000, "machine.adaptive_correction": True}
    assert [r["machine.encoder_lines"] for r in rows] == [5000, 1000, 2500, 5000]
    assert [c.id for c in cases(oat)] == ["c000", "c001", "c002", "c003"]
    grid = load_study(
        study_file(
            tmp_path,
            (
                'method = "grid"\n[[vary]]\nkey = "machine.encoder_lines"\nrange = [1000, 3000]\nsteps = 3\n'
                '[[vary]]\nkey = "machine.model.lead_screw_pitch_error"\nvalues = [0.0, 1e-4]\n'
            ),
        )
    )
    assert len(design(grid)) == 6 and design(grid)[1] == {
        "machine.encoder_lines": 1000,
        "machine.model.lead_screw_pitch_error": 1e-4,
    }
    mc = 'method = "monte-carlo"\nsamples = 5\nseed = {}\n[[vary]]\nkey = "machine.encoder_lines"\n' + (
        'distribution = "uniform"\nlo = 1000\nhi = 5000\n'
    )
    a, b, c = (
        design(load_study(study_file(tmp_path, mc.format(s), name=f"mc{s}{n}.toml"))) for n, s in enumerate((1, 1, 2))
    )
    assert a == b and a != c
    assert all(isinstance(r["machine.encoder_lines"], int) for r in a)
    assert [x.job_hash for x in cases(load_study(study_file(tmp_path, mc.format(1), name="m.toml")))] == [
        x.job_hash for x in cases(load_study(study_file(tmp_path, mc.format(1), name="n.toml")))
    ]


# ---- the budget on cases with a known answer --------------------------------------------------------------------

GEAR = (20, 1.0, 4.0, 0.0, 3)  # the default job's gear: z, mn, b, beta, k


def record(cid: str, values: dict, helix: float, pitch: float, status: str = "ok") -> dict:
    measured = {
        f"{n}_{s}": 0.1 for n in ("F_alpha", "f_falpha", "F_beta", "f_fbeta", "f_p", "F_pk") for s in ("left", "right")
    }
    measured.update(
        {
            "f_Hbeta_left": -helix,
            "f_Hbeta_right": helix,
            "F_p_left": pitch,
            "F_p_right": pitch - 1,
            "f_Halpha_left": 0.1,
            "f_Halpha_right": -0.1,
            "F_r": 0.1,
        }
    )
    return {"id": cid, "values": values, "status": status, "measured": measured, "error": "", "wall_s": 1.0}


def test_one_at_a_time_budget_and_the_tightening_that_reaches_a_class(tmp_path) -> None:
    """f_Hbeta = 2 + 1e4 eps (um) and F_p = 3 + 0.02 (c - 100) over two parts with stated tolerances: the
    sensitivities, the worst-case stack and the tolerance that reaches the target class follow exactly."""
    study = load_study(
        study_file(
            tmp_path,
            (
                '[[vary]]\nkey = "machine.model.lead_screw_pitch_error"\nvalues = [-2e-4, 2e-4]\ntolerance = 8e-4\n'
                'label = "screw"\n'
                '[[vary]]\nkey = "machine.model.tool_drive.stiffness"\nvalues = [1e4, 4e4]\ntolerance = 5e3\n'
            ),
        )
    )
    records = {}
    for c in cases(study):
        eps = c.values["machine.model.lead_screw_pitch_error"]
        k = c.values["machine.model.tool_drive.stiffness"]
        records[c.id] = record(c.id, c.values, 2.0 + 1e4 * abs(eps) * np.sign(eps + 1e-12), 3.0 + 1e-4 * (k - 2e4))
    records["c099"] = record("c099", {}, 0, 0, status="failed")
    budget = error_budget(study, records, GEAR, target=4)
    assert budget.cases_ok == 5 and budget.cases_failed == 1
    helix = next(p for p in budget.parameters if p.name == "f_Hbeta")
    screw = next(e for e in helix.parts if e.key.endswith("pitch_error"))
    assert screw.sensitivity == pytest.approx(1e4) and screw.contribution == pytest.approx(8.0)
    assert helix.base == pytest.approx(2.0) and helix.stacked == pytest.approx(10.0)
    tol = iso.tolerances(4, *GEAR)["f_Hbeta"]
    assert helix.answer.tolerance == tol and not helix.answer.meets and helix.answer.limiting == "screw"
    assert helix.answer.required == pytest.approx((tol - 2.0) / 1e4)
    pitch = next(p for p in budget.parameters if p.name == "F_p")
    stiff = next(e for e in pitch.parts if e.key.endswith("stiffness"))
    assert stiff.sensitivity == pytest.approx(1e-4) and stiff.contribution == pytest.approx(0.5)
    assert stiff.low == (1e4, pytest.approx(2.0)) and stiff.high == (4e4, pytest.approx(5.0))
    assert pitch.answer.meets
    signed = column_sensitivity(study, records, "f_Hbeta_left")
    assert signed["machine.model.lead_screw_pitch_error"] == pytest.approx(-1e4)


def test_a_part_that_cannot_reach_the_class_alone_is_said_so() -> None:
    """Base 3 um, part A 2 um and part B 4 um at their tolerances against a 6 um class tolerance: B limits, but A
    and the base leave it 1 um, so B needs 1/4 of its tolerance; against 4.5 um nothing is left for B."""
    from virtual_machine.studies.budget import ParameterBudget, PartEffect, _answer_stack, _stack

    def budget():
        parts = [
            PartEffect("a", "part A", 2.0, (0, 0), (1, 2), 1.0, 2.0),
            PartEffect("b", "part B", -8.0, (0, 0), (1, -8), 0.5, 4.0),
        ]
        return _stack("F_p", 3.0, parts)

    p: ParameterBudget = budget()
    assert p.stacked == pytest.approx(9.0) and [e.label for e in p.parts] == ["part B", "part A"]
    fine = _answer_stack(p, 6.0, 5, None)
    assert fine.limiting == "part B" and fine.required == pytest.approx(1.0 / 8.0) and not fine.meets
    stuck = _answer_stack(budget(), 4.5, 5, None)
    assert stuck.limiting == "part B" and stuck.required is None
    assert "base case (3.00 um) and the other parts' tolerances (2.00 um)" in stuck.note


def test_grid_budget_fits_every_case_at_once(tmp_path) -> None:
    """F_p = 3 + 2e3 eps + 1e-4 (k - 2e4) on a 3 x 2 grid that does not hold the base: the fit gives both
    sensitivities and the value at the base; the worst case stacks the stated tolerances on it."""
    study = load_study(
        study_file(
            tmp_path,
            (
                'method = "grid"\n[[vary]]\nkey = "machine.model.lead_screw_pitch_error"\nvalues = [1e-4, 2e-4, 3e-4]\n'
                "tolerance = 1e-4\n"
                '[[vary]]\nkey = "machine.model.tool_drive.stiffness"\nvalues = [1e4, 3e4]\ntolerance = 2e3\n'
            ),
        )
    )
    records = {}
    for c in cases(study):
        eps, k = c.values["machine.model.lead_screw_pitch_error"], c.values["machine.model.tool_drive.stiffness"]
        records[c.id] = record(c.id, c.values, 0.5, 3.0 + 2e3 * eps + 1e-4 * (k - 2e4))
    assert len(records) == 6
    pitch = next(p for p in error_budget(study, records, GEAR).parameters if p.name == "F_p")
    by = {e.key: e for e in pitch.parts}
    assert by["machine.model.lead_screw_pitch_error"].sensitivity == pytest.approx(2e3)
    assert by["machine.model.tool_drive.stiffness"].sensitivity == pytest.approx(1e-4)
    assert pitch.base == pytest.approx(3.0) and pitch.stacked == pytest.approx(3.0 + 0.2 + 0.2)


def test_monte_carlo_variance_shares(tmp_path) -> None:
    """F_p = 20 + 3e3 eps + 2e-4 (k - 2e4), eps and k drawn: the fit recovers both sensitivities, the variance
    shares b_i cov(x_i, F_p) / var(F_p) sum to 1 (no residual) and are b_i^2 var(x_i) / var(F_p) up to the
    sample's chance correlation of the draws, and the 95th percentile is the cases'."""
    study = load_study(
        study_file(
            tmp_path,
            (
                'method = "monte-carlo"\nsamples = 40\nseed = 3\n'
                '[[vary]]\nkey = "machine.model.lead_screw_pitch_error"\n'
                'distribution = "normal"\nmean = 0.0\nstd = 1e-3\n'
                '[[vary]]\nkey = "machine.model.tool_drive.stiffness"\n'
                'distribution = "uniform"\nlo = 1.5e4\nhi = 2.5e4\n'
            ),
        )
    )
    rows = design(study)
    eps = np.array([r["machine.model.lead_screw_pitch_error"] for r in rows])
    k = np.array([r["machine.model.tool_drive.stiffness"] for r in rows])
    fp = 20 + 3e3 * eps + 2e-4 * (k - 2e4)
    records = {f"c{i:03d}": record(f"c{i:03d}", r, 0.5, float(fp[i])) for i, r in enumerate(rows)}
    pitch = next(p for p in error_budget(study, records, GEAR, target=5).parameters if p.name == "F_p")
    by = {e.key: e for e in pitch.parts}
    assert by["machine.model.lead_screw_pitch_error"].sensitivity == pytest.approx(3e3)
    assert by["machine.model.tool_drive.stiffness"].sensitivity == pytest.approx(2e-4)
    share = 9e6 * np.var(eps, ddof=1) / np.var(fp, ddof=1)
    assert by["machine.model.lead_screw_pitch_error"].share == pytest.approx(share, abs=0.02)
    assert sum(e.share for e in pitch.parts) == pytest.approx(1.0) and pitch.residual_share == pytest.approx(
        0, abs=1e-9
    )
    assert pitch.stacked == pytest.approx(np.percentile(fp, 95)) and pitch.base == pytest.approx(fp.mean())


# ---- the case store: cases a study takes instead of running them -------------------------------------------------


def stored_result(helix: float) -> dict:
    """A finished case's result as a worker returns it, with a measurement that has every results.csv column."""
    from virtual_machine.studies.runner import FLANK_COLUMNS, SIDES

    doc: dict = {block: {side: {} for side in SIDES} for block in ("profile", "helix", "pitch")}
    for block, name in FLANK_COLUMNS:
        for side, sign in zip(SIDES, (-1, 1), strict=True):
            doc[block][side][name] = sign * helix if name.startswith("f_Hbeta") else 1.5
    doc["runout"] = {"F_r": 2.0}
    doc["iso1328"] = {"class": {"overall": 5}}
    doc["run"] = {"synchronisation": {"sync_error_in_cut": {"rms_um": 0.25}}}
    return {"id": "x", "status": "ok", "error": "", "wall_s": 12.0, "measurement": doc}


@pytest.mark.slow
def test_a_study_takes_the_cases_its_case_store_holds(tmp_path) -> None:
    """A study file's ``cache = "DIR"``: a case whose job the store holds is not run; its stored result is the
    case's, and result.json, the report and the study run say it was reused. The store is keyed by the job's
    content: the default job file as written (comments, its own layout) is the study's base case. A failed case is
    not stored."""
    from virtual_machine.studies.cache import CaseCache, content_key

    path = study_file(tmp_path, 'cache = "store"\n[[vary]]\nkey = "machine.encoder_lines"\nvalues = [1000]\n')
    study = load_study(path)
    assert study.cache == (tmp_path / "store").resolve()
    base, coarse = cases(study)
    text = DEFAULT.read_text()
    assert base.job_text != text and content_key(base.job_text) == content_key(text)
    assert content_key(coarse.job_text) != content_key(text)
    store = CaseCache(study.cache)
    assert store.put(text, stored_result(3.0)) and store.put(coarse.job_text, stored_result(4.5))
    assert not store.put(text + "# again\n", {**stored_result(9.0), "status": "failed"}) and len(store) == 2
    outcome = pipeline.run(path, tmp_path / "out", target=6)  # nothing to run: no cluster starts
    assert outcome.run.reused == ["c000", "c001"] and outcome.run.ran == [] and outcome.run.workers == 0
    table = rows(outcome.run.csv)
    assert [(r["case"], r["status"], r["f_Hbeta_right"]) for r in table] == [
        ("c000", "ok", "3.0"),
        ("c001", "ok", "4.5"),
    ]
    record = json.loads((tmp_path / "out" / "cases" / "c001" / "result.json").read_text())
    assert record["reused"] and record["job_hash"] == coarse.job_hash and record["measured"]["class"] == 5
    sensitivity = column_sensitivity(outcome.study, outcome.run.results, "f_Hbeta_right")
    assert sensitivity["machine.encoder_lines"] == pytest.approx((4.5 - 3.0) / (1000 - 5000))
    assert "2 reused from the case store" in outcome.report.read_text()
    # the command line says so too, and its bar has nothing to run (a fresh output: every case from the store)
    res = CliRunner().invoke(main, ["study", str(path), "--out", str(tmp_path / "cli")])
    assert res.exit_code == 0, res.output
    assert "0 run now, 0 already done, 2 reused from the case store" in res.output
    with pytest.raises(InputError) as err:
        load_study(study_file(tmp_path, 'cache = 3\n[[vary]]\nkey = "machine.encoder_lines"\nvalues = [1000]\n'))
    assert "cache" in err.value.keys


# ---- studies on Dask ----------------------------------------------------------------------------------------------


class StudyStoppedError(Exception):
    pass


def rows(path: Path) -> list[dict]:
    """results.csv without the wall time (the one column that depends on the machine's load)."""
    with path.open() as fh:
        return [{k: v for k, v in r.items() if k != "wall_s"} for r in csv.DictReader(fh)]


@pytest.fixture(scope="module")
def cluster():
    """A cluster that runs on its own, reached by its scheduler's address as on a real cluster: one single-threaded
    worker, started once for the studies of this file that run on it (each start spawns the worker and imports skive
    in it again). Its HTTP server on a free port: a study's own cluster takes the default one."""
    with LocalCluster(n_workers=1, threads_per_worker=1, dashboard_address=":0") as made:
        yield made


@pytest.fixture(scope="module")
def small_study(tmp_path_factory, cluster):
    """The tests' small job (z 18, b 2 mm: below ISO 1328-1's range, so no classes) with a tool motor too weak to
    hold the cut (that case fails: refused before its run) and a long lead screw, once on two workers straight
    through (a cluster of its own), once on the one worker of ``cluster`` interrupted after its first case and
    resumed. A Dask worker cannot stop a case it has started: the case after the interruption runs on, unused, and
    the resumed study runs it again. So the weak motor's case, refused at once, comes second and is that case (the
    interruption on two workers left a whole run of the job behind)."""
    tmp = tmp_path_factory.mktemp("study")
    (tmp / "small.toml").write_text(small_job(sweep_error=0.02, axial_feed=0.4))
    path = study_file(
        tmp,
        (
            '[[vary]]\nkey = "machine.model.tool_motor_torque"\nvalues = [0.5]\n'
            '[[vary]]\nkey = "machine.model.lead_screw_pitch_error"\nvalues = [0.01]\n'
        ),
        base=tmp / "small.toml",
    )
    two = pipeline.run(path, tmp / "two", workers=2, target=5)

    def stop(case_id, record, done, failed, total):
        raise StudyStoppedError(case_id)

    with pytest.raises(StudyStoppedError):
        pipeline.run(path, tmp / "one", scheduler=cluster.scheduler_address, on_case=stop)
    first = rows(tmp / "one" / "results.csv")
    one = pipeline.run(path, tmp / "one", scheduler=cluster.scheduler_address, target=5)
    return path, one, first, two


@pytest.mark.slow
def test_one_and_two_workers_and_a_resumed_study_give_the_same_table(small_study) -> None:
    path, one, first, two = small_study
    assert len(first) == 1  # the interrupted study kept its finished case
    assert one.run.skipped == [first[0]["case"]] and len(one.run.ran) == 2 and one.run.workers == 1
    assert two.run.workers == 2 and len(two.run.ran) == 3
    assert rows(one.run.csv) == rows(two.run.csv)
    table = rows(one.run.csv)
    assert [r["case"] for r in table] == ["c000", "c001", "c002"]
    assert [r["status"] for r in table] == ["ok", "failed", "ok"]
    # refused before its run: the estimated cutting torque exceeds the motor's
    # (virtual_machine/reach/skiving_load.py)
    assert table[1]["error"].startswith("MachineLimitError") and "M1" in table[1]["error"]
    # the table holds each case's own measurement (the figures of cases/c000/measurement.json)
    doc = json.loads((one.run.csv.parent / "cases" / "c000" / "measurement.json").read_text())
    stats = doc["run"]["synchronisation"]["sync_error_in_cut"]
    sync = stats["rms_um"]
    assert float(table[0]["sync_rms_um"]) == pytest.approx(sync, rel=1e-9)
    # its figures hang together (RMS^2 = mean^2 + RMS about the mean^2), and equal coordinates hold the mean within
    # one command pulse: 2 pi r2 / p = 2 pi 9 mm / 10000 = 5.65 um of arc on the reference circle
    sheet = json.loads(CliRunner().invoke(main, ["setup", str(path.parent / "small.toml"), "--json"]).output)
    r2 = load_job(path.parent / "small.toml").gear.reference_radius
    pulse_um = 2 * math.pi * r2 / sheet["constants"]["p_cmd"] * 1e3
    assert sync**2 == pytest.approx(stats["mean_um"] ** 2 + stats["rms_about_mean_um"] ** 2, rel=1e-9)
    assert 0 < sync and abs(stats["mean_um"]) <= pulse_um
    assert float(table[0]["F_alpha_left"]) == pytest.approx(doc["profile"]["left"]["F_alpha"], rel=1e-9)
    assert table[0]["class"] == "" and "ISO 1328-1" in one.budget.iso_error  # b = 2 mm: no classes, said so
    for name in ("report.html", "budget.json", "cases/c002/measurement.json", "cases/c001/result.json"):
        assert (one.run.csv.parent / name).is_file(), name
    assert "outside ISO 1328-1" in one.report.read_text()
    # the command line on the finished study: nothing runs again, the budget and the report are written anew
    res = CliRunner().invoke(main, ["study", str(path), "--out", str(one.run.csv.parent), "--target-class", "5"])
    assert res.exit_code == 0, res.output
    assert "0 run now" in res.output and "3 already done" in res.output and "no ISO 1328-1 classes" in res.output


@pytest.mark.slow
def test_a_studys_lead_screw_sensitivity_is_the_theory(tmp_path, shared_runs) -> None:
    """The helical scenario baseline and a 1 % long lead screw: the study's sensitivity of f_Hbeta is
    L_beta tan(beta_b) per unit of eps, opposite on the flanks (the scenario test's theory), within 5 %; the
    budget's contribution is that sensitivity times the stated tolerance. Its two cases are the scenario jobs
    helical_mechatronic and lead_screw_error: the study takes their runs from the session's case store (run once,
    shared with test_scenarios.py) instead of running them again."""
    for name in ("helical_mechatronic", "lead_screw_error"):
        shared_runs.run(SCENARIOS / f"{name}.toml")
    path = study_file(
        tmp_path,
        '[[vary]]\nkey = "machine.model.lead_screw_pitch_error"\nvalues = [0.01]\ntolerance = 8e-5\n',
        base=SCENARIOS / "helical_mechatronic.toml",
    )
    one = pipeline.run(path, tmp_path / "out", workers=2, target=5, cache=shared_runs.cache.directory)
    assert one.run.reused == ["c000", "c001"] and one.run.ran == []
    job = load_job(SCENARIOS / "helical_mechatronic.toml")
    g = job.gear
    doc = (tmp_path / "out" / "cases" / "c001" / "measurement.json").read_text()
    z0, z1 = json.loads(doc)["evaluation"]["helix_z_mm"]
    tan_beta_b = math.tan(g.beta) * math.cos(math.atan(math.tan(g.alpha_n) / math.cos(g.beta)))
    theory = (z1 - z0) * tan_beta_b * 1e3  # um per unit of eps
    for side, sign in (("left", -1), ("right", 1)):
        s = column_sensitivity(one.study, one.run.results, f"f_Hbeta_mean_{side}")
        assert s["machine.model.lead_screw_pitch_error"] == pytest.approx(sign * theory, rel=0.05), (side, s)
    helix = next(p for p in one.budget.parameters if p.name == "f_Hbeta")
    screw = next(e for e in helix.parts if e.key.endswith("pitch_error"))
    assert screw.contribution == pytest.approx(abs(screw.sensitivity) * 8e-5)
    page = one.report.read_text()
    assert "lead_screw_pitch_error" in page and "data:image/png;base64," in page


@pytest.mark.slow
def test_a_studys_change_gear_error_is_the_setting_sheets_drift(tmp_path, shared_runs, cluster) -> None:
    """S1 without a 17-tooth change gear (the scenario) against the same machine with one: the helix tilt between
    the two cases is the drift the setting sheet predicts for the realised ix, over L_beta, within 5 %. The base
    case is the scenario's run from the session's case store; the case with 17 runs on Dask (the file's cluster,
    its worker started already) and is stored."""
    base = SCENARIOS / "mechanical_change_gears.toml"
    shared_runs.run(base)
    job = load_job(base)
    with_17 = sorted([*job.machine.change_gears, 17])
    path = study_file(tmp_path, f'[[vary]]\nkey = "machine.change_gears"\nvalues = [{with_17}]\n', base=base)
    outcome = pipeline.run(
        path, tmp_path / "out", scheduler=cluster.scheduler_address, cache=shared_runs.cache.directory
    )
    res = outcome.run.results
    assert [res[c]["status"] for c in ("c000", "c001")] == ["ok", "ok"]
    assert outcome.run.reused == ["c000"] and outcome.run.ran == ["c001"]
    (case,) = (c for c in cases(outcome.study) if c.id == "c001")
    assert shared_runs.cache.get(case.job_text)["measurement"] == json.loads(
        (tmp_path / "out" / "cases" / "c001" / "measurement.json").read_text()
    )
    drift = []  # um of arc per mm of carriage, from each case's own setting sheet
    for case in ("c000", "c001"):
        ix = setup_sheet(load_job(tmp_path / "out" / "cases" / case / "job.toml"), "mechanical").settings["ix"]
        drift.append(ix.effect["pitch_um_per_work_rev"] / job.process.axial_feed)
    assert abs(drift[0]) > 5.0 and abs(drift[1]) < 0.05 * abs(drift[0])  # the set with 17 makes ix (almost) exact

    doc = json.loads((tmp_path / "out" / "cases" / "c000" / "measurement.json").read_text())
    z0, z1 = doc["evaluation"]["helix_z_mm"]
    g = job.gear
    predicted = -(drift[0] - drift[1]) * (z1 - z0) * math.cos(math.atan(math.tan(g.alpha_n) / math.cos(g.beta)))
    change = {
        s: res["c000"]["measured"][f"f_Hbeta_mean_{s}"] - res["c001"]["measured"][f"f_Hbeta_mean_{s}"]
        for s in ("left", "right")
    }
    opposite = (change["left"] - change["right"]) / 2
    assert opposite == pytest.approx(predicted, rel=0.05), (change, predicted)


@pytest.mark.parametrize("name", sorted(p.name for p in (ROOT / "assets" / "studies").glob("*.toml")))
def test_the_shipped_study_files_load_and_design_their_cases(name) -> None:
    """Each study file the project ships is valid: its base job and every case's job parse (nothing runs)."""
    study = load_study(ROOT / "assets" / "studies" / name)
    made = cases(study)
    assert len(made) >= 2 and len({c.job_hash for c in made}) == len(made)  # distinct cases
    assert all(v.key for v in study.varies) and len(study.varies) >= 2


def test_a_studys_cases_give_the_class_distribution(tmp_path) -> None:
    """The budget counts each case's ISO 1328-1 class (its worst parameter's) and the share at or better than a
    class: with F_p the only parameter that varies, the class of each case is F_p's class, graded by the standard."""
    study = load_study(
        study_file(
            tmp_path,
            'method = "monte-carlo"\nsamples = 12\nseed = 1\n[[vary]]\nkey = "machine.model.lead_screw_pitch_error"\n'
            'distribution = "normal"\nmean = 0.0\nstd = 1e-3\n',
        )
    )
    rows = design(study)
    fp = np.linspace(2.0, 40.0, len(rows))  # um: from class 1 to beyond class 8 on the default gear
    records = {f"c{i:03d}": record(f"c{i:03d}", r, 0.5, float(fp[i])) for i, r in enumerate(rows)}
    budget = error_budget(study, records, GEAR, target=6)
    expected: dict[int, int] = {}
    for v in fp:
        grades = [iso.grade(x, n, *GEAR) for n, x in graded(record("c", {}, 0.5, float(v))["measured"]).items()]
        c = max(g if g is not None else 12 for g in grades)
        expected[c] = expected.get(c, 0) + 1
    assert budget.class_counts == dict(sorted(expected.items())) and sum(budget.class_counts.values()) == 12
    assert budget.p_at_most(6) == pytest.approx(sum(k for c, k in expected.items() if c <= 6) / 12)
    assert len(budget.class_counts) >= 3  # a spread, not one class
    from virtual_machine.studies.report import class_histogram_png

    assert class_histogram_png(budget)[:8] == b"\x89PNG\r\n\x1a\n"  # the report's histogram of the classes
