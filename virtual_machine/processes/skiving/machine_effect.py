"""What the machine did to the cut, pass by pass: the three force components the chips put on it, the tool's
displacement relative to the workpiece at the generating point normal to the flanks, and its vibration
(measurement.json's ``run.forces.passes`` and ``run.vibration``).

The displacement at the generating point: the material point of the tool that the ideal kinematics put at the pitch
point on the mesh line ((r2, 0, P3) in the machine frame, +x the common perpendicular), moved by the motion the machine
really made (its axes, their servo errors, the synchronisation error and the loop's deflection:
:func:`virtual_machine.runtime.machine_run.relative_pose`) against the ideal motion (the work at the angle the cutter
and the carriage imply, the radial slide at the pass's centre distance), in the machine frame. Normal to the flanks
at the pitch point: the transverse normals of the space's two flanks, (s sin alpha_t, -+cos alpha_t, 0) cos beta_b
(s = +1 external, -1 a ring gear: positive when the tool stays off the flank and leaves material on it; the axial part
sin beta_b of a helical flank's normal is left out).
"""

from __future__ import annotations

import math

import numpy as np

from virtual_machine.runtime.machine_run import SEGMENTS, MotionRecord, relative_pose

FEED = SEGMENTS.index("feed")
#: a pass whose vibration grows by this over its cut (last quarter against the first) and reaches CHATTER_UM warns
#: (a choice, not a published criterion: growth marks regeneration, 1 um is a tenth of a class-6 gear's f_falpha)
CHATTER_GROWTH = 2.0
CHATTER_UM = 1.0
#: the moving average whose residue is the vibration [s]
TREND_S = 0.025


def pass_forces(loads, rows: np.ndarray, passes: int, rec: MotionRecord | None = None, setup=None) -> list[dict]:
    """Per pass the time means of the cutting, thrust and passive components [N] acting on the machine (the sum over
    the teeth in the cut: each engagement's components integrated over its time, over the pass's cutting time), the
    peak resultant [N] (the servo ticks' ``rows``: t, force on the workpiece in the blank frame (3), torque) and, with
    the motion record ``rec`` and the ``setup``, the mean force on the tool along the machine's axes [N] (x the
    centre distance, y, z the work axis) over the same time."""
    out = []
    on_tool = None
    if rec is not None and len(rows):
        turn = np.interp(rows[:, 0], rec.t, rec.q[:, 1]) + setup.work_phase  # the blank frame's turn
        c, s = np.cos(turn), np.sin(turn)
        f = rows[:, 1:4]
        on_tool = -np.stack([c * f[:, 0] - s * f[:, 1], s * f[:, 0] + c * f[:, 1], f[:, 2]], -1)
    for k in range(passes):
        mine = [a.load for a in loads if a.pass_index == k and a.load.components is not None and len(a.load.t) > 1]
        if not mine:
            out.append({"pass": k + 1, "cutting_mean_N": 0.0, "thrust_mean_N": 0.0, "passive_mean_N": 0.0,
                        "peak_N": 0.0})  # fmt: skip
            continue
        t0, t1 = min(ld.t[0] for ld in mine), max(ld.t[-1] for ld in mine)
        total = sum(np.trapezoid(np.abs(ld.components), ld.t, axis=0) for ld in mine)
        sel = (rows[:, 0] >= t0) & (rows[:, 0] <= t1) if len(rows) else np.zeros(0, bool)
        peak = float(np.linalg.norm(rows[sel, 1:4], axis=1).max()) if sel.any() else 0.0
        mean = total / max(t1 - t0, 1e-12)
        row = {
            "pass": k + 1,
            "cutting_mean_N": float(mean[0]),
            "thrust_mean_N": float(mean[1]),
            "passive_mean_N": float(mean[2]),
            "peak_N": peak,
        }
        if on_tool is not None and sel.any():
            row["tool_force_machine_mean_N"] = on_tool[sel].mean(axis=0).tolist()
        out.append(row)
    return out


def generating_point_displacement(rec: MotionRecord, setup) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per feed tick: the time [s], the pass index and the tool's displacement relative to the workpiece at the
    generating point in the machine frame [um] (n, 3) (see the module docstring)."""
    feed = rec.segment == FEED
    q = rec.q[feed]
    index = rec.pass_index[feed]
    defl = rec.deflection[feed] if rec.deflection is not None else None
    r2 = setup.gear.reference_radius
    ideal = q.copy()
    ideal[:, 1] -= rec.sync_um[feed] / (r2 * 1e3)  # the work where the cutter and the carriage imply it
    centre = np.array(setup.pass_centre_distances)
    ideal[:, 3] = centre[np.clip(index, 0, len(centre) - 1)]
    rot_a, t_a = relative_pose(setup, q, defl, rec.t[feed])
    rot_i, t_i = relative_pose(setup, ideal, None, rec.t[feed])
    turn = ideal[:, 1] + setup.work_phase
    c, s = np.cos(turn), np.sin(turn)
    pitch = np.stack([np.full(len(q), r2), np.zeros(len(q)), q[:, 2]], -1)  # machine frame [mm]
    p_blank = np.stack([c * pitch[:, 0] + s * pitch[:, 1], -s * pitch[:, 0] + c * pitch[:, 1], pitch[:, 2]], -1)
    tool_point = np.einsum("nji,nj->ni", rot_i, p_blank - t_i)  # in the cutter frame, where the ideal puts it
    moved = np.einsum("nij,nj->ni", rot_a, tool_point) + t_a - p_blank
    machine = np.stack([c * moved[:, 0] - s * moved[:, 1], s * moved[:, 0] + c * moved[:, 1], moved[:, 2]], -1)
    return rec.t[feed], index, machine * 1e3


def flank_normals(setup) -> np.ndarray:
    """(2, 3): the two flanks' normals at the pitch point of the space on the mesh line (module docstring)."""
    g = setup.gear
    alpha_t = math.atan(math.tan(g.alpha_n) / math.cos(g.beta))
    beta_b = math.atan(math.tan(g.beta) * math.cos(alpha_t))
    side = -1.0 if g.internal else 1.0
    sa, ca = math.sin(alpha_t), math.cos(alpha_t)
    return math.cos(beta_b) * np.array([[side * sa, -ca, 0.0], [side * sa, ca, 0.0]])


def surface_wavelength(frequency: float, setup) -> float | None:
    """The wavelength along the face [mm] of the marks a vibration of ``frequency`` [Hz] leaves on the flanks, or
    None when it is synchronous with the visits (a constant or a pitch pattern, no wave). A space's flank at height
    z is finished when a cutter tooth passes it; the same space is passed again z2 cutter pitches later (its
    interval T = z2 pitches of the cutter's turn; a helical gear's differential included: chip_load's revolution)
    while the carriage moves the axial feed s, so the flank samples the vibration once per T: the samples' phase
    advances by 2 pi (f T - round(f T)) per s of face, a wavelength s / |f T - round(f T)| (metrology/waviness.py
    reads it back from the measured helix traces)."""
    pitch = 2 * math.pi / setup.cutter.teeth
    visits = round(2 * math.pi / abs(setup.speed_ratio) / pitch) * pitch / (setup.tool_speed * 2 * math.pi / 60)
    beat = frequency * visits - round(frequency * visits)
    return setup.axial_feed / abs(beat) if abs(beat) > 1e-3 else None


def pass_deflection(rec: MotionRecord, setup) -> list[dict]:
    """Per pass: the displacement normal to the flanks at the generating point while the cutter is in the blank
    [um] (mean of the two flanks' and their peak; each flank's mean) and the vibration: the half range of the
    flank-normal displacement about its 25 ms moving average on the flank where it is larger, its dominant frequency
    [Hz], its growth (the largest later quarter of the cut against the first) and the wavelength of the marks it
    leaves along the face (:func:`surface_wavelength`), with a warning when it grows like chatter."""
    t, index, disp = generating_point_displacement(rec, setup)
    in_cut = rec.cutting[rec.segment == FEED]
    normal = disp @ flank_normals(setup).T  # (n, 2)
    out = []
    for k in range(len(setup.passes)):
        sel = (index == k) & in_cut
        if sel.sum() < 16:
            continue
        d = normal[sel]
        both = d.mean(axis=1)
        tt = t[sel]
        dt = float(np.median(np.diff(tt)))
        # the vibration: what a 25 ms moving average leaves (the structure's modes, 50 Hz and up; the slow course of
        # the deflection over the pass, the entry and exit at the faces, are the static part), on each flank (a
        # tangential vibration moves the two flanks' normals oppositely: their mean would hide it); the larger one
        w = max(3, round(TREND_S / dt) | 1)
        waves = [
            d[:, f] - np.convolve(np.pad(d[:, f], w // 2, mode="edge"), np.ones(w) / w, mode="valid") for f in (0, 1)
        ]
        wave = max(waves, key=np.ptp)
        n = len(wave)
        spec = np.abs(np.fft.rfft(wave * np.hanning(n)))
        freq = np.fft.rfftfreq(n, dt)
        quarter = max(n // 4, 1)
        first = np.ptp(wave[:quarter]) / 2
        # the largest quarter after the first (a chatter that has grown may fade as the cutter leaves the face)
        step = max(quarter // 4, 1)
        last = max(np.ptp(wave[i : i + quarter]) / 2 for i in range(quarter, max(n - quarter, quarter) + 1, step))
        growth = float(last / first) if first > 0 else math.inf
        frequency = float(freq[1:][np.argmax(spec[1:])]) if n > 2 else 0.0
        row = {
            "pass": k + 1,
            "flank_normal_deflection_um": {
                "mean": float(both.mean()),
                "peak": float(np.abs(d).max()),
                "flanks_mean": [float(d[:, 0].mean()), float(d[:, 1].mean())],
            },
            "vibration": {
                "amplitude_um": float(np.ptp(wave) / 2),
                "frequency_hz": frequency,
                "growth": growth,
                # the marks it leaves along the face (if this pass finishes the flank): surface_wavelength
                "surface_wavelength_mm": surface_wavelength(frequency, setup) if frequency > 0 else None,
            },
        }
        if growth > CHATTER_GROWTH and last > CHATTER_UM:
            row["warning"] = (
                f"chatter: the vibration at the generating point grows {growth:.1f}x over pass {k + 1} to "
                f"{last:.1f} um at {row['vibration']['frequency_hz']:.0f} Hz (skive stability JOB draws the lobes)"
            )
        out.append(row)
    return out
