"""The path that skives a job's flank modification (seed 003 applied to skiving), iterated to its accuracy check.

1. The target: the design's deviation along each flank's helix line on the reference cylinder, e_d(side, z);
   what varies over the profile (profile crowning, tip relief, twist) the path cannot make and is reported as the
   residual it leaves.
2. The corrections' effect (the seed's k_r and k_t), measured rather than assumed: the finishing pass cut once
   along the plain path and once each with a radial (da) and a tangential (dphi2) correction growing along the
   face; the change of each flank's helix slope gives the 2 x 2 matrix J: (e_left, e_right) = J (da, dphi2). (A
   constant dphi2 only turns the whole gear, which the measuring machine's datum takes out.)
3. Knots at z_i = i b / (2n), i = -n..n (the seed's initial points; n = 10) and two beyond the face; the carriage
   passes face position z at s = z. Feed-forward: (da, dphi2)_i = J^-1 e_d(z_i).
4. Iterate (the seed's accuracy check): cut along the path (the exact swept surface of the ideal motion with the
   corrections, no chord error), measure every tooth's helix trace against the design, and correct each knot by
   J^-1 of the teeth's mean residual there (beyond the measured range, the residual at its end), until the
   largest residual is below ``tolerance`` or it stops falling.

The cut is the ideal machine's (the job's exact kinematics plus the corrections): what the simulated machine makes
of the same path is the next step (the CNC's radial axis and the summator of the electronic gearbox).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from cutting.flank import SIDES
from cutting.skiving.edge import CuttingEdge, make_edge
from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.path_correction import PathCorrection, corrected_motion
from cutting.skiving.trajectory import PassMotion
from metrology.measure import MeasureOptions, measure_helix
from virtual_machine.job import Job
from virtual_machine.setting.plan import SkivingPlan, plan_of

KNOTS = 10  # n of the seed's z_i = i b / (2n)
PROBE = 2e-3  # mm of flank movement used to measure J


@dataclass
class Iteration:
    number: int
    residual_um: dict[str, float]  # largest |design - measured| of the teeth's mean helix trace, per flank
    C_beta: dict[str, float]  # measured (mean over the teeth) [um]
    f_Hbeta: dict[str, float]  # measured against the design, mean over the teeth [um]


@dataclass
class ModificationPath:
    correction: PathCorrection
    jacobian: np.ndarray  # (2, 2): (e_left, e_right) [mm] per (da [mm], dphi2 [rad])
    iterations: list[Iteration]
    converged: bool
    measurement: dict[str, Any]  # the best cut's helices measured against the design (metrology.measure_helix)
    motions: list = field(default_factory=list)  # the passes to cut (the finishing one corrected)
    beyond_path_um: dict[str, float] = field(default_factory=dict)  # per flank: what only a cutter could make

    def table(self) -> list[dict[str, Any]]:
        return iteration_table(self.iterations)


def iteration_table(iterations: list[Iteration]) -> list[dict[str, Any]]:
    """The accuracy check's iterations as rows (measurement.json, the command line)."""
    return [
        {"iteration": i.number, "residual_um": i.residual_um, "C_beta_um": i.C_beta, "f_Hbeta_um": i.f_Hbeta}
        for i in iterations
    ]


def helix_target(job: Job, z: np.ndarray) -> dict[str, np.ndarray]:
    """The design along each flank's helix line on the reference cylinder [mm]."""
    g = job.gear
    l_ref = float(np.sqrt(g.reference_radius**2 - g.base_radius**2))
    return {side: job.modification.deviation(g, side, l_ref, z) for side in SIDES}


def beyond_path(job: Job) -> dict[str, float]:
    """Per flank, the largest part of the design [um] that differs from its helix line on the reference cylinder
    (what varies over the profile: the path cannot make it)."""
    from metrology.measure import form_roll_length

    g = job.gear
    L = np.linspace(form_roll_length(g), np.sqrt(g.tip_radius**2 - g.base_radius**2), 25)
    z = np.linspace(-g.face_width / 2, g.face_width / 2, 25)
    line = helix_target(job, z)
    out = {}
    for side in SIDES:
        full = job.modification.deviation(g, side, L[:, None], z[None, :])
        out[side] = float(np.abs(full - line[side][None, :]).max() * 1e3)
    return out


def plan_path(
    job: Job, tolerance: float = 0.2e-3, max_iterations: int = 6, plan: SkivingPlan | None = None
) -> ModificationPath:
    """Corrections of the finishing pass that make the job's modification, iterated on the exact cut (``plan``: the
    job's ideal passes as an earlier stage made them)."""
    if job.modification is None:
        raise ValueError("the job has no [modification]: nothing to plan")
    plan = plan_of(job, plan)
    st = plan.setup
    edge = make_edge(st, job.cutter_options.edge)
    passes = list(plan.passes)
    finishing = passes[-1]
    opt = MeasureOptions.from_job(job.measurement, job.modification)
    b = st.gear.face_width
    zk = np.concatenate([[-b / 2 - 2.0], np.arange(-KNOTS, KNOTS + 1) * b / (2 * KNOTS), [b / 2 + 2.0]])
    target = helix_target(job, np.clip(zk, -b / 2, b / 2))

    def cut(correction: PathCorrection):
        """The ideal machine: the exact swept surface of the ideal passes, the finishing one corrected."""
        doc = measure(st.gear, edge, [*passes[:-1], corrected_motion(finishing, correction)], opt)
        return (doc, *mean_residual(doc), None)

    doc, base, z_meas, _ = cut(PathCorrection.zero(zk))
    radius = st.gear.base_radius
    jac = np.zeros((2, 2))
    # probes that change along the face: a constant work rotation only turns the whole gear (the measuring
    # machine's datum takes it out), so J is read from the change of each flank's helix slope
    for j, (da, dphi) in enumerate(((PROBE / b, 0.0), (0.0, PROBE / b / radius))):
        probe = PathCorrection(zk, da * zk, dphi * zk)
        _, moved, _, _ = cut(probe)
        slopes = [np.polyfit(z_meas, moved[i] - base[i], 1)[0] for i in range(2)]
        jac[:, j] = np.array(slopes) / (da or dphi)
    # feed-forward from the design, then the accuracy check's corrections
    ff = np.linalg.inv(jac) @ np.array([target[side] for side in SIDES])
    correction, iterations, converged, doc, _ = accuracy_check(
        PathCorrection(zk, ff[0], ff[1]), jac, cut, tolerance, max_iterations
    )
    motions = [*passes[:-1], corrected_motion(finishing, correction)]
    return ModificationPath(correction, jac, iterations, converged, doc, motions, beyond_path(job))


#: cut(correction) -> (measurement against the design, teeth's mean helix residual per flank (2, n) [mm], its z
#: [mm], whatever else the cut made: the co-simulation on the machine)
Cut = Callable[[PathCorrection], tuple[dict[str, Any], np.ndarray, np.ndarray, Any]]


def accuracy_check(
    correction: PathCorrection, jac: np.ndarray, cut: Cut, tolerance: float, max_iterations: int
) -> tuple[PathCorrection, list[Iteration], bool, dict[str, Any], Any]:
    """The seed's accuracy check: cut along the path, compare the flanks with the design, correct every knot by
    J^-1 of the teeth's mean residual there (beyond the measured range, the residual at its end); until the largest
    residual is below ``tolerance`` [mm] or stops falling (the best path is kept). Returns the path, the
    iterations, whether it converged, and the best cut's measurement and product."""
    inverse = np.linalg.inv(jac)
    zk = correction.s
    iterations, best, converged = [], None, False
    for number in range(1, max_iterations + 1):
        doc, residual, z_meas, made = cut(correction)
        worst = {side: float(np.nanmax(np.abs(residual[i])) * 1e3) for i, side in enumerate(SIDES)}
        iterations.append(
            Iteration(
                number,
                worst,
                {side: doc["helix"][side]["C_beta"] for side in SIDES},
                {side: doc["helix"][side]["f_Hbeta_mean"] for side in SIDES},
            )
        )
        score = max(worst.values())
        if best is not None and score >= best[0] * 0.95:  # no longer falling: keep the better path
            break
        best = (score, correction, doc, made)
        if score < tolerance * 1e3:
            converged = True
            break
        at_knots = np.array([np.interp(zk, z_meas, residual[i]) for i in range(2)])  # clipped to the range's ends
        step = inverse @ (-at_knots)
        correction = PathCorrection(zk, correction.da + step[0], correction.dphi + step[1])
    _, correction, doc, made = best
    return correction, iterations, converged, doc, made


def mean_residual(doc: dict[str, Any]) -> tuple[np.ndarray, np.ndarray]:
    """The teeth's mean helix trace per flank against the design [mm] (2, n), and its z [mm]."""
    tr = doc["_traces"]
    return np.array([np.nanmean(np.asarray(tr["helix"][side]), axis=0) for side in SIDES]), np.asarray(tr["z_mm"])


def measure(gear, edge: CuttingEdge, motions: list[PassMotion], opt: MeasureOptions) -> dict[str, Any]:
    """The exact swept surface of ``motions``: its helices measured against the design (all the path reads; the
    gear the path makes is measured whole afterwards, as every cut is)."""
    return measure_helix(SweptVolumes(gear, edge, motions), gear, opt)


@dataclass
class MachinePath:
    """The path iterated on the simulated machine: its iterations and the co-simulation of the best one."""

    correction: PathCorrection
    iterations: list[Iteration]
    converged: bool
    measurement: dict[str, Any]
    sim: Any  # virtual_machine.processes.skiving.cosim.CoSimulation of the path kept

    def table(self) -> list[dict[str, Any]]:
        return iteration_table(self.iterations)


def iterate_on_machine(
    job: Job,
    plan: ModificationPath,
    run: Callable[[PathCorrection], Any],
    tolerance: float = 0.5e-3,
    max_iterations: int = 4,
) -> MachinePath:
    """The accuracy check with the simulated machine (seed 003's last step, the machine's own deviations
    included): start from the ideal machine's path, cut with ``run(correction)`` (a co-simulation), measure the
    exact swept surface of the motion the machine made against the design, and correct with the same J (the
    machine's own corrections move the flanks as the ideal kinematics' do: measured within 2 %)."""
    from cutting.skiving.sampled_motion import sampled_passes

    opt = MeasureOptions.from_job(job.measurement, job.modification)

    def cut(correction: PathCorrection):
        sim = run(correction)
        doc = measure(job.gear, sim.edge, sampled_passes(job.skiving, sim.record.passes), opt)
        return (doc, *mean_residual(doc), sim)

    correction, iterations, converged, doc, sim = accuracy_check(
        plan.correction, plan.jacobian, cut, tolerance, max_iterations
    )
    return MachinePath(correction, iterations, converged, doc, sim)


def path_summary(plan: ModificationPath, machine: MachinePath | None = None) -> dict[str, Any]:
    """measurement.json's ``modification_path``: the corrections' effect J, the accuracy check's iterations on the
    ideal machine (and on the simulated one), the path as Bezier segments, and what only a cutter could make."""
    kept = machine.correction if machine is not None else plan.correction
    out: dict[str, Any] = {
        "converged": plan.converged,
        "jacobian": {"e_per_da": list(plan.jacobian[:, 0]), "e_per_dphi_mm_per_rad": list(plan.jacobian[:, 1])},
        "iterations": plan.table(),
        "bezier_segments": kept.bezier(),
        "beyond_path_um": plan.beyond_path_um,
    }
    if machine is not None:
        out["machine_iterations"] = machine.table()
        out["machine_converged"] = machine.converged
    return out
