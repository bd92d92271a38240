"""A numba compiler that tells LLVM a function's array arguments do not overlap.

numba passes each array to a compiled function as a struct whose data pointer LLVM must
assume may point into any other argument's memory.  A loop that writes one array and
reads another (the soft step's warm start writes the velocities and reads the contact
rows) then reloads every value after every store, and cannot keep them in registers.
Arrays a function allocates itself do not have that problem, which is why moving the
soft step's work arrays into arguments (:mod:`~solutions.response.soft_step_numba`) made
its sub-steps about 25 % slower until its body was compiled with this class.

:class:`NoAliasCompiler` is numba's own compiler with its ``noalias`` flag set: every
pointer argument gets LLVM's ``noalias`` attribute.  Use it only for a function whose
array arguments are distinct arrays or disjoint parts of one (two views of the same
memory passed as two arguments would make its results undefined); views the function
makes of one argument may overlap each other.  Given as ``@njit(pipeline_class=NoAliasCompiler)``.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (it serves the compiled twins).

from numba.core.compiler import Compiler


class NoAliasCompiler(Compiler):
    """numba's compiler with the ``noalias`` flag: the function's pointer arguments do not alias."""

    def __init__(self, typingctx, targetctx, library, args, return_type, flags, locals):
        flags = flags.copy()
        flags.noalias = True
        super().__init__(typingctx, targetctx, library, args, return_type, flags, locals)
