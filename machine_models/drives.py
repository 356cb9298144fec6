"""A drive stage in MuJoCo: motor -> torsional (or axial) compliance with backlash -> driven joint.

The stage is a fixed tendon ``L = driven - ratio * motor`` (driven-joint units: rad or m). Its passive
force is a dead-band spring (MuJoCo tendon ``springlength`` with two values): no force while ``|L| < b/2``,
``-K (|L| - b/2)`` beyond, so backlash and compliance act in series without a massless body between them,
and the stage damping acts on dL/dt. A rigid stage (stiffness None) is a tendon equality with a stiff
constraint (time constant 2 h, impedance 0.99..0.999): MuJoCo's default softness is far too soft for a
machine tool (library notes A1).
"""

from __future__ import annotations

import math

import mujoco

from machine_models.parameters import DriveStage


def couple(spec: mujoco.MjSpec, name: str, driven: str, motor: str, stage: DriveStage) -> None:
    """Add tendon ``name`` (and for a rigid stage its equality) coupling joint ``driven`` to joint ``motor``."""
    couple_linear(spec, name, [(driven, 1.0), (motor, -stage.ratio)], stage)


def couple_linear(spec: mujoco.MjSpec, name: str, terms: list[tuple[str, float]], stage: DriveStage) -> None:
    """A chain whose relation is linear in several joints: ``L = sum(coef * q) = 0`` (e.g. a differential:
    ``B2 - a B1 - b TV``), in the units of the first joint, with the stage's stiffness, backlash and damping
    (``stage.ratio`` is not used here: the coefficients carry the ratios)."""
    tendon = spec.add_tendon(name=name)
    for joint, coef in terms:
        tendon.wrap_joint(joint, coef)
    if stage.stiffness is None:
        eq = spec.add_equality(name=name, type=mujoco.mjtEq.mjEQ_TENDON, name1=name)
        eq.solref = [2 * spec.option.timestep, 1.0]
        eq.solimp = [0.99, 0.999, 0.001, 0.5, 2.0]
        return
    tendon.stiffness = [stage.stiffness, 0.0, 0.0]
    tendon.springlength = [-stage.backlash / 2, stage.backlash / 2]
    tendon.damping = [stage.damping, 0.0, 0.0]


def stage_frequency(stiffness: float, inertia_driven: float, inertia_motor: float, ratio: float) -> float:
    """Natural frequency [Hz] of a stage between its two inertias (motor inertia referred to the driven side)."""
    j_motor = inertia_motor / ratio**2
    j = inertia_driven * j_motor / (inertia_driven + j_motor)
    return math.sqrt(stiffness / j) / (2 * math.pi)
