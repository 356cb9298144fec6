"""The realised ratios of a structure's chains, from its setting sheet (machine_models.structure_drives).

Signs follow the ideal kinematics of cutting/skiving/kinematics.py: the tool turns positive, the work by the signed
speed ratio, B4 by the signed differential rotation per mm, the carriage in the feed direction."""

from __future__ import annotations

from machine_models.structure_drives import ChainRatios
from virtual_machine.job import Job, machine_constants
from virtual_machine.setting.sheet import setup_sheet


def _realised(sheet, name: str) -> float:
    s = sheet.settings[name]
    return float(s.realised if s.realised is not None else s.value)


def chain_ratios(job: Job) -> ChainRatios:
    structure = job.machine.structure
    sheet = setup_sheet(job, structure)
    m = machine_constants(job.machine, structure)
    st = job.skiving
    dir_work = 1.0 if st.speed_ratio > 0 else -1.0
    sign_h = 1.0 if st.differential_rotation_per_mm >= 0 else -1.0
    feed_dir = -1.0 if st.feed_direction == "down" else 1.0
    t = m.lead_screw_pitch
    speed = m.c3 * _realised(sheet, "iv")
    if structure == "mechanical":
        return ChainRatios(
            speed=speed,
            generating=dir_work * m.c1 * m.i_sigma,
            helix=sign_h * m.c2 * m.i_sigma,
            feed=feed_dir * dir_work * m.c4 * _realised(sheet, "is") / t,
            ix=_realised(sheet, "ix"),
            iy=abs(_realised(sheet, "iy")),
        )
    if structure == "hydraulic-differential":
        return ChainRatios(
            speed=speed,
            generating=dir_work * m.c1 * m.i_sigma,
            helix=sign_h * m.c2 * m.i_sigma,
            feed=feed_dir * dir_work * m.c4 / t,
        )
    if structure == "hydraulic-shaft":
        kx = _realised(sheet, "kx")
        return ChainRatios(
            speed=dir_work * speed / (m.c1 * abs(kx)),  # work per motor rad: the tool then turns at c3 iv n_M
            generating=dir_work * m.c1,
            feed=feed_dir * dir_work * m.c4 * _realised(sheet, "is") / t,
        )
    raise ValueError(f"structure {structure!r} has no chains (the mechatronic structure is all servo axes)")
