"""Kienzle forces from a chip: the material table, the law's worked numbers, and engagements with known answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from cutting.errors import InputError
from cutting.forces import engagement_load
from cutting.materials import H_MIN, Material, load_materials, material, rake_factor


def test_every_material_has_its_values_and_a_source() -> None:
    table = load_materials()
    assert {"16MnCr5", "20MnCr5", "42CrMo4", "C45E"} <= set(table)
    for row in table.values():
        assert row.kc11 > 1000 and 0 < row.mc < 0.5 and "Koenig" in row.source


def test_kienzle_worked_example() -> None:
    # 16MnCr5, b = 2 mm, h = 0.1 mm: Fc = 2100 * 2 * 0.1^0.74 = 764.3 N
    m = material("16MnCr5")
    assert m.kc11 == 2100.0 and m.mc == 0.26
    assert m.kc(0.1) * 2 * 0.1 == pytest.approx(2100 * 2 * 10**-0.74, rel=1e-12)
    assert m.kc(0.1) * 2 * 0.1 == pytest.approx(764.3, abs=0.1)
    assert m.kc(1e-5) == m.kc(H_MIN)  # the power law is not extrapolated below the thinnest chip
    assert rake_factor(6.0) == 1.0 and rake_factor(0.0) == pytest.approx(1.09)


def test_unknown_material_lists_the_known_ones() -> None:
    with pytest.raises(InputError) as err:
        material("Unobtainium")
    assert err.value.keys == ["process.material"] and "16MnCr5" in str(err.value)


def test_bad_table_rows_are_named(tmp_path) -> None:
    p = tmp_path / "m.toml"
    p.write_text("[materials.X]\nkc11 = -5.0\nmc = 1.2\n")
    with pytest.raises(InputError) as err:
        load_materials(p)
    assert set(err.value.keys) == {"materials.X.kc11", "materials.X.mc", "materials.X.source"}


STEEL = Material("test", "test steel", 2000.0, 0.25, "test")
EDGE = np.array([[0.0, 0.0, 0.0], [0.5, 0.0, 0.0], [1.0, 0.0, 0.0]])  # 1 mm of edge along x


def translating(v: float):
    """The edge moving along +y at v [mm/s], without rotation."""

    def pose(t: np.ndarray):
        t = np.atleast_1d(t)
        trans = np.zeros((len(t), 3))
        trans[:, 1] = v * t
        return np.repeat(np.eye(3)[None], len(t), axis=0), trans

    return pose


def test_straight_cut_recovers_thickness_force_and_energy() -> None:
    # 1 mm of edge at 1 m/s for 2 ms sweeps 2 mm^2; a chip of 0.1 mm^3 is 0.05 mm thick
    load = engagement_load(translating(1000.0), EDGE, 0.0, 2e-3, 0.1, STEEL, lambda w: np.ones(w.shape[:-1], bool))
    assert load.thickness == pytest.approx(0.05, rel=1e-9)
    fc = 2000.0 * 0.05**-0.25 * 1.0 * 0.05 * rake_factor(0.0)  # kc(h) * b * h
    np.testing.assert_allclose(load.force, np.tile([0.0, fc, 0.0], (len(load.t), 1)), rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(load.point[:, 0], 0.5, atol=1e-12)  # the middle of the edge
    # the work of the force along the edge's path is the chip's specific energy times its volume
    assert load.energy == pytest.approx(load.kc * 0.1e-3)
    assert fc * 1000.0 * 2e-3 * 1e-3 == pytest.approx(load.energy, rel=1e-9)


def test_partly_engaged_edge_thickens_the_same_chip() -> None:
    # points at x = 0 and 0.5 inside, x = 1 outside: the element crossing the boundary counts half -> b = 0.75 mm
    part = engagement_load(translating(1000.0), EDGE, 0.0, 2e-3, 0.1, STEEL, lambda w: w[..., 0] <= 0.5)
    assert part.thickness == pytest.approx(0.1 / (0.75 * 2.0), rel=1e-9)
    h = part.thickness
    assert part.force[:, 1] == pytest.approx(2000.0 * h**-0.25 * 0.75 * h * rake_factor(0.0))
    assert part.point[0, 0] == pytest.approx((0.25 * 0.5 + 0.75 * 0.25) / 0.75)


def test_rotating_edge_force_follows_each_elements_velocity() -> None:
    # an edge on a radius turning about z: every element moves tangentially, so the resultant is tangential
    omega = 100.0

    def pose(t: np.ndarray):
        t = np.atleast_1d(t)
        c, s = np.cos(omega * t), np.sin(omega * t)
        rot = np.zeros((len(t), 3, 3))
        rot[:, 0, 0], rot[:, 0, 1], rot[:, 1, 0], rot[:, 1, 1], rot[:, 2, 2] = c, -s, s, c, 1.0
        return rot, np.zeros((len(t), 3))

    edge = np.array([[10.0, 0.0, -0.5], [10.0, 0.0, 0.0], [10.0, 0.0, 0.5]])  # 1 mm along z at r = 10
    t1 = 1e-3
    load = engagement_load(pose, edge, 0.0, t1, 0.02, STEEL, lambda w: np.ones(w.shape[:-1], bool))
    # swept area = 1 mm * 10 mm * omega * t1 = 1 mm^2 -> h = 0.02 mm
    assert load.thickness == pytest.approx(0.02, rel=1e-6)
    angle = omega * load.t
    tangent = np.column_stack([-np.sin(angle), np.cos(angle), np.zeros_like(angle)])
    np.testing.assert_allclose(load.force / np.linalg.norm(load.force, axis=1)[:, None], tangent, atol=1e-6)
    assert math.isclose(load.peak(), STEEL.kc(0.02) * rake_factor(0.0) * 1.0 * 0.02, rel_tol=1e-6)


def test_no_chip_no_load() -> None:
    load = engagement_load(translating(1000.0), EDGE, 0.0, 2e-3, 0.0, STEEL, lambda w: np.ones(w.shape[:-1], bool))
    assert load.peak() == 0.0 and not len(load.t)


def test_wrench_does_the_work_of_the_forces_along_the_edge() -> None:
    """Force at the centroid plus moment about it: on a rigid body the same power as the distributed forces, for
    an edge that turns about a tilted axis while it translates (v = u + w x (p - u t))."""
    from cutting.forces import engaged_speed

    u, w = np.array([300.0, -50.0, 20.0]), np.array([10.0, 40.0, 120.0])  # mm/s, rad/s

    def pose(t: np.ndarray):
        t = np.atleast_1d(t)
        rot = np.zeros((len(t), 3, 3))
        for k, tk in enumerate(t):
            v = w * tk
            a = np.linalg.norm(v)
            kx = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]]) / a
            rot[k] = np.eye(3) + np.sin(a) * kx + (1 - np.cos(a)) * kx @ kx
        return rot, u * t[:, None]

    edge = np.array([[8.0, 1.0, 0.0], [9.0, 0.5, 0.3], [10.0, 0.0, 0.2], [11.0, -0.8, -0.1], [12.0, -1.0, 0.0]])
    inside = lambda p: np.ones(p.shape[:-1], bool)  # noqa: E731
    load = engagement_load(pose, edge, 1e-4, 2e-3, 0.05, STEEL, inside, samples=9)
    length, _, vel = engaged_speed(pose, edge, load.t, inside)
    distributed = load.kc * load.thickness * (length * np.linalg.norm(vel, axis=2)).sum(axis=1)  # N mm/s
    v_centroid = u + np.cross(w, load.point - u * load.t[:, None])
    wrench = (load.force * v_centroid).sum(axis=1) + (load.moment * 1e3 * w).sum(axis=1)
    np.testing.assert_allclose(wrench, distributed, rtol=1e-5)
    assert np.abs(load.moment).max() > 0  # the moment matters here
