"""The spindles' torsion through their drives (virtual_machine/processes/skiving/spindle_torsion.py), the compliance
`skive stability` adds at the cutting point, against a tap test of the simulated machine: a torque pulse on the
running spindle (MuJoCo, the S4 controls with their correction), the response less the same run's without it."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from virtual_machine.job import load_job
from virtual_machine.processes.skiving.spindle_torsion import spindle_drives
from virtual_machine.runtime.machine_run import simulate
from virtual_machine.setting.machine_layout import machine_params

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"
#: the pulse: 1 ms at 1 s (the spindles at speed), 50 N m unless a test says
START, LENGTH, TORQUE = 1.0, 1e-3, 50.0


def _tap(name: str, axis: str, torque: float = TORQUE):
    """The simulated and the linear responses [rad] of ``axis`` to the pulse of ``torque`` [N m], from 10 ms before
    it, and their times from the pulse [s]."""
    job = load_job(JOBS / f"{name}.toml")
    params = machine_params(job)
    # the work stage's 20 arcsec backlash is a nonlinearity the linearisation leaves out (under the cut's torque
    # the stage rides on one flank): the tap test takes it out
    params = dataclasses.replace(params, work_drive=dataclasses.replace(params.work_drive, backlash=0.0))
    pulse = lambda t: torque if START <= t < START + LENGTH else 0.0  # noqa: E731
    base = simulate(job, params, duration=START + 0.06)
    tap = simulate(job, params, duration=START + 0.06, disturbance=pulse, disturbance_axis=axis)
    i = ("B1", "B2").index(axis)
    keep = tap.t >= START - 0.01
    sim, t = (tap.q[:, i] - base.q[:, i])[keep], tap.t[keep] - START
    dt = t[1] - t[0]
    drive = spindle_drives(params, job.skiving)["tool" if axis == "B1" else "work"]
    n = 1 << 14
    omega = 2 * np.pi * np.fft.rfftfreq(n, dt)
    omega[0] = 1e-6
    grid = np.arange(n) * dt - 0.01
    force = np.fft.rfft(np.where((grid >= -dt / 2) & (grid < LENGTH - dt / 2), torque, 0.0))
    linear = np.fft.irfft(drive.response(omega) * force, n)[: len(sim)]
    return t, sim, linear


@pytest.mark.parametrize(("name", "torque"), [("spur_external", 50.0), ("helical_internal", 300.0)])
def test_a_tap_on_the_tool_spindle_answers_as_its_linearised_drive(name: str, torque: float) -> None:
    """The tool spindle (a belt stage on the servo motor M1; spur_external on the medium machine, helical_internal on
    the large one, where a pulse six times larger turns it as far): the pulse's peak turn within 12 % (measured 964
    against 1007 urad, 880 against 929) and the rebound's time within 15 % (13.5 against 13.0 ms, 12.75 against
    12.5), its depth within 30 % (-319 against -341 urad, -480 against -469). Below about a pulse of the correction
    (628 urad at 10000 pulses a turn) the linearisation fails: the quantised loop then rests anywhere in its dead
    band (a 50 N m tap on the large machine turns the spindle 160 urad and leaves it 150 urad off)."""
    t, sim, linear = _tap(name, "B1", torque)
    assert np.abs(sim).max() == pytest.approx(np.abs(linear).max(), rel=0.12)
    assert t[np.argmin(sim)] == pytest.approx(t[np.argmin(linear)], rel=0.15)
    assert sim.min() == pytest.approx(linear.min(), rel=0.30)


def test_a_tap_on_the_work_spindle_answers_as_its_linearised_drive() -> None:
    """The work spindle of spur_external (a 1:2 stage, 1e6 N m/rad, on the servo motor M2): the peak turn within
    10 % (measured 99.4 against 101.5 urad), the rebound within 30 % (-28.3 against -36.0 urad at 13.3 against
    14.5 ms)."""
    t, sim, linear = _tap("spur_external", "B2")
    assert np.abs(sim).max() == pytest.approx(np.abs(linear).max(), rel=0.10)
    assert sim.min() == pytest.approx(linear.min(), rel=0.30)
    assert t[np.argmin(sim)] == pytest.approx(t[np.argmin(linear)], rel=0.15)
