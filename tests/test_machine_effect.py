"""What the machine did (virtual_machine/processes/skiving/machine_effect.py): the forces per pass, the displacement at
the generating point, and the static deflection's known answer on the gear."""

from __future__ import annotations

import math
from pathlib import Path
from unittest import mock

import numpy as np
import pytest
from small_jobs import small_job

from cutting.skiving.exact_sweep import SweptVolumes
from cutting.skiving.sampled_motion import sampled_passes
from metrology.measure import measure_gear
from virtual_machine.job import load_job
from virtual_machine.processes.skiving.cosim import cosimulate
from virtual_machine.processes.skiving.machine_effect import (
    FEED,
    flank_normals,
    generating_point_displacement,
    pass_deflection,
)
from virtual_machine.processes.skiving.run import run_job
from virtual_machine.processes.skiving.stability import pass_stability
from virtual_machine.setting.machine_layout import machine_params

JOBS = Path(__file__).resolve().parent.parent / "assets" / "jobs"
#: a roughing pass and a finishing pass of 0.25 mm on the 18-tooth m1 gear, 4 mm face
SMALL = small_job(sweep_error=0.02, axial_feed=0.4, face_width=4.0).replace("passes = [2.25]", "passes = [2.0, 0.25]")
#: one soft mode at the tool along the centre distance: 20 N/um (issue 42's proof), 150 Hz, zeta 0.05
K = 2.0e7
SOFT = SMALL + (
    '\n[[machine.model.loop]]\nat = "tool"\ndirection = [1.0, 0.0, 0.0]\nfrequency = 150.0\ndamping = 0.05\n'
    f"stiffness = {K}\n"
)


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    """The job on the default machine and with the soft mode: each run's document and co-simulation."""
    import virtual_machine.processes.skiving.run as run_module

    tmp = tmp_path_factory.mktemp("effect")
    out, cosimulate = [], run_module.cosimulate
    sims = []

    def keep(*args, **kwargs):
        sims.append(cosimulate(*args, **kwargs))
        return sims[-1]

    for name, text in (("rigid", SMALL), ("soft", SOFT)):
        path = tmp / f"{name}.toml"
        path.write_text(text)
        with mock.patch.object(run_module, "cosimulate", keep):
            doc = run_job(path, tmp / name)
        out.append((load_job(path), doc, sims[-1]))
    return out


def radial_force(sim, job) -> np.ndarray:
    """Per load row: the cutting load's radial component on the tool [N] (the resultant on the workpiece, turned
    with the work spindle into the machine frame; positive: pushing the tool out along the centre distance)."""
    rec, rows = sim.record, sim.load_rows
    turn = np.interp(rows[:, 0], rec.t, rec.q[:, 1]) + job.skiving.work_phase
    return -(np.cos(turn) * rows[:, 1] - np.sin(turn) * rows[:, 2])


def _at_section(job, doc, sim):
    """While the finishing pass's cutter passes the span's section (the helix range's end, +-0.3 mm): the mean radial
    force on the tool [N] and the mean displacement normal to the flanks at the generating point [um]."""
    rec, rows = sim.record, sim.load_rows
    z = doc["evaluation"]["helix_z_mm"][1]
    last = len(job.skiving.passes) - 1
    radial = radial_force(sim, job)
    near = (np.abs(np.interp(rows[:, 0], rec.t, rec.q[:, 2]) - z) < 0.3) & (
        np.interp(rows[:, 0], rec.t, rec.pass_index) > last - 0.5
    )
    _, index, disp = generating_point_displacement(rec, job.skiving)
    p3 = rec.q[rec.segment == FEED, 2]
    there = (np.abs(p3 - z) < 0.3) & (index == last)
    return float(radial[near].mean()), float((disp[there] @ flank_normals(job.skiving).T).mean())


@pytest.mark.slow
def test_a_soft_radial_loop_pushes_the_tool_off_the_flanks_by_its_static_deflection(pair) -> None:
    """The finishing pass's radial force F on the tool pushes it out by delta = F / k on the soft mode: at the
    generating point the tool stands delta sin(alpha_n) further off each flank than on the rigid machine (within
    5 %: the loop's static deflection in the run), and the teeth come out thicker: the span grows.

    Issue 42's proof asks the span's change to be 2 delta sin(alpha_n) within 20 % in a steady cut (spur_external):
    here, on a 4 mm face that holds no steady engagement, it is 8.7 um against 11.0 um (0.79 of it), and on an 8 mm
    face 0.45 of it: the flank at the span's section is finished while the cutter enters the face, earlier than
    the cutter's passing of that section, at a smaller force (open: docs/forces.md)."""
    (job, rigid, sim0), (_, soft, sim1) = pair
    force, moved = _at_section(job, soft, sim1)
    _, still = _at_section(job, rigid, sim0)
    delta = force / K * 1e6  # um
    alpha_n = math.radians(20.0)
    assert force > 100.0  # the thrust pushes the tool out of the space
    assert moved - still == pytest.approx(delta * math.sin(alpha_n), rel=0.05), (moved, still, delta)
    change = (soft["thickness"]["span"]["W_k_mm"] - rigid["thickness"]["span"]["W_k_mm"]) * 1e3
    assert 0.3 * 2 * delta * math.sin(alpha_n) < change < 1.05 * 2 * delta * math.sin(alpha_n)


@pytest.mark.slow
def test_the_report_gives_each_pass_its_components_and_vibration(pair) -> None:
    (_, rigid, _), (_, soft, _) = pair
    for doc in (rigid, soft):
        passes = doc["run"]["forces"]["passes"]
        assert [p["pass"] for p in passes] == [1, 2]
        for p in passes:
            assert p["cutting_mean_N"] > p["passive_mean_N"] > 0 and p["thrust_mean_N"] > 0
            assert p["peak_N"] >= max(p["cutting_mean_N"], p["thrust_mean_N"])
            assert set(p["flank_normal_deflection_um"]) == {"mean", "peak", "flanks_mean"}
            assert len(p["tool_force_machine_mean_N"]) == 3
        assert passes[0]["cutting_mean_N"] > passes[1]["cutting_mean_N"]  # the roughing pass takes more
        for v in doc["run"]["vibration"]:
            assert v["amplitude_um"] >= 0 and v["frequency_hz"] > 0 and "warning" not in v
    # the soft loop rings more under the tooth-passing force
    assert soft["run"]["vibration"][0]["amplitude_um"] > rigid["run"]["vibration"][0]["amplitude_um"]


@pytest.mark.slow
def test_spur_external_on_a_soft_radial_axis_grows_its_span_by_twice_the_flank_normal_deflection(tmp_path) -> None:
    """Issue 42's proof: spur_external with the tool's radial (centre-distance) stiffness set to 20 N/um (the radial
    slide, [machine.model] radial_stiffness, against its 200 N/um): the span W_k grows by 2 delta sin(alpha_n),
    delta = the finishing pass's mean radial force in the steady cut (the face's middle half) over the stiffness,
    within 20 %; the rigid run's own radial deflection (F / 200 N/um) subtracted. Here on a 10 mm face at 0.6 mm
    feed (the same gear, cutter, passes and machine; a sixth of the run): the finishing pass's radial force 199 N
    (208 N on the stiff axis), the span +6.26 um against 6.09 um (1.03). And the chip of the moment's volume per pass
    against the removal's on the stiff run (0.95, 0.92, 0.94, 0.67: the thin finishing layer under-counted)."""
    text = (JOBS / "spur_external.toml").read_text()
    text = text.replace("face_width = 20.0", "face_width = 10.0").replace("axial_feed = 0.2 ", "axial_feed = 0.6 ")
    soft = text.replace("[machine]", "[machine.model]\nradial_stiffness = 2.0e7\n\n[machine]", 1)
    (tmp_path / "rigid.toml").write_text(text)
    (tmp_path / "soft.toml").write_text(soft)
    found = {}
    for name in ("rigid", "soft"):
        job = load_job(tmp_path / f"{name}.toml")
        sim = cosimulate(job, removal="dexel" if name == "rigid" else "none")  # the soft run's chips are not read
        exact = SweptVolumes(job.gear, sim.edge, sampled_passes(job.skiving, sim.record.passes))
        doc = measure_gear(exact, job.gear)
        rec, rows = sim.record, sim.load_rows
        radial = radial_force(sim, job)
        last = len(job.skiving.passes) - 1
        steady = (np.interp(rows[:, 0], rec.t, rec.pass_index) > last - 0.5) & (
            np.abs(np.interp(rows[:, 0], rec.t, rec.q[:, 2])) < job.gear.face_width / 4
        )
        found[name] = (doc["thickness"]["span"]["W_k_mm"], float(radial[steady].mean()))
        if name == "rigid":  # the chip of the moment in later passes: the space the passes before opened holds none
            for k in range(len(job.skiving.passes)):
                mine = [a.load for a in sim.loads if a.pass_index == k]
                ratio = sum(ld.model_volume for ld in mine) / sum(ld.volume for ld in mine)
                assert 0.6 < ratio < 1.1, (k, ratio)  # measured 0.95, 0.92, 0.94, 0.67 (the thin finishing layer)
    (w0, f0), (w1, f1) = found["rigid"], found["soft"]
    assert f1 > 100.0  # the thrust pushes the tool out of the space
    delta = f1 / 2.0e7 - f0 / 2.0e8  # m: the soft axis's deflection less the rigid one's
    expected = 2 * delta * 1e6 * math.sin(math.radians(20.0))
    assert (w1 - w0) * 1e3 == pytest.approx(expected, rel=0.2), (w1 - w0, expected)


def _band(sim, job, zs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Over the finishing pass, at each height ``zs`` [mm] of the generating point (the carriage within +-0.05 mm):
    the mean radial force on the tool [N] and the mean displacement normal to the two flanks there [um] (n, 2)."""
    rec, rows = sim.record, sim.load_rows
    last = len(job.skiving.passes) - 1
    radial = radial_force(sim, job)
    at = np.interp(rows[:, 0], rec.t, rec.q[:, 2])
    finishing = np.interp(rows[:, 0], rec.t, rec.pass_index) > last - 0.5
    _, index, disp = generating_point_displacement(rec, job.skiving)
    normal = disp[index == last] @ flank_normals(job.skiving).T
    p3 = rec.q[rec.segment == FEED, 2][index == last]
    force = np.array([radial[finishing & (np.abs(at - z) < 0.05)].mean() for z in zs])
    return force, np.array([normal[np.abs(p3 - z) < 0.05].mean(axis=0) for z in zs])


@pytest.mark.slow
def test_the_default_job_with_one_soft_mode_as_its_static_and_dynamic_estimates_say(tmp_path) -> None:
    """Issue 42's proof: the default job with a user's [[machine.model.loop]] of one soft tool mode along the centre
    distance (20 N/um, 150 Hz, zeta 0.05), each estimate stated before the run is read.

    Dynamic: `skive stability` gives margins 1.59 and 3.19 (stable, with the spindles' drives in the loop), so the run
    must not chatter: the mode rings under the changing tooth load at its damped frequency with the radial slide in
    series (measured 135-136 Hz, 0.7 um, not growing beyond 1.1x).

    Static, from the finishing pass's radial force F(z) while the generating point crosses height z of the helix
    range (the carriage there): the tool stands delta_n(z) = F(z) / k |n_x| further off each flank (n_x = sin
    alpha_n, the flank normals' part along the centre distance). On the 4 mm face F(z) is no constant: it builds up
    from 75 N as the cutter enters to 123 N and 159 N at the far end (the pass's mean, with the entry and the exit, 82
    N), and the estimate follows it:
    - the mean displacement normal to the flanks over the range grows by the mean of delta_n (1.81 um; measured
      1.82 / 1.78 um, within 10 %);
    - the helix slope f_Hbeta of each flank grows by the slope of delta_n(z) over L_beta (1.84 um; measured +1.65 /
      +1.83 um, within 20 %), so its class is the class of the rigid run's f_Hbeta plus that (2.8 um: class 4, measured
      4, where the rigid run has 1);
    - the span, whose anvils touch the outermost points of the range, grows between twice the mean and twice the
      largest delta_n (3.6-5.4 um; measured 4.6 um);
    - nothing else of the estimate changes a class: the overall class is the rigid run's (7, the profile form's,
      which a rigid shift of the tool leaves alone) or the helix slope's, whichever is worse."""
    from metrology.tolerances import grade

    base = (JOBS / "default.toml").read_text()
    mode = '\n[[machine.model.loop]]\nat = "tool"\ndirection = [1.0, 0.0, 0.0]\nfrequency = 150.0\ndamping = 0.05\n'
    (tmp_path / "rigid.toml").write_text(base)
    (tmp_path / "soft.toml").write_text(base + mode + f"stiffness = {K}\n")
    rigid, soft = (load_job(tmp_path / f"{n}.toml") for n in ("rigid", "soft"))
    margins = [p.margin for p in pass_stability(soft.skiving, machine_params(soft), "16MnCr5", 0.010)]
    assert min(margins) > 1.0
    found = {}
    for name, job in (("rigid", rigid), ("soft", soft)):
        sim = cosimulate(job, removal="none")  # the gear is its exact swept surfaces; no chip volume is read
        doc = measure_gear(SweptVolumes(job.gear, sim.edge, sampled_passes(job.skiving, sim.record.passes)), job.gear)
        found[name] = (doc, pass_deflection(sim.record, job.skiving), sim)
    (doc0, _, sim0), (doc1, moved1, sim1) = found["rigid"], found["soft"]
    assert all("warning" not in d for d in moved1)
    assert max(d["vibration"]["growth"] for d in moved1) < 1.2

    z0, z1 = doc1["evaluation"]["helix_z_mm"]
    zs = np.linspace(z0, z1, 37)
    force, normal1 = _band(sim1, soft, zs)
    _, normal0 = _band(sim0, rigid, zs)
    assert force.max() > 100.0  # the thrust pushes the tool out of the space
    n_x = float(np.mean(np.abs(flank_normals(soft.skiving)[:, 0])))
    delta_n = force / K * 1e6 * n_x  # um
    moved = (normal1 - normal0).mean(axis=0)
    assert moved == pytest.approx([delta_n.mean()] * 2, rel=0.1), (moved, delta_n.mean())

    slope = float(np.polyfit(zs, delta_n, 1)[0]) * (z1 - z0)  # um over L_beta
    g = soft.gear
    for side in ("left", "right"):
        change = doc1["helix"][side]["f_Hbeta_mean"] - doc0["helix"][side]["f_Hbeta_mean"]
        assert change == pytest.approx(slope, rel=0.2), (side, change, slope)
    predicted = max(abs(doc0["helix"][s]["f_Hbeta"] + slope) for s in ("left", "right"))
    helix_class = grade(predicted, "f_Hbeta", g.teeth, g.normal_module, g.face_width, math.degrees(g.beta))
    classes0, classes1 = doc0["iso1328"]["class"], doc1["iso1328"]["class"]
    assert classes1["f_Hbeta"] == helix_class > classes0["f_Hbeta"]
    assert classes1["overall"] == max(classes0["overall"], helix_class)

    span = (doc1["thickness"]["span"]["W_k_mm"] - doc0["thickness"]["span"]["W_k_mm"]) * 1e3
    assert 2 * delta_n.mean() <= span <= 2 * delta_n.max(), (span, delta_n.mean(), delta_n.max())
