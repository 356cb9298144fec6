"""The drives of each kinematic structure of seed 000, added to the common machine (bodies of skiving_machine).

- ``mechatronic`` (S4, fig. 4): servo motors M1 -> B1, M2 -> B2, M3 -> TV, each through its stage.
- ``mechanical`` (S1, fig. 1): the main motor M1 -> speed chain (iv) -> B1; guitar ix from B1 to shaft 5 and
  guitar iy from TV to shaft 14 (``shaft5``, ``shaft14``: hinges with the change gears' inertia), the differential
  with the dividing chain to the work spindle ``B2 = g5 shaft5 + g14 shaft14`` (c1 iS, c2 iS), each stage with
  its own stiffness and backlash; the feed chain ``TV = k B2`` (is) behind clutch 12; the setting-traverse motor
  M2 drives TV through clutch 15. (In the seed the helix chain leaves the lead screw behind clutch 12; here B4
  always follows TV, so a rapid return keeps the helix phase, which the real machine gets by re-indexing.) With
  iy disengaged (spur gear) shaft 14 is held by the differential's self-locking worm.
- ``hydraulic-differential`` (S2, fig. 2): M1 -> iv -> B1; stepping motors GShD1 (fed by GGI1 on B1) and GShD2
  (GGI2 on TV) drive the differential: ``B2 = g1 GShD1 + g2 GShD2``; GShD3 (GGI3 on B2, or the CNC's rapid
  pulses) drives the lead screw: ``TV = g3 GShD3``.
- ``hydraulic-shaft`` (S3, fig. 3): M1 -> iv -> B2 (the master of the setting ``kx``: one work turn ->
  (z2/z0)(1 + s/T) cutter turns); GShD (GGI on B2) drives the tool: ``B1 = g1 GShD``; feed ``TV = k B2`` (is)
  with a reversing gear for the return stroke and a brake on the screw. (The seed's chain listing runs from
  B1 to B2; the setting formula makes the work the master, which is what is built.)

Every chain is a tendon relation with the stage's stiffness, backlash and damping (drives.couple_linear).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import mujoco

from machine_models.drives import couple, couple_linear
from machine_models.parameters import SkivingMachineParams
from machine_models.parts import GREY, inertial, motor, visual


@dataclass(frozen=True)
class ChainRatios:
    """Signed, realised ratios of a structure's chains (rad per rad; TV in rad)."""

    speed: float = 1.0  # spindle driven by the main motor, per motor rad (iv c3)
    generating: float = 0.0  # S1: B2 per shaft-5 rad; S2: B2 per GShD1 rad (both c1 iS); S3: B1 per GShD rad (c1)
    helix: float = 0.0  # S1: B2 per shaft-14 rad; S2: B2 per GShD2 rad (both c2 iS)
    ix: float = 0.0  # S1: shaft 5 per B1 rad (the realised guitar ix)
    iy: float = 0.0  # S1: shaft 14 per TV rad (the realised guitar iy; 0: disengaged)
    feed: float = 0.0  # S1, S3: TV per B2 rad (c4 is / t_TV); S2: TV per GShD3 rad (c4 / t_TV)


@dataclass
class Drives:
    actuators: tuple[str, ...]
    chain_driven: frozenset[str] = frozenset()  # joints whose home position a chain sets
    clutched: frozenset[str] = frozenset()  # tendons that a clutch engages and releases
    extra: dict = field(default_factory=dict)


def _motor_body(spec, parent, name: str, pos, inertia: float, peak: float) -> None:
    motor(spec, parent.add_body(name=f"{name}_rotor", pos=list(pos)), name, inertia, peak)


def mechatronic(spec, bodies, params: SkivingMachineParams, chains: ChainRatios) -> Drives:
    world, head = bodies["world"], bodies["head"]
    _motor_body(spec, head, "M1", (0.1, 0.0, 0.2), params.tool_motor_inertia, params.tool_motor_torque)
    spec.body("M1_rotor").gravcomp = params.counterbalance
    _motor_body(spec, world, "M2", (-0.28, 0.0, -0.09), params.work_motor_inertia, params.work_motor_torque)
    _motor_body(spec, world, "M3", (0.35, 0.25, 0.38), params.feed_motor_inertia, params.feed_motor_torque)
    couple(spec, "tool_drive", "B1", "M1", params.tool_drive)
    couple(spec, "work_drive", "B2", "M2", params.work_drive)
    couple(spec, "feed_drive", "TV", "M3", params.feed_drive)
    return Drives(("M1", "M2", "M3"))


def mechanical(spec, bodies, params: SkivingMachineParams, chains: ChainRatios) -> Drives:
    world = bodies["world"]
    _motor_body(spec, world, "M1", (-0.3, 0.3, 0.3), params.main_motor_inertia, 2.5 * params.main_motor_torque)
    _motor_body(spec, world, "M2", (0.35, 0.25, 0.38), params.traverse_motor_inertia, params.traverse_motor_torque)
    couple(spec, "speed_chain", "B1", "M1", replace(params.speed_chain, ratio=chains.speed))
    for name, pos in (("shaft5", (-0.25, 0.2, -0.1)), ("shaft14", (-0.25, 0.3, -0.1))):
        body = world.add_body(name=name, pos=list(pos))
        inertial(body, 2.0, params.guitar_shaft_inertia)
        body.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
        visual(body, mujoco.mjtGeom.mjGEOM_CYLINDER, (0.04, 0.01), GREY)
    couple(spec, "ix", "shaft5", "B1", replace(params.ix_stage, ratio=chains.ix))
    if chains.iy:
        couple(spec, "iy", "shaft14", "TV", replace(params.iy_stage, ratio=chains.iy))
    else:  # spur gear: the iy guitar is out; the differential's worm holds shaft 14
        couple_linear(spec, "iy", [("shaft14", 1.0)], replace(params.iy_stage, stiffness=None, backlash=0.0))
    couple_linear(
        spec,
        "generating_chain",
        [("B2", 1.0), ("shaft5", -chains.generating), ("shaft14", -chains.helix)],
        params.generating_chain,
    )
    couple_linear(spec, "feed_chain", [("TV", 1.0), ("B2", -chains.feed)], params.feed_chain)  # clutch 12
    couple(spec, "traverse", "TV", "M2", params.feed_drive)  # clutch 15
    return Drives(("M1", "M2"), frozenset({"B2", "shaft5", "shaft14"}), frozenset({"feed_chain", "traverse"}))


def _stepping_motor(spec, world, name: str, pos, params: SkivingMachineParams) -> None:
    _motor_body(spec, world, name, pos, params.hydraulic_motor_inertia, 10 * params.hydraulic_torque_limit)


def hydraulic_differential(spec, bodies, params: SkivingMachineParams, chains: ChainRatios) -> Drives:
    world = bodies["world"]
    _motor_body(spec, world, "M1", (-0.3, 0.3, 0.3), params.main_motor_inertia, 2.5 * params.main_motor_torque)
    couple(spec, "speed_chain", "B1", "M1", replace(params.speed_chain, ratio=chains.speed))
    for name, pos in (("GShD1", (-0.3, -0.2, -0.1)), ("GShD2", (-0.3, -0.35, -0.1)), ("GShD3", (0.35, 0.4, 0.38))):
        _stepping_motor(spec, world, name, pos, params)
    couple_linear(
        spec,
        "differential",
        [("B2", 1.0), ("GShD1", -chains.generating), ("GShD2", -chains.helix)],
        params.differential_stage,
    )
    couple(spec, "feed_drive", "TV", "GShD3", replace(params.feed_drive, ratio=chains.feed))
    return Drives(("M1", "GShD1", "GShD2", "GShD3"))


def hydraulic_shaft(spec, bodies, params: SkivingMachineParams, chains: ChainRatios) -> Drives:
    world = bodies["world"]
    _motor_body(spec, world, "M1", (-0.3, 0.3, 0.3), params.main_motor_inertia, 2.5 * params.main_motor_torque)
    couple(spec, "speed_chain", "B2", "M1", replace(params.speed_chain, ratio=chains.speed))
    _stepping_motor(spec, world, "GShD", (-0.3, -0.2, -0.1), params)
    couple(spec, "generating_chain", "B1", "GShD", replace(params.differential_stage, ratio=chains.generating))
    # the feed chain with its reversing gear (forward for the stroke, reverse for the return), and the screw's
    # brake that holds the carriage while neither is engaged
    couple_linear(spec, "feed_chain", [("TV", 1.0), ("B2", -chains.feed)], params.feed_chain)
    couple_linear(spec, "feed_reverse", [("TV", 1.0), ("B2", chains.feed)], params.feed_chain)
    couple_linear(spec, "screw_brake", [("TV", 1.0)], params.feed_chain)
    return Drives(("M1", "GShD"), frozenset({"B1"}), frozenset({"feed_chain", "feed_reverse", "screw_brake"}))


DRIVES: dict[str, Callable[..., Drives]] = {
    "mechatronic": mechatronic,
    "mechanical": mechanical,
    "hydraulic-differential": hydraulic_differential,
    "hydraulic-shaft": hydraulic_shaft,
}

#: the [machine.model] parameter that sets each motor's peak torque, per structure (for the CNC's alarm text)
MOTOR_TORQUE_KEYS: dict[str, dict[str, str]] = {
    "mechatronic": {"M1": "tool_motor_torque", "M2": "work_motor_torque", "M3": "feed_motor_torque"},
    "mechanical": {"M1": "main_motor_torque", "M2": "traverse_motor_torque"},
    "hydraulic-differential": {
        "M1": "main_motor_torque",
        **{m: "hydraulic_torque_limit" for m in ("GShD1", "GShD2", "GShD3")},
    },
    "hydraulic-shaft": {"M1": "main_motor_torque", "GShD": "hydraulic_torque_limit"},
}
