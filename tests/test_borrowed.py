"""cutting.borrowed: a kernel's arrays without reference counts are the same arrays (reads, writes, tuples)."""

import sys

import numpy as np
from numba import njit

from cutting.borrowed import borrowed


@njit(cache=True)
def _scale_and_sum(a, pair, k):
    a, pair = borrowed((a, pair))
    b, (c, n) = pair
    total = 0.0
    for i in range(a.shape[0]):
        a[i] *= k  # a write through the borrowed view lands in the caller's array
        total += a[i] + b[i, 0] + c[i]
    return total * n, a


def test_borrowed_views_read_and_write_the_callers_arrays():
    a = np.arange(5.0)
    b = np.ones((5, 2))
    c = np.full(5, 2.0)
    counts = [sys.getrefcount(x) for x in (a, b, c)]
    total, back = _scale_and_sum(a, (b, (c, 2)), 3.0)
    assert np.array_equal(a, 3.0 * np.arange(5.0))
    assert total == 2 * (3.0 * 10 + 5 + 10)
    assert np.array_equal(back, a)  # the data, not a copy
    del back
    # the arrays' reference counts are as before the call: nothing leaked, nothing freed early
    assert [sys.getrefcount(x) for x in (a, b, c)] == counts
