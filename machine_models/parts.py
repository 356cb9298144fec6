"""Building blocks of the MJCF machines: units, colours, inertial bodies, visual geoms, motors.

Shared by the skiving machine and the thread lathe so each model file only says what the machine is.
"""

from __future__ import annotations

import math

import mujoco

MM = 1e-3
STEEL = 7850.0  # kg/m^3
GREY, DARK, BLUE, ORANGE, STEELC = (
    [0.6, 0.6, 0.62, 1],
    [0.25, 0.25, 0.28, 1],
    [0.2, 0.4, 0.8, 1],
    [0.95, 0.55, 0.1, 1],
    [0.75, 0.75, 0.78, 1],
)


def machine_spec(name: str, timestep: float, integrator: str, gravity: tuple[float, float, float]) -> mujoco.MjSpec:
    """An empty machine model: angles in radians, explicit inertias, the time step and integrator, gravity, and
    no collision detection (no body touches another: the cut is the cutting engine's business)."""
    spec = mujoco.MjSpec()
    spec.modelname = name
    spec.compiler.degree = False
    spec.compiler.inertiafromgeom = mujoco.mjtInertiaFromGeom.mjINERTIAFROMGEOM_FALSE
    spec.option.timestep = timestep
    spec.option.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{integrator.upper()}")
    spec.option.gravity = list(gravity)
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    spec.visual.global_.offwidth = 1280
    return spec


def quat_z(angle: float) -> list[float]:
    return [math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)]


def quat_x(angle: float) -> list[float]:
    return [math.cos(angle / 2), math.sin(angle / 2), 0.0, 0.0]


def inertial(body, mass: float, axial: float, transverse: float | None = None) -> None:
    """Mass and principal inertia (axial about the body's z) at the body origin."""
    body.mass = mass
    t = axial / 2 + 1e-6 if transverse is None else transverse
    body.inertia = [t, t, axial]
    body.ipos = [0.0, 0.0, 0.0]  # must be set: left unset it takes the body's position
    body.explicitinertial = True


def visual(body, kind, size, rgba, pos=(0, 0, 0), quat=(1, 0, 0, 0), name: str = "") -> None:
    body.add_geom(
        name=name,
        type=kind,
        size=list(size),
        rgba=rgba,
        pos=list(pos),
        quat=list(quat),
        contype=0,
        conaffinity=0,
        mass=0.0,
        density=0.0,
    )


def motor(spec: mujoco.MjSpec, body, name: str, inertia: float, peak: float) -> None:
    """A motor: rotor hinge ``name`` with its inertia, and a torque actuator ``name`` (ctrl in N m)."""
    inertial(body, 8.0, inertia)
    body.add_joint(name=name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1])
    visual(body, mujoco.mjtGeom.mjGEOM_CYLINDER, (0.05, 0.07), DARK)
    act = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
    act.set_to_motor()
    act.ctrllimited = True
    act.ctrlrange = [-peak, peak]


def tendon_coefs(model: mujoco.MjModel, tendon: str) -> dict[str, float]:
    t = model.tendon(tendon).id
    adr, num = int(model.tendon_adr[t]), int(model.tendon_num[t])
    return {model.joint(int(model.wrap_objid[i])).name: float(model.wrap_prm[i]) for i in range(adr, adr + num)}
