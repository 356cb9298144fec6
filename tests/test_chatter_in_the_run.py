"""Chatter grows in a skiving run where `skive stability` says it does, and not where it says the cut is stable: the
chip of the moment (cutting.skiving.chip_of_the_moment) regenerates through the loop's own mode."""

from __future__ import annotations

import pytest
from small_jobs import job_from_text, small_job

from cutting.errors import ChatterError
from virtual_machine.processes.skiving.cosim import cosimulate
from virtual_machine.processes.skiving.machine_effect import pass_deflection
from virtual_machine.processes.skiving.stability import pass_stability
from virtual_machine.setting.machine_layout import machine_params

#: one tool mode along y (the mesh's tangential direction at the pitch point, where this cut's oriented coefficient
#: is largest: -3.4 N/um); its stiffness sets the pass's stability margin
MODE = """
[[machine.model.loop]]
at = "tool"
direction = [0.0, 1.0, 0.0]
frequency = 200.0
damping = 0.03
stiffness = {k}
"""


def job_with(tmp_path, k: float):
    return job_from_text(tmp_path, small_job(sweep_error=0.02, face_width=10.0) + MODE.format(k=k), f"k{k:.0f}.toml")


@pytest.mark.slow
def test_a_pass_the_lobes_call_unstable_chatters_and_a_stable_one_does_not(tmp_path) -> None:
    """The wide small job (one full-depth pass at 2000 rpm) with the mode at 42 N/um: `skive stability` gives the
    pass a margin of 0.86 (chatter at 209.6 Hz; the spindles' torsion through their drives included); the run's
    vibration grows at 210 Hz (the record's spectrum, 0.5 Hz apart from the lobes' frequency) until the cut tears the
    gear, which the run refuses with a ChatterError naming the pass. At 55 N/um the margin is 1.11 and the run's
    vibration does not grow (measured 1.03x: the teeth's forced vibration at 568 Hz). The time domain and the lobes
    agree on the stability limit within 15 % of the stiffness."""
    unstable, stable = job_with(tmp_path, 4.2e7), job_with(tmp_path, 5.5e7)
    (lobe,) = pass_stability(unstable.skiving, machine_params(unstable), "16MnCr5", 0.010)
    assert lobe.margin == pytest.approx(0.86, abs=0.03)
    with pytest.raises(ChatterError, match="pass 1") as err:
        cosimulate(unstable)
    frequency = float(str(err.value).split(" Hz")[0].rsplit(" ", 1)[1])
    assert frequency == pytest.approx(lobe.chatter_frequency, rel=0.02)
    (calm,) = pass_stability(stable.skiving, machine_params(stable), "16MnCr5", 0.010)
    assert calm.margin == pytest.approx(1.11, abs=0.03)
    (row,) = pass_deflection(cosimulate(stable, removal="none").record, stable.skiving)  # the motion is the dexel run's
    assert row["vibration"]["growth"] < 1.2 and "warning" not in row


@pytest.mark.slow
@pytest.mark.parametrize(("rpm", "chatters"), [(2570.0, False), (2738.0, True)])
def test_the_lobes_and_the_run_agree_at_other_speeds(tmp_path, rpm: float, chatters: bool) -> None:
    """The same job at 42 N/um at two more tool speeds (with 2000 rpm above, three): the lobes of the work period
    60 / (n0 z0 / z2) put 2570 rpm in a pocket (margin 1.72) and 2738 rpm on a lobe (0.75, chatter at 205.1 Hz); the
    runs agree: at 2570 rpm no chatter (the largest vibration is the teeth's forced one at 730 Hz, 1.1 um), at 2738
    rpm the vibration grows at 206 Hz until the cut tears the gear (ChatterError)."""
    text = small_job(sweep_error=0.02, face_width=10.0).replace("tool_speed = 2000.0", f"tool_speed = {rpm}")
    job = job_from_text(tmp_path, text + MODE.format(k=4.2e7), f"n{rpm:.0f}.toml")
    (lobe,) = pass_stability(job.skiving, machine_params(job), "16MnCr5", 0.010)
    assert (lobe.margin < 1.0) == chatters, lobe.margin
    if chatters:
        with pytest.raises(ChatterError, match="pass 1") as err:
            cosimulate(job)
        frequency = float(str(err.value).split(" Hz")[0].rsplit(" ", 1)[1])
        assert frequency == pytest.approx(lobe.chatter_frequency, rel=0.02)
        return
    (row,) = pass_deflection(cosimulate(job, removal="none").record, job.skiving)  # the motion is the dexel run's
    assert "warning" not in row
    # no vibration near the mode grows: what rings is the teeth's forced vibration, far above it
    assert row["vibration"]["frequency_hz"] > 2 * lobe.chatter_frequency or row["vibration"]["growth"] < 1.2
