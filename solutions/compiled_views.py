"""A C-contiguous 1-D array seen as an array of another shape, in compiled code, for nothing.

numba's ``array.reshape`` calls a C helper that works out the strides of any layout
(``numba_attempt_nocopy_reshape``): 26 ns a call, and the compiled soft step cuts its
blocks of work space into rows some 40 times a step (on a world of three boxes, a tenth
of the step).  :func:`contiguous_view` makes the same view (the same data, shape and
C-order strides, the same owner) from its shape alone, in 3 ns.  It does not check
that the shape's size equals the array's: every caller cuts a block of that size first
(:func:`~solutions.response.soft_step_layout.take`).

>>> import numpy as np
>>> from numba import njit
>>> @njit
... def rows(block):
...     return contiguous_view(block[2:8], (2, 3)).copy()
>>> rows(np.arange(10.0)).tolist()
[[2.0, 3.0, 4.0], [5.0, 6.0, 7.0]]
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (it serves the compiled twins).

from numba import types
from numba.core import cgutils
from numba.core.imputils import impl_ret_borrowed
from numba.extending import intrinsic
from numba.np.arrayobj import make_array, populate_array


@intrinsic
def contiguous_view(typingctx, array, shape):
    """``array.reshape(shape)`` for a one-dimensional C-contiguous ``array`` whose size
    is the product of ``shape`` (a tuple of integers); compiled code only."""
    if not (isinstance(array, types.Array) and array.ndim == 1 and array.layout == "C"
            and isinstance(shape, types.BaseTuple) and all(isinstance(size, types.Integer) for size in shape)):
        return None
    view_type = array.copy(ndim=len(shape), layout="C")

    def codegen(context, builder, signature, args):
        array_type, shape_type = signature.args
        source = make_array(array_type)(context, builder, args[0])
        sizes = [context.cast(builder, size, size_type, types.intp)
                 for size, size_type in zip(cgutils.unpack_tuple(builder, args[1]), shape_type)]
        strides, stride = [], source.itemsize           # C order: the last index is contiguous
        for size in reversed(sizes):
            strides.insert(0, stride)
            stride = builder.mul(stride, size)
        view = make_array(signature.return_type)(context, builder)
        populate_array(view, data=source.data, shape=sizes, strides=strides, itemsize=source.itemsize,
                       meminfo=source.meminfo, parent=source.parent)
        return impl_ret_borrowed(context, builder, signature.return_type, view._getvalue())

    return view_type(array, shape), codegen
