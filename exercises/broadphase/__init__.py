# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/broadphase/__init__.py on the instructor's
# side.
"""Broad phase: from N bodies to the few candidate pairs worth a narrow-phase test.

Every broad phase here takes an ``(N, 4)`` float array of world AABBs
``[min_x, min_y, max_x, max_y]`` (m), built with :func:`aabb_array`, and returns the
pairs ``(i, j)``, ``i < j``, whose boxes overlap or touch: a set of tuples, or for the
vectorised :func:`pairs_grid_numpy` a sorted ``(M, 2)`` int64 array.  All of them
return exactly the pairs of :func:`pairs_brute_force`, the oracle.

- :mod:`.brute_force`: all C(N, 2) pairs; a readable loop and a chunked numpy version.
- :mod:`.uniform_grid`: square cells, ``"every_cell"`` or ``"center_cell"`` insertion.
- :mod:`.quadtree`: adaptive cells by full containment, with the three stopping rules.
- :mod:`.sorted_grid_numpy`: a grid of strips swept along x, vectorised for 10^4 to 10^5 bodies.
"""
from .aabb_array import aabb_array, validate_aabbs
from .brute_force import aabbs_overlap, pairs_brute_force, pairs_brute_force_numpy
from .quadtree import Quadtree, QuadtreeNode, pairs_quadtree
from .sorted_grid_numpy import pairs_as_set, pairs_grid_numpy
from .uniform_grid import pairs_uniform_grid, suggest_cell_size

__all__ = [
    "aabb_array", "validate_aabbs", "aabbs_overlap", "pairs_brute_force", "pairs_brute_force_numpy",
    "pairs_uniform_grid", "suggest_cell_size", "Quadtree", "QuadtreeNode", "pairs_quadtree",
    "pairs_grid_numpy", "pairs_as_set",
]
