"""The tool-work loop's modes (machine_models/loop.py) as MuJoCo bodies and joints: static compliance against the
modes' compliance matrix, impulse responses against each mode's frequency and damping, and bad modes refused."""

from __future__ import annotations

import itertools
import math

import mujoco
import numpy as np
import pytest

from machine_models.loop import LoopMode, add_modes, compliance, frequency_response, parse_loop
from machine_models.parts import inertial, quat_x

TILT = math.radians(-20.0)  # the swivel head's turn about x, as a skiving machine's
TOOL = (
    LoopMode("tool", (1, 0, 0), 180, 0.03, 5e7),
    LoopMode("tool", (0, 1, 0), 160, 0.03, 4e7),
    LoopMode("tool", (0, 0, 1), 250, 0.03, 8e7),
    LoopMode("tool", (1, 0, 0), 250, 0.03, 6e6, "tilt", 0.25),
    LoopMode("tool", (0, 1, 0), 260, 0.03, 6e6, "tilt", 0.25),
)
WORK = (
    LoopMode("work", (1, 0, 0), 200, 0.03, 6e7),
    LoopMode("work", (0, 1, 0), 210, 0.04, 6e7),
    LoopMode("work", (1, 0, 0), 300, 0.03, 5e6, "tilt", 0.1),
    LoopMode("work", (0, 1, 0), 320, 0.03, 5e6, "tilt", 0.1),
)


def _turn(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def loop_model(modes) -> tuple[mujoco.MjModel, int, int]:
    """The loop as the skiving machine builds it (machine_models/skiving_machine.py): the work modes under the work
    spindle (a 0.15 kg m^2 table), the tool modes between a swivel head turned by TILT and the tool spindle (0.02 kg
    m^2), each spindle free about its own axis; no gravity. Returns the model and the two spindles' body ids."""
    spec = mujoco.MjSpec()
    spec.option.timestep = 1.25e-4
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.option.gravity = [0.0, 0.0, 0.0]
    world = spec.worldbody
    base = add_modes(world, modes, "work", np.eye(3), np.array([0.0, 0.0, 1.0]), 0.075)
    work = base.add_body(name="work_spindle")
    inertial(work, 1e-3, 0.15)
    work.add_joint(name="B2", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    head = world.add_body(name="head", pos=[0.3, 0.0, 0.0], quat=quat_x(TILT))
    turn = _turn(TILT)
    mount = add_modes(head, modes, "tool", turn.T, turn @ np.array([0.0, 0.0, 1.0]), 0.01)
    tool = mount.add_body(name="tool_spindle")
    inertial(tool, 1e-3, 0.02)
    tool.add_joint(name="B1", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    model = spec.compile()
    return model, model.body("tool_spindle").id, model.body("work_spindle").id


def settle(model, data, steps: int) -> None:
    for _ in range(steps):
        mujoco.mj_step(model, data)


def test_a_static_force_deflects_each_side_by_its_compliance() -> None:
    model, tool, work = loop_model(TOOL + WORK)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    x_tool, x_work = data.xpos[tool].copy(), data.xpos[work].copy()
    force = np.array([300.0, -200.0, 500.0])  # on the tool at the cutter's centre, the reaction on the workpiece
    data.xfrc_applied[tool, :3] = force
    data.xfrc_applied[work, :3] = -force
    settle(model, data, 24000)  # 3 s: 30 time constants of the slowest mode's decay
    mujoco.mj_forward(model, data)
    c_tool = compliance(TOOL, "tool", _turn(TILT) @ np.array([0.0, 0.0, 1.0]))
    c_work = compliance(WORK, "work", np.array([0.0, 0.0, 1.0]))
    # the tilts couple the directions: a force along x at the tool turns the head about y as well
    assert abs(c_tool[0, 1]) > 0 or abs(c_tool[1, 2]) > 0
    for moved, expected in ((data.xpos[tool] - x_tool, c_tool @ force), (data.xpos[work] - x_work, c_work @ -force)):
        assert np.linalg.norm(moved - expected) <= 0.02 * np.linalg.norm(expected), (moved * 1e6, expected * 1e6)


@pytest.mark.parametrize("mode", [TOOL[1], TOOL[4], WORK[0], WORK[3]], ids=lambda m: f"{m.at}-{m.kind}")
def test_an_impulse_rings_at_the_modes_frequency_and_damping(mode) -> None:
    model, tool, work = loop_model((mode,))
    data = mujoco.MjData(model)
    body = tool if mode.at == "tool" else work
    arm = _turn(TILT) @ np.array([0.0, 0.0, 1.0]) if mode.at == "tool" else np.array([0.0, 0.0, 1.0])
    push = mode.unit() if mode.kind == "translation" else np.cross(mode.unit(), arm)  # the point's mode shape
    push /= np.linalg.norm(push)
    mujoco.mj_forward(model, data)
    rest = data.xpos[body].copy()
    data.xfrc_applied[body, :3] = 2000.0 * push  # a 0.5 ms hammer blow
    settle(model, data, 4)
    data.xfrc_applied[body, :3] = 0.0
    n = 3200  # 0.4 s
    y = np.empty(n)
    for i in range(n):
        mujoco.mj_step(model, data)
        y[i] = (data.xpos[body] - rest) @ push
    t = np.arange(n) * model.opt.timestep
    # frequency from the zero crossings, damping from the logarithmic decrement of the peaks
    up = np.flatnonzero((y[:-1] < 0) & (y[1:] >= 0))
    crossings = t[up] - y[up] * model.opt.timestep / (y[up + 1] - y[up])
    f_d = (len(crossings) - 1) / (crossings[-1] - crossings[0])
    peaks = [np.abs(y[a:b]).max() for a, b in itertools.pairwise(up)]
    delta = np.log(peaks[0] / peaks[-1]) / (len(peaks) - 1)
    zeta = delta / math.sqrt(4 * math.pi**2 + delta**2)
    f_n = f_d / math.sqrt(1 - zeta**2)
    assert f_n == pytest.approx(mode.frequency, rel=0.01)
    assert zeta == pytest.approx(mode.damping, rel=0.10)


def test_the_frequency_response_is_the_compliance_at_rest_and_peaks_at_resonance() -> None:
    arm = np.array([0.0, 0.0, 1.0])
    g = frequency_response(WORK, "work", np.array([0.0, 2 * math.pi * 200.0]), arm)
    assert g[0].real == pytest.approx(compliance(WORK, "work", arm), rel=1e-12)
    # along y at 200 Hz: the y translation (210 Hz, zeta 0.04) and the tilt about x, whose 0.1 m lever moves the
    # blank's centre along -y by 0.1 m per radian (u_y^2 = 0.01): 1 / (k (1 - r^2 + 2 i zeta r)) each
    r1, r2 = 200 / 210, 200 / 300
    expected = 1 / (6e7 * (1 - r1**2 + 2j * 0.04 * r1)) + 0.01 / (5e6 * (1 - r2**2 + 2j * 0.03 * r2))
    assert g[1, 1, 1] == pytest.approx(expected, rel=1e-12)
    # at the x translation's own resonance its response is -i / (2 zeta k), the tilt about y (320 Hz) beside it
    at_x = frequency_response(WORK, "work", np.array([2 * math.pi * 200.0]), arm)[0, 0, 0]
    r3 = 200 / 320
    assert at_x == pytest.approx(-1j / (2 * 0.03 * 6e7) + 0.01 / (5e6 * (1 - r3**2 + 2j * 0.03 * r3)), rel=1e-12)


@pytest.mark.parametrize(
    ("value", "words"),
    [
        ("soft", "must be a list of modes"),
        ([{"at": "tool", "direction": [1, 0, 0], "frequency": 100, "damping": 0.03}], "missing ['stiffness']"),
        ([{"at": "table", "direction": [1, 0, 0], "frequency": 100, "damping": 0.03, "stiffness": 1e7}], "'tool' or"),
        ([{"at": "tool", "direction": [1, 1, 0], "frequency": 100, "damping": 0.03, "stiffness": 1e7}], "unit vector"),
        ([{"at": "tool", "direction": [1, 0, 0], "frequency": 100, "damping": 1.5, "stiffness": 1e7}], "damping ratio"),
        ([{"at": "tool", "direction": [1, 0, 0], "frequency": 1e5, "damping": 0.03, "stiffness": 1e7}], "1 to 5000 Hz"),
        ([{"at": "tool", "direction": [1, 0, 0], "frequency": 90, "damping": 0.03, "stiffness": 1e7, "q": 1}], "q"),
    ],
)
def test_bad_modes_are_refused_naming_what_is_wrong(value, words) -> None:
    with pytest.raises(TypeError) as err:
        parse_loop(value)
    assert words in str(err.value)


def test_a_tilt_lighter_than_the_spindle_it_turns_is_refused() -> None:
    light = (LoopMode("tool", (1, 0, 0), 2000, 0.03, 1e5, "tilt", 0.25),)  # 6e-4 kg m^2 under a 0.01 kg m^2 spindle
    with pytest.raises(ValueError, match="less than the spindle's"):
        loop_model(light)


def test_a_jobs_loop_is_parsed_and_a_bad_one_named(tmp_path) -> None:
    from small_jobs import job_from_text, small_job

    from cutting.errors import InputError
    from virtual_machine.setting.machine_layout import machine_params

    mode = '\n[[machine.model.loop]]\nat = "tool"\ndirection = [1.0, 0.0, 0.0]\nfrequency = 150.0\ndamping = 0.03\n'
    job = job_from_text(tmp_path, small_job() + mode + "stiffness = 2.0e7\n")
    (loop,) = machine_params(job).loop
    assert loop == LoopMode("tool", (1.0, 0.0, 0.0), 150.0, 0.03, 2.0e7)
    assert loop.mass == pytest.approx(2e7 / (2 * math.pi * 150) ** 2)
    with pytest.raises(InputError) as err:
        job_from_text(tmp_path, small_job() + mode + "stiffness = -1.0\n", "bad.toml")
    assert err.value.keys == ["machine.model.loop"] and "modal stiffness > 0" in str(err.value)
