"""Whether this package holds the fast twins of its readable code.

The instructor's package (``solutions``) has numpy and numba twins of the narrow phase
and of the solver (batch SAT and clipping of boxes, the compiled kernel, the soft step
compiled whole), each tested equal to the readable code.  They compute what the
exercises compute, so the student package (``exercises``, made by
``grader/release/exercises.py``) leaves them out and steps the world with the readable
code: the same motion, to rounding, only slower.

>>> isinstance(HAS_TWINS, bool)
True
"""
from __future__ import annotations

from importlib.util import find_spec

#: True in the instructor's package, False in the student package.
HAS_TWINS = find_spec(f"{__package__}.solver.kernel_numba") is not None


def require_twins(what: str) -> None:
    """Raise a ValueError naming ``what`` if this package has no twins."""
    if not HAS_TWINS:
        raise ValueError(f"{what} runs the compiled twins of the instructor's edition, which the student "
                         "edition does not include: use backend='python' (the same motion, only slower)")
