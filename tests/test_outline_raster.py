"""The outline's signed-distance raster (the dexel march's estimate) against the analytic distance to a rectangle:
exact within its band, and the wide raster's far-off lower bound within 1.42 cells of the truth, never above it."""

import numpy as np

from cutting.skiving.exact_sweep import Outline

CELL, PAD, BAND = 0.016, 2.0, 4.0
F32 = 2e-6  # float32 rounding of a few millimetres [mm]


def rectangle_distance(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Signed distance (+ inside) to the rectangle [0, 2] x [-1, 1]."""
    dx = np.maximum(np.abs(x - 1.0) - 1.0, 0.0)
    dy = np.maximum(np.abs(y) - 1.0, 0.0)
    inside = np.minimum(1.0 - np.abs(x - 1.0), 1.0 - np.abs(y))
    return np.where(inside > 0, inside, -np.hypot(dx, dy))


def _nodes(lo: np.ndarray, shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    return np.meshgrid(lo[0] + CELL * np.arange(shape[0]), lo[1] + CELL * np.arange(shape[1]), indexing="ij")


def test_the_exact_raster_is_the_distance_and_the_bounded_one_stays_below_it():
    outline = Outline(np.array([[0.0, -1.0], [2.0, -1.0], [2.0, 1.0], [0.0, 1.0]]))
    exact, lo = outline.exact_raster(CELL, 2, 4)  # a pad and band given as ints work alike
    truth = np.clip(rectangle_distance(*_nodes(lo, exact.shape)), -BAND, BAND)
    assert np.abs(exact - truth).max() < F32

    near = 0.5
    bounded, lo_b = outline.exact_raster(CELL, PAD, BAND, exact_within=near)
    assert np.array_equal(lo, lo_b) and bounded.shape == exact.shape
    assert np.array_equal(np.sign(bounded), np.sign(exact))  # every node keeps its side
    close = np.abs(truth) <= near
    assert np.abs(bounded[close] - truth[close]).max() < F32  # exact near the outline
    short = np.abs(truth) - np.abs(bounded)  # what the bound gives away farther off
    assert short.min() > -F32  # a lower bound: the march's steps stay safe
    assert short.max() <= 1.42 * CELL + F32
