"""A co-simulation without a workpiece (``removal="none"``) makes the dexel run's motion and loads: the force is the
chip of the moment, which reads the exact surfaces the passes before left, never the dexels."""

from __future__ import annotations

import numpy as np
import pytest
from small_jobs import job_from_text, small_job

from virtual_machine.processes.skiving.cosim import cosimulate


def test_a_run_without_a_workpiece_moves_and_loads_the_machine_as_the_dexel_run(tmp_path) -> None:
    """The small job (a 2 mm face at 0.4 mm feed: the claim does not depend on the size) run with the dexel workpiece
    and with none: the same motion record and the same loads, tick by tick (bit for bit: nothing the machine reads
    comes from the removal); the run without has no chips' volumes and no solid, and refuses snapshots."""
    job = job_from_text(tmp_path, small_job(sweep_error=0.02, axial_feed=0.4), "small.toml")
    dexel, none = cosimulate(job), cosimulate(job, removal="none")
    assert np.array_equal(dexel.record.q, none.record.q) and np.array_equal(dexel.record.t, none.record.t)
    assert np.array_equal(dexel.load_rows, none.load_rows)
    assert [a.load.model_volume for a in dexel.loads] == [a.load.model_volume for a in none.loads]
    assert sum(a.load.volume for a in dexel.loads) > 0 and all(a.load.volume == 0 for a in none.loads)
    assert none.cut.gear is None and none.cut.chips == [] and none.dexel is None
    with pytest.raises(ValueError, match="snapshots of the stock need a workpiece"):
        cosimulate(job, removal="none", snapshots_per_pass=2)
    with pytest.raises(ValueError, match="'dexel', 'manifold' or 'none'"):
        cosimulate(job, removal="voxels")
