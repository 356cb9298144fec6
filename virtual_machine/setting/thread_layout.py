"""The thread lathe's layout for a job: its form (seed 001 figs. 1-3) and the ratios its setting sheet realises.

It reads the job and the setting sheet, so it lives here rather than in ``machine_models`` (which never imports
``virtual_machine``); ``machine_models.thread_lathe.build_thread_lathe_spec`` builds the MJCF model from it.
"""

from __future__ import annotations

import math

from cutting.errors import InputError, Problem
from machine_models.parts import MM
from machine_models.thread_lathe import ThreadLatheParams, ThreadLayout
from virtual_machine.setting.sheet import thread_sheet


def thread_form(job) -> str:
    """``mechanical``, ``master-slave`` or ``equal-coordinates`` from the job's [machine] structure/synchronization."""
    m = job.machine
    if m.structure == "mechanical":
        return "mechanical"
    if m.structure == "mechatronic":
        return m.synchronization
    raise InputError(
        Problem(
            "machine.structure",
            m.structure,
            "the thread group of seed 001 exists as 'mechanical' or 'mechatronic'",
            "use one of those (with machine.synchronization 'master-slave' or 'equal-coordinates')",
        ),
        job.source,
    )


def thread_layout(job, params: ThreadLatheParams, sheet=None) -> ThreadLayout:
    """The layout of ``job`` (a thread job) from its setting sheet (computed if not given)."""
    if job.kind not in ("thread", "turning"):
        raise ValueError(f"{job.source} is a gear job; the thread lathe needs a [thread] job")
    form = thread_form(job)
    sheet = sheet or thread_sheet(job, "mechanical" if form == "mechanical" else "mechatronic")
    t, m = job.thread, job.machine
    st = sheet.settings
    hand = -1 if t["hand"] == "right" else 1
    n_sp = sheet.geometry["spindle_speed_rpm"] * 2 * math.pi / 60
    chain = feed = None
    if form == "mechanical":
        spindle_ratio = m.c3 * st["iv"].realised
        chain = hand * st["ix"].realised * m.i01
        motor = m.motor_speed * 2 * math.pi / 60
        speed = motor * spindle_ratio
    else:
        spindle_ratio = params.spindle_drive.ratio
        feed = m.i0 if form == "master-slave" else m.i01
        if form == "master-slave":
            speed = n_sp  # the master is a speed drive: no setting rounds its speed
        else:
            speed = 2 * math.pi * m.reference_frequency / (st["kv"].realisation["integer"] * m.command_pulses_per_rev)
        motor = speed / spindle_ratio
    length = t["length"] * MM
    lead = t["lead"] * MM
    approach = lead * speed / (2 * math.pi) * params.runup_time / 2 + params.clearance
    start = length + 2 * approach if hand < 0 else 0.0
    return ThreadLayout(
        form,
        hand,
        lead,
        m.lead_screw_pitch * MM / (2 * math.pi),
        spindle_ratio,
        chain,
        feed,
        speed,
        motor,
        length,
        approach,
        start,
        t["diameter"] * MM,
    )
