"""Chatter shows on the gear: the marks a vibration leaves along the face (machine_effect.surface_wavelength), read
back from the measured helix traces (metrology/waviness.py) as a gear measuring machine's report shows them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from small_jobs import job_from_text, small_job

from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.sampled_motion import sampled_passes
from cutting.skiving.trajectory import ideal_passes
from metrology.measure import measure_gear
from metrology.waviness import helix_waviness
from virtual_machine.processes.skiving.cosim import cosimulate
from virtual_machine.processes.skiving.machine_effect import pass_deflection, surface_wavelength
from virtual_machine.processes.skiving.run import _flank_marks

#: the chatter test's tool mode along y (tests/test_chatter_in_the_run.py): at 42 N/um the pass's margin is 0.86
MODE = '\n[[machine.model.loop]]\nat = "tool"\ndirection = [0.0, 1.0, 0.0]\nfrequency = 200.0\ndamping = 0.03\n'


def test_the_waviness_of_known_traces() -> None:
    """20 teeth x 2 flanks of a 3.6 mm helix range (200 points), each a 3 um sine of 0.66 mm at its own phase on a
    slope and a 0.1 um noise: the wave within 2 % and its amplitude within 5 %; without the sine, no amplitude
    above the noise's; with the feed's cusps on top, the feed's wavelength unless the feed is given."""
    rng = np.random.default_rng(7)
    z = np.linspace(-1.8, 1.8, 200)
    wave = {
        side: np.array([3e-3 * np.sin(2 * np.pi * z / 0.66 + p) + 2e-3 * z + 1e-4 * rng.standard_normal(200)
                        for p in rng.uniform(0, 2 * np.pi, 20)])
        for side in ("left", "right")
    }  # fmt: skip
    found = helix_waviness(z, wave)
    assert found["wavelength_mm"] == pytest.approx(0.66, rel=0.02)
    assert found["amplitude_um"] == pytest.approx(3.0, rel=0.05)
    flat = {side: 2e-3 * z[None, :] + 1e-4 * rng.standard_normal((20, 200)) for side in ("left", "right")}
    assert helix_waviness(z, flat)["amplitude_um"] < 0.1
    # the feed's cusps (every 0.2 mm, 12 um deep: 4.9 um of fundamental) dominate; told the feed, the search looks past
    cusps = {side: w + 12e-3 * (((z / 0.2) % 1.0) - 0.5) ** 2 * 4 for side, w in wave.items()}
    assert helix_waviness(z, cusps)["wavelength_mm"] == pytest.approx(0.2, rel=0.02)
    assert helix_waviness(z, cusps, feed=0.2)["wavelength_mm"] == pytest.approx(0.66, rel=0.02)


def test_the_marks_wavelength_by_hand(tmp_path) -> None:
    """The tests' small job (z2 18, z0 17, 2000 rpm, s 0.2 mm): a space is passed every z2 cutter pitches, T = 18 /
    (17 x 2000 / 60) = 31.76 ms; a 210.9 Hz vibration makes 6.699 cycles per visit, so the flank's samples drift
    by -0.301 cycle per s: marks 0.2 / 0.301 = 0.664 mm long. A vibration at a multiple of 1 / T (here 5 / T) leaves
    none."""
    job = job_from_text(tmp_path, small_job(), "small.toml")
    visits = 18 / (17 * 2000 / 60)
    f = 210.9
    beat = f * visits - round(f * visits)
    assert surface_wavelength(f, job.skiving) == pytest.approx(0.2 / abs(beat), rel=1e-9)
    assert surface_wavelength(f, job.skiving) == pytest.approx(0.664, abs=0.001)
    assert surface_wavelength(5 / visits, job.skiving) is None


@pytest.mark.slow
def test_a_pass_that_chatters_leaves_its_marks_on_the_flanks(tmp_path) -> None:
    """The small job on a 4 mm face (one full-depth pass) with the 42 N/um tool mode: the lobes call it unstable
    (margin 0.86) and the run's vibration grows, here without tearing the short face: to 5.8 um at 211 Hz, a
    chatter warning. The measured gear shows it as a gear measuring machine's helix traces would: their dominant
    wave has the wavelength the vibration predicts (0.66 mm: measured within 10 %), and the helix form deviation
    f_fbeta is the vibration's peak-to-peak at the generating point (2 x 5.8 um; measured 11.2 / 11.9 um: within 25
    %), several times the ideal cut's (the feed marks alone). The run's report gives both (``flanks`` beside
    ``surface_wavelength_mm`` in the finishing pass's ``run.vibration``)."""
    job = job_from_text(tmp_path, small_job(sweep_error=0.02, face_width=4.0) + MODE + "stiffness = 4.2e7\n")
    sim = cosimulate(job, removal="none")  # the gear is the exact swept surfaces; no chip volume is read
    (row,) = pass_deflection(sim.record, job.skiving)
    vib = row["vibration"]
    assert "chatter" in row.get("warning", "") and vib["growth"] > 2.0
    assert vib["frequency_hz"] == pytest.approx(210.0, abs=5.0)
    doc = measure_gear(SweptVolumes(job.gear, sim.edge, sampled_passes(job.skiving, sim.record.passes)), job.gear)
    tr = doc["_traces"]
    marks = helix_waviness(tr["z_mm"], tr["helix"], job.skiving.axial_feed)  # the feed marks aside
    assert marks["wavelength_mm"] == pytest.approx(vib["surface_wavelength_mm"], rel=0.1), (marks, vib)
    for side in ("left", "right"):
        assert doc["helix"][side]["f_fbeta"] == pytest.approx(2 * vib["amplitude_um"], rel=0.25), side
    ideal = measure_gear(SweptVolumes(job.gear, sim.edge, ideal_passes(job.skiving)), job.gear)
    assert all(doc["helix"][s]["f_fbeta"] > 2 * ideal["helix"][s]["f_fbeta"] for s in ("left", "right"))
    vibration = [{"pass": 1, **vib}]
    _flank_marks(vibration, doc, len(job.skiving.passes), job.skiving.axial_feed)
    assert vibration[0]["flanks"] == marks
    assert math.isfinite(vibration[0]["surface_wavelength_mm"])
