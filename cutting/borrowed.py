"""Arrays handed down a compiled kernel without their reference counts.

numba counts references to every array it passes around: a helper that takes an array (or a tuple of them)
increments and decrements the array's count on entry and exit, with an atomic instruction. In the dexel and
exact-surface kernels, whose helpers run tens of millions of times per cut, those atomics were over half of the
kernel's time (measured with perf: NRT_incref/NRT_decref 57 % of the samples on one thread, the same on two).
A kernel's entry point (which the caller's Python keeps its arrays alive through) takes :func:`borrowed` views
of its arrays: the same data, shape and strides with no reference count (numba's own null-meminfo case, as for
arrays made from a raw pointer), so the counting below the entry point does nothing.
"""

from __future__ import annotations

from numba import types
from numba.core import cgutils
from numba.extending import intrinsic


def _drop_counts(context, builder, ty, value):
    if isinstance(ty, types.Array):
        ary = context.make_array(ty)(context, builder, value=value)
        ary.meminfo = cgutils.get_null_value(ary.meminfo.type)
        return ary._getvalue()
    if isinstance(ty, types.BaseTuple):
        for k, item in enumerate(ty.types):
            part = builder.extract_value(value, k)
            value = builder.insert_value(value, _drop_counts(context, builder, item, part), k)
    return value


@intrinsic
def borrowed(typingctx, value):
    """``value`` (an array, or a tuple holding arrays, nested) with every array's reference count dropped: valid
    while the caller holds the originals (a kernel's arguments, for the kernel's whole run)."""

    def codegen(context, builder, signature, args):
        return _drop_counts(context, builder, signature.args[0], args[0])

    return value(value), codegen
