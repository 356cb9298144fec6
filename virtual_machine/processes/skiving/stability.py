"""`skive stability JOB`: each pass's stability lobe diagram, the critical radial infeed against the tool speed, from
the loop's frequency response at the cutting point and the oriented cutting coefficients of the pass's engaged edge
(cutting/regeneration.py: the average-force approach of Altintas and Budak).

Regeneration in skiving: each tooth space is passed once per work revolution, so the surface a passage meets was
left by the passage through the same space one work revolution earlier (offset by the feed): the delay is the work's
period T = 60 / n2 = 60 / (n0 |z0 / z2|) s, so the tool speed n0 = 60 / (T |z0 / z2|) rpm.

The loop at the cutting point (the generating point at the pitch circle on the mesh line, +x of the machine frame):
the machine's `[machine.model.loop]` modes at the tool and at the workpiece (their shapes there: machine_models/loop.py)
plus the axes' own compliance as modes: the radial slide's position servo along x (radial_stiffness, radial_mass and
what rides on it, radial_damping) and the nut along z (nut_stiffness, the carriage with everything on it); plus the
spindles' torsion through their drives (spindle_torsion.py: stage, motor, speed regulator and correction), along
each spindle's turn at the point.

The oriented coefficients D of a pass (3 x 3, N/m): its engaged edge (the involute edge inside the blank's envelope,
as the co-simulation's force model spreads the chip) over one engagement at the pass's centre distance by the ideal
kinematics, each element's oblique components linearised in the chip (dF/dh per unit width: the model's
tau_s(h) f (1 - mc (h - h_min) / h), h the pass's mean chip), summed and averaged over a cutter pitch (the teeth in the
cut together). The critical infeed at a speed: the infeed whose D (the edge engaged at that depth, its chip from the
pass's removed cross-section) reaches the lobes' limit there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from cutting.materials import material
from cutting.oblique import ObliqueForces, load_cutting_model
from cutting.regeneration import lobes
from cutting.skiving.ideal_moment import IdealMoment
from cutting.skiving.kinematics import SkivingSetup, rot_x, rot_z
from machine_models.loop import LoopMode, frequency_response
from machine_models.parameters import SkivingMachineParams
from virtual_machine.processes.skiving.spindle_torsion import spindle_drives, torsion_response
from virtual_machine.reach.skiving_load import engagement_half_angle_at


@dataclass(frozen=True)
class PassStability:
    """One pass: its infeed [mm] and the job's tool speed [rpm]; the critical infeed at that speed [mm] and the
    chatter frequency there [Hz]; the lobe diagrams over the tool speeds [rpm]: the critical infeed [mm] and the
    stability margin of the pass as it is (the factor on its dynamic cutting stiffness D at which it would chatter:
    > 1 stable).

    In skiving the chip's width is the engaged profile (both flanks and the bottom of the space, the layer every
    passage takes), which the infeed hardly changes once the edge is in the full depth: a finishing pass's stability
    then hardly depends on its infeed (the linear theory's width is fixed), and its margin says more than a critical
    infeed; a roughing pass into the blank engages more edge the deeper it goes."""

    index: int
    infeed: float
    tool_speed: float
    critical_infeed: float
    chatter_frequency: float
    speeds: np.ndarray
    critical: np.ndarray
    margins: np.ndarray

    @property
    def margin(self) -> float:
        """The stability margin at the job's speed: > 1 stable."""
        return float(np.interp(self.tool_speed, self.speeds, self.margins))

    def summary(self) -> dict:
        return {
            "pass": self.index + 1,
            "infeed_mm": self.infeed,
            "tool_speed_rpm": self.tool_speed,
            "critical_infeed_mm": _finite(self.critical_infeed),
            "margin": _finite(self.margin),
            "stable": bool(self.margin > 1.0),
            "chatter_frequency_hz": _finite(self.chatter_frequency),
            "lobes": {
                "tool_speed_rpm": self.speeds.tolist(),
                "critical_infeed_mm": [_finite(v) for v in self.critical.tolist()],
                "margin": [_finite(v) for v in self.margins.tolist()],
            },
        }


def _finite(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


def axis_modes(params: SkivingMachineParams) -> tuple[LoopMode, ...]:
    """The axes' own compliance as modes at the tool: the radial slide's servo along x and the nut along z (an axis
    above 5 kHz, the loop modes' range, counts as rigid: it cannot ring with the cut's tooth frequencies)."""
    out = []
    riding = params.radial_mass + sum(m.mass for m in params.loop if m.at == "tool" and m.kind == "translation")
    for direction, k, mass, c in (
        ((1.0, 0.0, 0.0), params.radial_stiffness, params.radial_mass, params.radial_damping),
        ((0.0, 0.0, 1.0), params.nut_stiffness, params.carriage_mass + riding, params.nut_damping),
    ):
        if k is None or k <= 0:
            continue
        omega = math.sqrt(k / mass)
        if omega > 2 * math.pi * 5000.0:
            continue
        out.append(LoopMode("tool", direction, omega / (2 * math.pi), max(c / (2 * math.sqrt(k * mass)), 1e-4), k))
    return tuple(out)


def loop_response(
    setup: SkivingSetup, params: SkivingMachineParams, structure: str = "mechatronic", adaptive: bool = True
):
    """G(omega) (n, 3, 3) [m/N]: the tool's displacement relative to the workpiece per force on the tool at the
    cutting point (tool side plus work side: the workpiece takes the opposite force): the loop's modes, the axes'
    and the spindles' torsion through their drives (spindle_torsion: the job's ``structure``, ``adaptive``
    correction)."""
    tool_axis = rot_x(setup.tilt) @ np.array([0.0, 0.0, 1.0])  # the head's z turned by the tilt about x
    point = np.array([setup.gear.reference_radius, 0.0, 0.0])  # the pitch point on the mesh line
    a = setup.pass_centre_distances[-1]
    modes = params.loop + axis_modes(params)
    drives = spindle_drives(params, setup, structure, adaptive)

    def g(omega: np.ndarray) -> np.ndarray:
        tool = frequency_response(modes, "tool", omega, tool_axis, point - np.array([a, 0.0, 0.0]))
        work = frequency_response(modes, "work", omega, np.array([0.0, 0.0, 1.0]), point)
        return tool + work + torsion_response(drives, setup, omega)

    return g


def oriented_coefficients(
    setup: SkivingSetup, model: ObliqueForces, centre_distance: float, previous: float | None, samples: int = 121
) -> tuple[np.ndarray, float]:
    """D (3, 3) [N/m] of one engagement at ``centre_distance`` [mm] after a pass at ``previous`` [mm] (None: into the
    blank), averaged over a cutter pitch, and the engagement's mean chip [mm] (the chips' area over the width).

    The chips are the co-simulation's (cutting.skiving.chip_of_the_moment) on the ideal machine at mid face: each
    element's chip between it and the surface the previous revolution left (the regenerative bound), the previous
    pass's or the blank's. An element whose chip the previous revolution bounds changes it by -n . (delta(t) -
    delta(t - T)); its force changes by dF/dh = tau_s(h) (1 - mc (h - h_min) / h) b (f_c e_c - f_t n + f_p p), so it
    adds dF/dh n^T. The elements bounded by the previous pass or the blank have no delayed term (no regeneration:
    they stiffen the process and are left out)."""
    moment = IdealMoment(setup, centre_distance, previous)
    half = engagement_half_angle_at(setup, moment.points, centre_distance)
    if half <= 0:
        return np.zeros((3, 3)), 0.0
    ratio, diff, zeta, omega0 = setup.speed_ratio, setup.differential_rotation_per_mm, moment.zeta, moment.omega0
    c, mat = model.model, model.material
    h_min = model.min_chip
    phi = np.linspace(-half, half, samples)
    per_time = np.zeros((samples, 3, 3))
    area = width_sum = 0.0
    for i, b1 in enumerate(phi):
        width, _, dirs, factors, _, chips, bound = moment.chips(b1, c.friction_angle, c.rake_floor)
        b, h = width[0], chips[0]
        on = (b > 0) & (h > 0)
        area += float((b[on] * h[on]).sum())
        width_sum += float(b[on].sum())
        regen = on & (bound[0] == 1) & (h > h_min)
        if not regen.any():
            continue
        hh = h[regen]
        tau = np.asarray(model.shear_stress(hh))
        slope = tau * np.maximum(1.0 - mat.mc * (hh - h_min) / hh, 0.0) * b[regen]
        # the directions from the blank frame into the machine frame (the work's turn at this instant)
        turn = rot_z(ratio * b1 + diff * zeta * b1 + setup.work_phase)
        d = dirs[0][regen] @ turn.T  # (e, 3, 3): e_c, n, p in the machine frame
        f = factors[0][regen]
        force = f[:, 0:1] * d[:, 0] - f[:, 1:2] * d[:, 1] + f[:, 2:3] * d[:, 2]
        per_time[i] = np.einsum("e,ei,ej->ij", slope, force, d[:, 1])
    integral = np.trapezoid(per_time, phi / omega0, axis=0)
    pitch_time = moment.pitch / omega0
    return integral / pitch_time * 1e3, (area / width_sum if width_sum > 0 else 0.0)


def pass_stability(
    setup: SkivingSetup,
    params: SkivingMachineParams,
    material_key: str,
    edge_radius: float = 0.010,
    speeds: np.ndarray | None = None,
    depths: int = 16,
    structure: str = "mechatronic",
    adaptive: bool = True,
) -> list[PassStability]:
    """Every pass's lobes (see the module docstring): tool speeds from 0.4 to 2.5 times the job's (``speeds`` [rpm]
    to choose), the critical infeed at each by ``depths`` trial infeeds from 0.1 to 4 times the pass's; the loop
    with the spindles' drives of the machine ``structure`` (``adaptive``: its correction on)."""
    model = ObliqueForces(material(material_key), load_cutting_model(), edge_radius)
    ratio = abs(setup.speed_ratio)  # work turns per tool turn
    n0 = setup.tool_speed
    speeds = np.linspace(0.4 * n0, 2.5 * n0, 300) if speeds is None else np.asarray(speeds, dtype=float)
    delays = 60.0 / (speeds * ratio)
    g = loop_response(setup, params, structure, adaptive)
    # the modes' frequencies and the drives': their stages' and their speed loops' (the PI's own, w / 2)
    drives = spindle_drives(params, setup, structure, adaptive).values()
    freqs = [m.frequency for m in params.loop + axis_modes(params)] + [d.frequency() for d in drives]
    freqs += [d.tuning.speed_bandwidth / 2 for d in drives if d.tuning is not None]
    f_lo = 0.5 * min(f for f in freqs if f > 0)
    f_hi = 1.6 * max(freqs)
    omega = 2 * math.pi * np.geomspace(f_lo, f_hi, 3000)
    response = g(omega)  # the loop's, the same for every pass and trial
    count = math.ceil(omega[-1] * delays.max() / (2 * math.pi)) + 2
    out = []
    # the cutter goes deeper towards the work's axis (a ring gear: away from it)
    deeper = 1.0 if setup.gear.internal else -1.0
    previous = setup.pass_centre_distances[0] - deeper * setup.passes[0]  # the tip circle just touching
    for k, (a, infeed) in enumerate(zip(setup.pass_centre_distances, setup.passes, strict=True)):
        trials = infeed * np.unique(np.append(np.geomspace(0.1, 4.0, depths), 1.0))
        lims = np.empty((len(trials), len(speeds)))
        freqs = np.empty((len(trials), len(speeds)))
        for i, d in enumerate(trials):
            dmat, _ = oriented_coefficients(setup, model, previous + deeper * d, None if k == 0 else previous)
            lb = lobes(response, dmat, omega, count)
            lims[i], freqs[i] = lb.limits(delays)
        critical = np.array([_critical(trials, lims[:, j]) for j in range(len(speeds))])
        # at the job's own speed and infeed
        mine = int(np.argmin(np.abs(trials - infeed)))
        own = float(np.interp(n0, speeds, critical))
        j0 = int(np.argmin(np.abs(speeds - n0)))
        out.append(PassStability(k, infeed, n0, own, float(freqs[mine, j0]), speeds, critical, lims[mine]))
        previous = a
    return out


def _critical(trials: np.ndarray, limits: np.ndarray) -> float:
    """The infeed at which the scale limit falls to 1 (the trial infeed's own D chatters), interpolated in the
    log of the infeed; inf if none of the trials chatters."""
    margin = np.log(limits)  # > 0 stable
    for i in range(len(trials)):
        if margin[i] <= 0:
            if i == 0 or not math.isfinite(margin[i - 1]):
                return float(trials[i])
            f = margin[i - 1] / (margin[i - 1] - margin[i])
            return float(math.exp(math.log(trials[i - 1]) + f * (math.log(trials[i]) - math.log(trials[i - 1]))))
    return math.inf


def stability_chart(results: list[PassStability], path, title: str = "") -> None:
    """The lobe diagrams: per pass the critical infeed [mm] against the tool speed [rpm], the job's operating point
    (its infeed at its speed) marked; below a curve the pass is stable."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (top, ax) = plt.subplots(2, 1, figsize=(8, 7), dpi=110, sharex=True)
    for r in results:
        (line,) = top.plot(r.speeds, np.minimum(r.margins, 1e3), label=f"pass {r.index + 1}")
        top.plot([r.tool_speed], [r.margin], "o", color=line.get_color(), mfc="white" if r.margin > 1 else None)
        cap = 4.0 * r.infeed  # the trials' reach: beyond it drawn at it (stable there)
        ax.plot(r.speeds, np.minimum(r.critical, cap), color=line.get_color(), label=f"pass {r.index + 1}")
        ax.plot([r.tool_speed], [r.infeed], "o", color=line.get_color(), mfc="white" if r.margin > 1 else None)
    top.axhline(1.0, color="k", lw=0.8)
    top.set_yscale("log")
    top.set_ylabel("stability margin (x the pass's D)")
    top.set_title(title or "stability lobes")
    top.text(0.01, 0.02, "o the job's passes (filled: chatters); below 1 the pass chatters", transform=top.transAxes,
             fontsize=8)  # fmt: skip
    ax.set_yscale("log")
    ax.set_xlabel("tool speed n0 [rpm]")
    ax.set_ylabel("critical radial infeed [mm]\n(capped at 4x the pass's)")
    for a in (top, ax):
        a.grid(True, which="both", alpha=0.3)
        a.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
