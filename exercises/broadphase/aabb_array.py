# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/broadphase/aabb_array.py on the instructor's
# side.
"""The input of every broad phase: an ``(N, 4)`` array of axis-aligned boxes.

Row ``i`` is body ``i``'s world AABB ``[min_x, min_y, max_x, max_y]`` in metres.
Boxes are closed: a box whose ``max_x`` equals another's ``min_x`` touches it, and
touching boxes count as overlapping (the project's convention, see :mod:`exercises`).
Zero-size boxes (points and segments) are allowed.
"""
from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from ..shapes import Shape, bounding_aabb

#: Column indices of an AABB array, named so that code reads ``aabbs[:, MAX_X]``.
MIN_X, MIN_Y, MAX_X, MAX_Y = 0, 1, 2, 3


def aabb_array(shapes: Iterable[Shape]) -> np.ndarray:
    """Stack the world AABBs of ``shapes`` into an ``(N, 4)`` float array.

    Parameters
    ----------
    shapes : iterable of Circle, AABB, OBB or ConvexPolygon
        Shapes in world coordinates (m), for example ``[b.world_shape() for b in bodies]``.

    Returns
    -------
    numpy.ndarray
        ``(N, 4)`` float64, row ``i`` = ``[min_x, min_y, max_x, max_y]`` (m) of the
        smallest box enclosing ``shapes[i]``.  An empty input gives shape ``(0, 4)``.

    Examples
    --------
    >>> import importlib
    >>> shapes = importlib.import_module(bounding_aabb.__module__)   # the package's shapes module
    >>> aabb_array([shapes.Circle((1.0, 2.0), 0.5), shapes.AABB((0.0, 0.0), (3.0, 1.0))])
    array([[0.5, 1.5, 1.5, 2.5],
           [0. , 0. , 3. , 1. ]])
    """
    rows = []
    for shape in shapes:
        box = bounding_aabb(shape)
        rows.append([box.min_corner[0], box.min_corner[1], box.max_corner[0], box.max_corner[1]])
    return np.array(rows, dtype=float).reshape(len(rows), 4)


def validate_aabbs(aabbs) -> np.ndarray:
    """Check an AABB array and return it as a C-contiguous ``(N, 4)`` float64 array.

    Parameters
    ----------
    aabbs : array_like
        ``(N, 4)`` boxes ``[min_x, min_y, max_x, max_y]`` (m).  An empty sequence
        is accepted as ``N = 0``.

    Returns
    -------
    numpy.ndarray
        The same boxes, ``(N, 4)`` float64 (a copy only when a conversion was needed).

    Raises
    ------
    ValueError
        If the array is not ``(N, 4)``, holds NaN or infinite values, or a row has
        ``min > max`` on some axis; the message names the first offending row.

    Examples
    --------
    >>> validate_aabbs([[0, 0, 1, 1]])
    array([[0., 0., 1., 1.]])
    >>> validate_aabbs([[2, 0, 1, 1]])
    Traceback (most recent call last):
    ...
    ValueError: aabbs row 0 has min_x > max_x: [2.0, 0.0, 1.0, 1.0]
    """
    try:
        boxes = np.ascontiguousarray(aabbs, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise ValueError(f"aabbs must be an (N, 4) array of numbers: {error}") from None
    if boxes.size == 0 and boxes.ndim == 1:
        return boxes.reshape(0, 4)
    if boxes.ndim != 2 or boxes.shape[1] != 4:
        raise ValueError(f"aabbs must have shape (N, 4) [min_x, min_y, max_x, max_y], got {boxes.shape}")
    finite = np.isfinite(boxes).all(axis=1)
    if not finite.all():
        row = int(np.argmin(finite))
        raise ValueError(f"aabbs row {row} is not finite (NaN or inf): {boxes[row].tolist()}")
    for axis, name in ((0, "x"), (1, "y")):
        inverted = boxes[:, MIN_X + axis] > boxes[:, MAX_X + axis]
        if inverted.any():
            row = int(np.argmax(inverted))
            raise ValueError(f"aabbs row {row} has min_{name} > max_{name}: {boxes[row].tolist()}")
    return boxes
