"""cutting.parallel: every item of a kernel's range is done exactly once, by chunks or from the shared counter."""

import numpy as np
from numba import njit

import cutting.parallel as threads
from cutting.parallel import claim, run_chunks, run_shared


@njit(cache=True, nogil=True)
def _count_chunk(lo, hi, hits):
    for k in range(lo, hi):
        hits[k] += 1


@njit(cache=True, nogil=True)
def _count_shared(counter, n, hits, spin, spent):
    while True:
        k = claim(counter)
        if k >= n:
            break
        s = 0.0
        for j in range(spin[k]):  # uneven items, as a passage's cells are
            s += j * 1e-9
        spent[k] = s
        hits[k] += 1


def test_every_item_is_taken_once(monkeypatch):
    n = 5000
    spin = (np.arange(n) % 97 * 50).astype(np.int64)
    for k in (1, 2, 4):
        monkeypatch.setattr(threads, "threads", lambda k=k: k)
        hits, spent = np.zeros(n, np.int64), np.zeros(n)
        run_shared(_count_shared, n, hits, spin, spent)
        assert (hits == 1).all(), f"{k} threads: items taken {np.unique(hits)} times"
        assert np.allclose(spent, spin * (spin - 1) / 2 * 1e-9)  # every item's work done, by whichever thread"
        hits[:] = 0
        run_chunks(_count_chunk, n, hits)
        assert (hits == 1).all()
    run_shared(_count_shared, 0, np.zeros(0, np.int64), spin, np.zeros(0))  # nothing to do: no call, no error
