"""metrology.measure.measure_helix: the helix part of a measurement alone, the same figures as the whole one's."""

from __future__ import annotations

import numpy as np
from small_jobs import job_from_text, small_job

from cutting.skiving.edge import make_edge
from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.trajectory import ideal_passes
from metrology.measure import MeasureOptions, measure_gear, measure_helix


def test_the_helices_alone_are_the_whole_measurements_helices(tmp_path) -> None:
    """The small job's ideal cut with 10 um of lead crowning in the design (the modification path's trial cuts read
    the helices against it): measure_helix gives the whole measurement's helix block, range and traces, bit for
    bit."""
    crowned = small_job(face_width=4.0, sweep_error=0.02) + "[modification]\nlead_crowning = 0.01\n"
    job = job_from_text(tmp_path, crowned)
    st = job.skiving
    opt = MeasureOptions.from_job(job.measurement, job.modification)
    cut = SweptVolumes(st.gear, make_edge(st, "involute"), ideal_passes(st))
    whole, helices = measure_gear(cut, st.gear, opt), measure_helix(cut, st.gear, opt)
    assert helices["helix"] == whole["helix"]
    assert helices["evaluation"]["helix_z_mm"] == whole["evaluation"]["helix_z_mm"]
    assert np.array_equal(helices["_traces"]["z_mm"], whole["_traces"]["z_mm"])
    for side in ("left", "right"):
        assert np.array_equal(helices["_traces"]["helix"][side], whole["_traces"]["helix"][side], equal_nan=True)
    assert abs(whole["helix"]["left"]["C_beta_design"] - 10.0 * (3.6 / 4.0) ** 2) < 0.01  # the design is read
