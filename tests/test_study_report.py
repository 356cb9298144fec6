"""report.html of a study, from hand-made studies, records and budgets (no case runs)."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest

from virtual_machine.studies.budget import Budget, ParameterBudget, PartEffect, TargetAnswer
from virtual_machine.studies.report import write_study_report
from virtual_machine.studies.spec import Study, Vary

BACKLASH = "machine.model.work_drive.backlash"
RUNOUT = "machine.model.spindle.runout"
ODD = "spindle <runout> & co"
ERROR = "LostSynchronismError: the work axis lost synchronism at t = 1.2 s"


def _study(method: str) -> Study:
    if method == "monte-carlo":
        varies = (
            Vary(BACKLASH, "work-drive backlash", 5e-4, distribution="normal", mean=5e-4, std=1e-4),
            Vary(RUNOUT, ODD, 0.0, distribution="uniform", lo=0.0, hi=2e-5),
        )
    else:
        varies = (
            Vary(BACKLASH, "work-drive backlash", 5e-4, values=(1e-4, 5e-4, 1e-3), tolerance=2e-4),
            Vary(RUNOUT, ODD, 0.0, values=(0.0, 1e-5), tolerance=None),
        )
    return Study(
        path=Path("x/s.toml"),
        base_path=Path("x/base.toml"),
        base_data={},
        method=method,
        varies=varies,
        samples=20 if method == "monte-carlo" else 0,
        seed=7 if method == "monte-carlo" else 0,
    )


def _record(cid: str, backlash: float, runout: float, failed: bool = False) -> dict[str, Any]:
    measured = {"class": None if failed else 6, "sync_rms_um": None if failed else 0.4321}
    return {
        "id": cid,
        "job_hash": "0" * 64,
        "values": {BACKLASH: backlash, RUNOUT: runout},
        "status": "failed" if failed else "ok",
        "error": ERROR + "\nTraceback (most recent call last): ..." if failed else "",
        "wall_s": 12.345,
        "measured": measured,
    }


def _records() -> dict[str, dict[str, Any]]:
    return {
        "c000": _record("c000", 5e-4, 0.0),
        "c001": _record("c001", 1e-4, 0.0),
        "c002": _record("c002", 1e-3, 0.0, failed=True),
        "c003": _record("c003", 5e-4, 1e-5),
    }


def _budget(method: str, target: int | None = 5) -> Budget:
    mc = method == "monte-carlo"
    parts = [
        PartEffect(BACKLASH, "work-drive backlash", 4000.0, (1e-4, 2.0), (1e-3, 6.0), 2e-4, 0.8, 0.8 if mc else 1.0),
        PartEffect(
            RUNOUT, ODD, 1.5e5, (0.0, 3.0), (1e-5, 4.5), 1e-5 if mc else None, 1.5 if mc else None, 0.1 if mc else None
        ),
    ]
    slope = [PartEffect(BACKLASH, "work-drive backlash", float("nan"), (1e-4, 1.0), (1e-3, 1.0), 2e-4, None)]
    f_alpha = ParameterBudget("F_alpha", 3.0, 3.8, 6, parts, 0.1 if mc else None)
    f_h = ParameterBudget("f_Halpha", 1.0, 1.0, 4, slope, 0.0 if mc else None)
    if target is not None:
        f_alpha.answer = TargetAnswer(
            target, 3.5, False, ODD if mc else "work-drive backlash", 1.23e-4, "tighten it & see"
        )
        f_h.answer = TargetAnswer(target, 2.0, True)
    return Budget(method, 3, 1, [f_alpha, f_h], target)


def _page(tmp_path: Path, method: str, budget: Budget, records: dict | None = None) -> str:
    path = tmp_path / "report.html"
    out = write_study_report(path, _study(method), _records() if records is None else records, budget, 5, 83.2, 4)
    assert out == path
    return path.read_text()


def _section(page: str, heading: str) -> str:
    start = page.index(f"<h2>{heading}")
    end = page.find("<h2>", start + 1)
    return page[start : end if end > 0 else len(page)]


@pytest.mark.parametrize("method", ["one-at-a-time", "grid", "monte-carlo"])
def test_page_for_every_method(tmp_path: Path, method: str) -> None:
    page = _page(tmp_path, method, _budget(method))
    assert "<title>skive study: s</title>" in page and "<h1>skive study: s</h1>" in page
    assert "3 ok, 1 failed, 5 in the design" in page and "x/base.toml" in page
    assert "<script" not in page and 'src="http' not in page and "<link" not in page
    # two parameters: one tornado figure, one embedded PNG
    assert len(re.findall(r'src="data:image/png;base64,[A-Za-z0-9+/=]+"', page)) == 1
    # the answer: the limiting parameter, its largest contributor, and the required tolerance
    limits = _section(page, "Which part limits the class")
    assert "F_alpha limits the class: 3.80 um" in limits and "class 6" in limits
    contributor = (html_escaped(ODD), "1.50") if method == "monte-carlo" else ("work-drive backlash", "0.80")
    assert f"Its largest contributor: <b>{contributor[0]}</b> ({contributor[1]} um)" in limits
    target = limits[limits.index("<table>") :]
    assert "0.000123" in target and "tighten it &amp; see" in target
    fail_rows = re.findall(r'<tr class="fail">(.*?)</tr>', target)
    assert len(fail_rows) == 1 and "<td>F_alpha</td>" in fail_rows[0] and "<td>no</td>" in fail_rows[0]
    # the label with < is escaped everywhere
    assert ODD not in page and html_escaped(ODD) in page
    # the failed case: its row, its first error line only
    cases = _section(page, "Cases")
    row = re.search(r'<tr class="fail"><td>c002</td>.*?</tr>', cases)
    assert row is not None and ERROR in row.group(0) and "Traceback" not in page
    assert "<td>0.43</td>" in cases and "<td>12.3</td>" in cases
    budget = _section(page, "Error budget")
    assert "<td>4000</td>" in budget and "<td>1.5e+05</td>" in budget  # 4 significant digits
    assert ("residual (nonlinear, interactions)" in budget) == (method == "monte-carlo")
    if method == "monte-carlo":
        assert "95th percentile of the cases" in limits and "<th>std</th>" in budget
        assert "20 samples, seed 7" in page
        assert re.search(r"residual \(nonlinear, interactions\)</td>.*<td>10\.0</td>", budget)
    else:
        assert "worst case at the stated tolerances" in limits and "not stated" in budget


def test_without_target(tmp_path: Path) -> None:
    page = _page(tmp_path, "one-at-a-time", _budget("one-at-a-time", target=None))
    limits = _section(page, "Which part limits the class")
    assert "F_alpha limits the class" in limits and "<table>" not in limits
    assert 'class="fail"' not in _section(page, "Error budget")


def test_outside_iso_range(tmp_path: Path) -> None:
    budget = _budget("grid", target=None)
    budget.iso_error = "module 0.1 mm < 0.5 mm"
    page = _page(tmp_path, "grid", budget)
    assert "outside ISO 1328-1" in page and "module 0.1 mm &lt; 0.5 mm" in page


def test_all_cases_failed(tmp_path: Path) -> None:
    records = {cid: _record(cid, 5e-4, 0.0, failed=True) for cid in ("c000", "c001")}
    budget = Budget("one-at-a-time", 0, 2, [], target=5)
    page = _page(tmp_path, "one-at-a-time", budget, records)
    assert "<h1>skive study: s</h1>" in page and "No parameter could be evaluated" in page
    assert "data:image/png" not in page
    assert page.count(ERROR) == 2 and "0 ok, 2 failed, 5 in the design (3 not finished)" in page


def html_escaped(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")


def test_one_png_per_ten_parameters(tmp_path: Path) -> None:
    budget = _budget("grid", target=None)
    budget.parameters = [
        ParameterBudget(f"P{i}", 1.0, 2.0, 5, list(budget.parameters[0].parts)) for i in range(12)
    ]  # two figures: 10 subplots and 2
    page = _page(tmp_path, "grid", budget)
    assert page.count("data:image/png;base64,") == 2
