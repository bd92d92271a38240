# Exercise file of the collision course: write the functions that raise NotImplementedError, then
# check them with `grader check grid`.
# Handed out with the course; generated from solutions/broadphase/uniform_grid.py on the
# instructor's side.
"""Uniform grid broad phase, in the two variants of the course notes.

The plane is cut into square cells of side ``cell_size`` (m).  Cell ``(cx, cy)`` is
the set of points with ``floor(x / cell_size) == cx`` and ``floor(y / cell_size) == cy``;
``floor`` (not ``int``) keeps negative coordinates right: x = -0.5 is in cell -1.
Only bodies that share a cell (or neighbouring cells) are tested against each other,
so with a good cell size the cost is close to O(N) instead of O(N^2).

A body whose AABB spans several cells is handled in one of two ways:

``"every_cell"``
    Insert the body into every cell its AABB overlaps.  Boxes are closed, so a body
    whose ``max_x`` lies exactly on a cell boundary is in the cells on both sides of
    it: two boxes that touch along that boundary share a cell.  A pair that shares
    several cells is met several times; the result is a set, so it is kept once.
``"center_cell"``
    Insert the body only into the cell of its AABB centre.  A partner's centre can
    then lie in another cell, so each body searches its cells plus ``reach`` cells
    around them, where ``reach`` is the largest number of cell boundaries any body
    crosses (1 when no body is larger than a cell: the classic 3 x 3 neighbourhood).
    Bodies larger than a cell are still found; they just widen every search.

Either way a body that crosses a cell edge must meet bodies in the neighbouring
cells too: "bodies only collide inside one group" is wrong for a grid (erratum 5).

Both variants return exactly the pairs of :func:`~exercises.broadphase.brute_force.pairs_brute_force`:
candidates found through the grid are filtered with the exact AABB test.
"""
from __future__ import annotations

import math
from collections import defaultdict

import numpy as np

from .aabb_array import MAX_X, MAX_Y, MIN_X, MIN_Y, validate_aabbs
from .brute_force import aabbs_overlap

GRID_METHODS = ("every_cell", "center_cell")


def check_cell_size(cell_size) -> float:
    """``cell_size`` as a float; ValueError unless it is finite and > 0.

    Examples
    --------
    >>> check_cell_size(2)
    2.0
    """
    size = float(cell_size)
    if not math.isfinite(size) or size <= 0:
        raise ValueError(f"cell_size must be a finite length > 0 (m), got {cell_size!r}")
    return size


def cell_index(x: float, y: float, cell_size: float) -> tuple[int, int]:
    """Integer index ``(cx, cy)`` of the cell holding point ``(x, y)`` (m).

    Examples
    --------
    >>> cell_index(2.5, -0.5, 1.0)
    (2, -1)
    """
    return math.floor(x / cell_size), math.floor(y / cell_size)


def covered_cells(box, cell_size: float) -> tuple[tuple[int, int], tuple[int, int]]:
    """Lowest and highest cell index ``(lo, hi)`` overlapped by a closed ``box``.

    The box overlaps every cell ``(cx, cy)`` with ``lo[0] <= cx <= hi[0]`` and
    ``lo[1] <= cy <= hi[1]``.  ``floor`` never decreases when its argument grows,
    so two boxes that share a point share the cell of that point.

    Examples
    --------
    >>> covered_cells([0.5, 0.5, 2.0, 0.7], 1.0)   # max_x = 2.0 lies on a boundary
    ((0, 0), (2, 0))
    """
    return cell_index(box[0], box[1], cell_size), cell_index(box[2], box[3], cell_size)


def suggest_cell_size(aabbs) -> float:
    """A reasonable cell size (m): twice the median body extent.

    The extent of a body is ``max(width, height)`` of its AABB.  With cells about twice
    as large as a typical body, most bodies overlap one to four cells and each cell
    holds a handful of bodies.  Fallbacks: if most bodies are points (median extent 0),
    the scene span divided by ``sqrt(N)`` (about one body per cell); if even that is
    0 (empty scene, or every body at one point), 1 m.

    Parameters
    ----------
    aabbs : array_like, shape (N, 4)
        Boxes ``[min_x, min_y, max_x, max_y]`` (m).

    Returns
    -------
    float
        A finite cell size > 0 (m).

    Examples
    --------
    >>> suggest_cell_size([[0, 0, 1, 1], [5, 5, 6, 7], [2, 2, 3.5, 2.5]])
    3.0
    """
    boxes = validate_aabbs(aabbs)
    if len(boxes) == 0:
        return 1.0
    widths = boxes[:, MAX_X] - boxes[:, MIN_X]
    heights = boxes[:, MAX_Y] - boxes[:, MIN_Y]
    size = 2.0 * float(np.median(np.maximum(widths, heights)))
    if size > 0 and math.isfinite(size):
        return size
    span = max(
        float(boxes[:, MAX_X].max() - boxes[:, MIN_X].min()),
        float(boxes[:, MAX_Y].max() - boxes[:, MIN_Y].min()),
    )
    if span > 0 and math.isfinite(span):
        return span / math.sqrt(len(boxes))
    return 1.0


def pairs_uniform_grid(aabbs, cell_size: float, method: str = "every_cell") -> set[tuple[int, int]]:
    """Overlapping-or-touching pairs ``(i, j)``, ``i < j``, found with a uniform grid.

    Parameters
    ----------
    aabbs : array_like, shape (N, 4)
        Boxes ``[min_x, min_y, max_x, max_y]`` (m).
    cell_size : float
        Side of a square cell (m), finite and > 0; see :func:`suggest_cell_size`.
    method : {"every_cell", "center_cell"}
        How a body spanning several cells is stored (see the module docstring).

    Returns
    -------
    set of tuple of int
        Exactly the pairs of the brute force.

    Raises
    ------
    ValueError
        For a bad AABB array, a cell size that is not finite and > 0, or an unknown
        method.

    Examples
    --------
    >>> boxes = [[0, 0, 1, 1], [1, 0, 2, 1], [-3, -3, -2, -2]]
    >>> sorted(pairs_uniform_grid(boxes, cell_size=1.0, method="center_cell"))
    [(0, 1)]
    """
    boxes = validate_aabbs(aabbs)
    cell_size = check_cell_size(cell_size)
    if method == "every_cell":
        return pairs_grid_every_cell(boxes, cell_size)
    if method == "center_cell":
        return pairs_grid_center_cell(boxes, cell_size)
    raise ValueError(f"method must be one of {GRID_METHODS}, got {method!r}")


def pairs_grid_every_cell(aabbs, cell_size: float) -> set[tuple[int, int]]:
    """Grid broad phase storing each body in every cell its AABB overlaps.

    Parameters
    ----------
    aabbs : array_like, shape (N, 4)
        Boxes ``[min_x, min_y, max_x, max_y]`` (m), each with min <= max.  Not
        checked here: :func:`pairs_uniform_grid` validates its input.
    cell_size : float
        Side of a square cell (m), finite and > 0.

    Returns
    -------
    set of tuple of int
        Pairs ``(i, j)``, ``i < j``, whose AABBs overlap or touch.

    Examples
    --------
    >>> sorted(pairs_grid_every_cell([[0, 0, 1, 1], [1, 1, 2, 2], [3, 0, 4, 1]], 1.0))
    [(0, 1)]
    """
    raise NotImplementedError("write pairs_grid_every_cell(), then run `grader check grid`")


def pairs_grid_center_cell(aabbs, cell_size: float) -> set[tuple[int, int]]:
    """Grid broad phase storing each body in the cell of its AABB centre only.

    When looking for the partners of body ``i``, every cell within ``reach`` cells of
    a cell that ``i`` overlaps is searched, where ``reach`` (per axis) is the largest
    number of cell boundaries crossed by any body.  Proof sketch: if ``i`` and ``j``
    overlap they share a cell ``c``; ``j``'s centre cell is one of ``j``'s cells, all
    within ``reach`` of ``c``.  Cell spans come from the same ``floor`` as the cell
    indices, so rounding cannot lose a pair.

    Parameters
    ----------
    aabbs : array_like, shape (N, 4)
        Boxes ``[min_x, min_y, max_x, max_y]`` (m), each with min <= max.  Not
        checked here: :func:`pairs_uniform_grid` validates its input.
    cell_size : float
        Side of a square cell (m), finite and > 0.

    Returns
    -------
    set of tuple of int
        Pairs ``(i, j)``, ``i < j``, whose AABBs overlap or touch.

    Examples
    --------
    >>> sorted(pairs_grid_center_cell([[0, 0, 1, 1], [1, 1, 2, 2], [0, 0, 9, 0.5]], 1.0))
    [(0, 1), (0, 2)]
    """
    raise NotImplementedError("write pairs_grid_center_cell(), then run `grader check grid`")
