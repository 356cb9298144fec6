"""Compiled kernels on every core: a nogil numba function over chunks of its index range, in a thread pool.

The kernels (the exact measurement's, the dexel workpiece's) are loops over independent items (probe lines,
dexel cells, poses). Written as ``kernel(lo, hi, *args)`` with ``nogil=True`` they run on every core from plain
threads (:func:`run_chunks`). numba's own ``parallel=True`` would do the same, but its parfor compilation costs
several times the kernel's own (and compiles each callee twice), which a user pays on the first run after an install.

A kernel called many times on little work (the co-simulation cuts one tooth passage, ~100 dexel cells, per call)
takes its items one by one from a shared counter instead (:func:`run_shared`, :func:`claim`): each thread enters the
kernel once, and the items balance without a chunk's worth of imbalance or a call per chunk.
"""

from __future__ import annotations

import itertools
import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from numba import types
from numba.extending import intrinsic

_pool: ThreadPoolExecutor | None = None


def default_workers() -> int:
    """Worker processes for work split over processes (the manifold removal, a study's local cluster): one per core,
    at most 8."""
    return max(1, min(os.cpu_count() or 1, 8))


def threads() -> int:
    """Threads the kernels use: the cores this process may run on (NUMBA_NUM_THREADS caps it), at most 8."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        cores = os.cpu_count() or 1
    cap = int(os.environ.get("NUMBA_NUM_THREADS", "0") or 0)
    return max(1, min(cores, 8, cap or cores))


def run_chunks(kernel, n: int, *args, smallest: int = 1) -> None:
    """``kernel(lo, hi, *args)`` over [0, n) in chunks of at least ``smallest`` items, taken by the threads as they
    become free (many chunks per thread, so that uneven items balance; this thread works too); inline when there is
    one thread or too little work to share."""
    if n <= 0:
        return
    k = threads()
    chunks = min(16 * k, n // max(smallest, 1))
    if k == 1 or chunks < 2:
        kernel(0, n, *args)
        return
    edges = np.linspace(0, n, chunks + 1).astype(np.int64).tolist()
    taken = itertools.count()  # next() on it is atomic under the GIL: each chunk goes to one thread

    def work() -> None:
        while (c := next(taken)) < chunks:
            if edges[c + 1] > edges[c]:
                kernel(edges[c], edges[c + 1], *args)

    _on_threads(k, work)


def _on_threads(k: int, work) -> None:
    """``work()`` on this thread and on k - 1 threads of the pool at once; a thread's error is raised here."""
    global _pool
    if _pool is None:
        _pool = ThreadPoolExecutor(max_workers=threads() - 1, thread_name_prefix="skive-kernel")
    futures = [_pool.submit(work) for _ in range(k - 1)]
    work()
    for f in futures:
        f.result()


@intrinsic
def claim(typingctx, counter):
    """The next item of a shared counter (``counter[0]``, an int64 array): its value, incremented atomically, so
    that every item goes to exactly one thread of :func:`run_shared`."""
    if not (isinstance(counter, types.Array) and counter.dtype == types.int64):
        return None

    def codegen(context, builder, signature, args):
        ary = context.make_array(signature.args[0])(context, builder, value=args[0])
        one = context.get_constant(types.int64, 1)
        return builder.atomic_rmw("add", ary.data, one, "monotonic")

    return types.int64(counter), codegen


def run_shared(kernel, n: int, *args) -> None:
    """``kernel(counter, n, *args)`` once on every thread (this one too), the threads taking the items [0, n) one
    by one with :func:`claim` on ``counter`` (inline when there is one thread or one item)."""
    if n <= 0:
        return
    counter = np.zeros(1, np.int64)
    k = min(threads(), n)
    if k == 1:
        kernel(counter, n, *args)
        return
    _on_threads(k, lambda: kernel(counter, n, *args))
