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
#: the pulse: 50 N m for 1 ms at 1 s (the spindles at speed)
START, LENGTH, TORQUE = 1.0, 1e-3, 50.0


def _tap(name: str, axis: str):
    """The simulated and the linear responses [rad] of ``axis`` to the pulse, from 10 ms before it, and their
    times from the pulse [s]."""
    job = load_job(JOBS / f"{name}.toml")
    params = machine_params(job)
    # the work stage's 20 arcsec backlash is a nonlinearity the linearisation leaves out (under the cut's torque
    # the stage rides on one flank): the tap test takes it out
    params = dataclasses.replace(params, work_drive=dataclasses.replace(params.work_drive, backlash=0.0))
    pulse = lambda t: TORQUE if START <= t < START + LENGTH else 0.0  # noqa: E731
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
    force = np.fft.rfft(np.where((grid >= -dt / 2) & (grid < LENGTH - dt / 2), TORQUE, 0.0))
    linear = np.fft.irfft(drive.response(omega) * force, n)[: len(sim)]
    return t, sim, linear


@pytest.mark.parametrize("name", ["spur_external", "helical_internal"])
def test_a_tap_on_the_tool_spindle_answers_as_its_linearised_drive(name: str) -> None:
    """The tool spindle (belt stage 2e4 N m/rad on the servo motor M1): the pulse's peak turn within 12 % (measured
    spur_external 964 against 1007 urad, helical_internal 941 against 1007) and the rebound's time within 15 %
    (13.5 and 14.75 ms against 13.0 ms); the rebound is up to 16 % deeper in the simulation (-396 against -341 urad:
    the correction's pulse quantisation, one pulse being 628 urad, the linear model leaves out)."""
    t, sim, linear = _tap(name, "B1")
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
