"""Oblique cutting per edge element (cutting.oblique, cutting.forces.oblique_load): a slab planed by a straight edge
with rake and inclination, against the model's forces worked by hand, and the chip's energy."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cutting.errors import InputError
from cutting.forces import EdgeFaces, engagement_load, oblique_sums
from cutting.oblique import load_cutting_model, oblique_forces

# The worked example: 16MnCr5 (kc1.1 = 2100 N/mm^2, mc = 0.26), beta_a = 30 deg (the table's), h = 0.1 mm,
# b = 2 mm, normal rake gamma_n = +10 deg, inclination lambda_s = 15 deg. By hand:
#   kc(0.1) = 2100 x 0.1^-0.26 = 3821.37 N/mm^2
#   the table's tool (gamma = 6 deg, lambda = 0): phi = 45 - (30 - 6)/2 = 33 deg,
#     K_c / tau = cos 24 / (sin 33 cos 57) = 3.07973, so tau_s = 3821.37 / 3.07973 = 1240.81 N/mm^2
#   tan beta_n = tan 30 cos 15 -> beta_n = 29.1474 deg; phi_n = 45 - (29.1474 - 10)/2 = 35.4263 deg
#   S = sqrt(cos^2(54.5737) + (tan 15 sin 29.1474)^2) = 0.594165
#   K_c = tau / (sin phi_n S) (cos 19.1474 + tan^2 15 sin 29.1474) = 3529.39 N/mm^2
#   K_t = tau / (sin phi_n S) sin 19.1474 / cos 15 = 1223.38 N/mm^2
#   K_p = tau / (sin phi_n S) (cos 19.1474 tan 15 - tan 15 sin 29.1474) = 441.760 N/mm^2
#   F = K h b: Fc = 705.878 N, Ft = 244.675 N, Fp = 88.352 N
# With a 10 um edge (h_min = 0.3 x 10 um = 3 um; edge forces 10 and 17 N/mm at 10 um): the sheared chip is
# 0.097 mm: Fc = 3529.39 x 0.194 + 10 x 2 = 704.70 N, Ft = 1223.38 x 0.194 + 17 x 2 = 271.34 N, Fp = 85.70 N.
SHARP = (705.878, 244.675, 88.352)
HONED = (704.70, 271.34, 85.70)
GAMMA, LAMBDA, H, B = math.radians(10.0), math.radians(15.0), 0.1, 2.0


@pytest.mark.parametrize(("radius", "expected"), [(0.0, SHARP), (0.010, HONED)])
def test_three_components_of_the_worked_example(radius, expected) -> None:
    model = oblique_forces("16MnCr5", radius)
    forces = model.element(H, B, GAMMA, LAMBDA)
    assert [float(f) for f in forces] == pytest.approx(expected, rel=0.01)
    assert model.shear_stress(H) == pytest.approx(1240.81, rel=1e-4)


def test_orthogonal_cutting_is_merchants() -> None:
    model = oblique_forces("16MnCr5")
    for g in (-20.0, 0.0, 6.0, 15.0):
        kc, kt, kp = model.coefficients(0.2, math.radians(g), 0.0)
        assert kt / kc == pytest.approx(math.tan(math.radians(30.0 - g)), rel=1e-12)  # Ft / Fc = tan(beta - gamma)
        assert kp == pytest.approx(0.0, abs=1e-9)
    assert model.coefficients(0.2, math.radians(6.0), 0.0)[0] == pytest.approx(model.material.kc(0.2), rel=1e-12)
    # below the floor the rake is held
    assert model.coefficients(0.2, math.radians(-55.0), 0.0)[1] == model.coefficients(0.2, math.radians(-30.0), 0.0)[1]


def test_a_chip_under_the_minimum_only_ploughs() -> None:
    model = oblique_forces("16MnCr5", 0.010)
    fc, ft, fp = model.element(0.002, 1.0, 0.0, 0.2)  # 2 um < h_min = 3 um
    assert (float(fc), float(ft), float(fp)) == pytest.approx((10.0, 17.0, 0.0))
    assert model.element(0.0, 1.0, 0.0, 0.0)[0] == 0.0


def planer(gamma: float, lam: float, speed: float, frame: np.ndarray):
    """A straight edge that spans a slab of width B (normal to the velocity) at inclination ``lam``, its rake face
    at normal rake ``gamma``, moving at ``speed`` [mm/s] along x of the slab, cutting its surface z = 0 (the chip
    above it, the tool's body above). Everything turned by ``frame`` (3, 3). Returns the pose, the edge (rake frame),
    its faces and the unit directions (cutting, thrust normal into the tool's side, passive) in the slab's frame."""
    t0 = np.array([math.sin(lam), math.cos(lam), 0.0])
    e1 = np.array([math.cos(lam), -math.sin(lam), 0.0])  # the velocity's part normal to the edge
    n = np.array([0.0, 0.0, 1.0])
    g = math.cos(gamma) * e1 + math.sin(gamma) * n  # the rake face's normal towards the chip
    rot = np.column_stack([t0, np.cross(g, t0), g])  # rake frame -> slab frame
    half = B / 2 / math.cos(lam)
    edge = np.column_stack([np.linspace(-half, half, 41), np.zeros(41), np.zeros(41)])
    body = np.array([0.0, 1.0 if np.cross(g, t0)[2] > 0 else -1.0, 0.0])
    faces = EdgeFaces.of_outline(edge, [0.0, 0.0, 1.0])
    faces = EdgeFaces(faces.rake, np.repeat(body[None], 40, axis=0))

    def pose(t):
        t = np.atleast_1d(t)
        trans = np.zeros((len(t), 3))
        trans[:, 0] = speed * t
        return np.repeat((frame @ rot)[None], len(t), axis=0), trans @ frame.T

    p = np.array([0.0, 1.0, 0.0])  # t0's part normal to v
    return pose, edge, faces, np.array([1.0, 0.0, 0.0]), n, p


@pytest.mark.parametrize("radius", [0.0, 0.010])
def test_planing_a_slab_gives_the_worked_forces_and_the_chip_energy(radius) -> None:
    rng = np.random.default_rng(3)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    q *= np.sign(np.linalg.det(q))  # any turned frame: the model sees only the geometry
    model = oblique_forces("16MnCr5", radius)
    speed, duration = 2000.0, 2e-3  # 2 m/s over 4 mm of cut
    pose, edge, faces, v, n, p = planer(GAMMA, LAMBDA, speed, q)
    volume = H * B * speed * duration
    load = engagement_load(pose, edge, 0.0, duration, volume, model, lambda w: np.ones(w.shape[:-1], bool),
                           thickness=H, faces=faces)  # fmt: skip
    cutting, thrust, passive = SHARP if radius == 0 else HONED
    assert load.components == pytest.approx(np.tile([cutting, thrust, passive], (len(load.t), 1)), rel=0.01)
    # on the workpiece: dragged along v, pushed away from the tool (-n), along the edge's part normal to v
    expected = (cutting * v - thrust * n + passive * p) @ q.T
    assert load.force == pytest.approx(np.tile(expected, (len(load.t), 1)), rel=0.01)
    # the work of the three along the relative motion is the chip's energy
    work = float(np.sum(load.force @ (q @ v)) * speed * duration / len(load.t)) * 1e-3  # constant force [J]
    energy = model.chip_energy(H, B, GAMMA, LAMBDA, speed * duration)
    assert work == pytest.approx(energy, rel=0.02)
    assert load.energy == pytest.approx(energy, rel=0.02)


def test_compiled_factors_are_the_models() -> None:
    model = oblique_forces("16MnCr5")
    for gamma, lam in ((0.3, 0.1), (-0.4, -0.5), (-1.0, 0.2)):
        pose, edge, faces, *_ = planer(gamma, lam, 1000.0, np.eye(3))
        rot, trans = pose(np.array([0.0, -1e-6, 1e-6]))
        placed = np.matmul(rot, edge.T).transpose(0, 2, 1) + trans[:, None, :]
        ins = np.ones((1, len(edge)))
        out = oblique_sums(placed, ins, rot[:1], np.array([0.0]), 1e-6, faces.rake, faces.body,
                           model.model.friction_angle, model.model.rake_floor)  # fmt: skip
        factors = out[4][0, 0]
        assert factors == pytest.approx(np.array(model.factors(gamma, lam)), rel=1e-9)


def test_the_cutting_model_table_checks_values_and_sources(tmp_path) -> None:
    m = load_cutting_model()
    assert m.friction_angle == pytest.approx(math.radians(30.0)) and m.min_chip_ratio == 0.3
    bad = tmp_path / "m.toml"
    bad.write_text("[cutting_model]\nfriction_angle_deg = 95.0\n")
    with pytest.raises(InputError) as err:
        load_cutting_model(bad)
    assert "cutting_model.friction_angle_deg" in err.value.keys
    assert "cutting_model.sources.min_chip_ratio" in err.value.keys
