"""The passes' balance (cutting/skiving/pass_balance.py, `skive setup --balance-passes`): increments that give every
pass the same largest uncut chip, for the job's number of passes and depth."""

from __future__ import annotations

import numpy as np
import pytest
from checks import JOBS

from cutting.skiving.pass_balance import PassBalance, _common_chip, balance_passes


def test_the_common_chip_spreads_the_depth_as_the_power_laws_say():
    """Known answer: with h_i = c_i d_i^p_i, the chip H whose increments (H / c_i)^(1 / p_i) sum to the depth."""
    c, p, depth = np.array([0.7, 0.9, 1.3]), np.array([0.75, 0.5, 1.0]), 2.25
    h = _common_chip(c, p, depth)
    d = (h / c) ** (1 / p)
    assert d.sum() == pytest.approx(depth, abs=1e-12)
    assert c * d**p == pytest.approx(np.full(3, h), rel=1e-12)
    # equal laws split the depth evenly
    assert _common_chip(np.full(2, 0.8), np.full(2, 0.75), 2.0) == pytest.approx(0.8, rel=1e-12)


def test_the_default_jobs_passes_come_closer_to_the_same_largest_chip():
    """The default job's roughing pass (1.75 mm) takes about 2.4 times its finishing pass's (0.5 mm) largest chip;
    one step of the balance moves depth from the first to the second pass and brings them within 1.4 of each other;
    the depth and the number of passes stay the job's."""
    from cutting.skiving.edge import make_edge
    from virtual_machine import load_job

    job = load_job(JOBS / "default.toml")
    st = job.skiving
    seen = []
    b = balance_passes(st, make_edge(st, job.cutter_options.edge), steps=1, progress=lambda *a: seen.append(a))
    assert [s[0] for s in seen] == [0, 1]
    assert b.before_passes == st.passes
    job_spread = max(b.before_chips) / min(b.before_chips)
    assert 2.0 < job_spread < 3.0
    assert sum(b.passes) == pytest.approx(sum(st.passes), abs=1e-12) and len(b.passes) == 2
    assert b.passes[0] < st.passes[0] and b.spread < 1.4 < job_spread


def test_setup_prints_the_proposal(monkeypatch):
    """`skive setup --balance-passes` prints the job's and the proposed increments with each pass's largest chip
    (the balance itself is the test above's; here its wiring into the sheet, the JSON and the command line)."""
    import json

    from click.testing import CliRunner

    from cutting.skiving import pass_balance
    from virtual_machine.cli import main

    def fake(setup, edge, tolerance=0.05, steps=6, progress=None):
        return PassBalance((1.0, 1.25), (0.8, 0.81), setup.passes, (1.2, 0.5), 3)

    monkeypatch.setattr(pass_balance, "balance_passes", fake)
    out = CliRunner().invoke(main, ["setup", str(JOBS / "default.toml"), "--balance-passes"])
    assert out.exit_code == 0, out.output
    assert "proposed   process.passes = [1.000, 1.250]: 800 / 810 um (largest / smallest 1.01" in out.output
    assert "the job's  process.passes = [1.75, 0.5]: 1200 / 500 um (largest / smallest 2.40)" in out.output
    as_json = CliRunner().invoke(main, ["setup", str(JOBS / "default.toml"), "--balance-passes", "--json"])
    doc = json.loads(as_json.stdout)
    assert doc["pass_balance"]["passes_mm"] == [1.0, 1.25]
    plain = CliRunner().invoke(main, ["setup", str(JOBS / "default.toml")]).output
    assert "proposed" not in plain and "pass balance" not in plain
