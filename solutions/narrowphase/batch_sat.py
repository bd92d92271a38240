"""Vectorised OBB-OBB overlap test for many pairs at once (numpy).

The readable reference is :func:`solutions.narrowphase.polygon_polygon.obbs_overlap`,
which projects the corners on each of the four axes.  Here the same four axes are
tested with the centre / half-extents form, which needs no corners: on a unit axis
``L`` a box of centre ``c``, unit axes ``u, v`` and half-extents ``(h_u, h_v)`` projects
to ``Dot(c, L) +- r`` with ``r = h_u |Dot(u, L)| + h_v |Dot(v, L)|`` (here ``abs`` is
right: it measures a half-width, it never folds a position).  With ``d = c_B - c_A`` the
boxes are apart on ``L`` when ``|Dot(d, L)| > r_A + r_B``.  On A's x axis,
``Dot(u_B, u_A) = cos(theta_B - theta_A)`` and ``Dot(v_B, u_A) = -sin(...)``, so all four
tests need only the cosine and sine of the two angles and of their difference.

Touching counts as overlapping, as in the rest of the narrow phase.  Pairs within
roundoff of touching may be classified differently from the readable version.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (the sat exercise's test for boxes, in numpy form).

import numpy as np


def checked_array(name: str, value, shape: tuple, count: int | None) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    if array.ndim != len(shape) or array.shape[1:] != shape[1:] or (count is not None and len(array) != count):
        wanted = ("n",) + shape[1:]
        raise ValueError(f"{name} must have shape {wanted} with the same n for every array, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} must be finite (no NaN or inf)")
    return array


def obbs_overlap_batch(centers_a, half_a, angles_a, centers_b, half_b, angles_b) -> np.ndarray:
    """Whether box ``A[i]`` overlaps or touches box ``B[i]``, for every ``i``.

    Parameters
    ----------
    centers_a, centers_b : array_like, shape (n, 2)
        Box centres (m).
    half_a, half_b : array_like, shape (n, 2)
        Half-extents (m) along each box's own x and y axes, >= 0.
    angles_a, angles_b : array_like, shape (n,)
        Box angles (rad, counter-clockwise).

    Returns
    -------
    numpy.ndarray of bool, shape (n,)

    Raises
    ------
    ValueError
        For mismatched shapes, NaN or infinite values, or a negative half-extent.

    Examples
    --------
    >>> obbs_overlap_batch([[0.0, 0.0], [-5.0, 0.0]], [[1.0, 1.0], [1.0, 1.0]], [0.0, 0.0],
    ...                    [[2.3, 0.0], [-2.0, 0.0]], [[1.0, 1.0], [1.0, 1.0]], [0.785398, 0.0]).tolist()
    [True, False]
    """
    centers_a = checked_array("centers_a", centers_a, (0, 2), None)
    n = len(centers_a)
    half_a = checked_array("half_a", half_a, (0, 2), n)
    angles_a = checked_array("angles_a", angles_a, (0,), n)
    centers_b = checked_array("centers_b", centers_b, (0, 2), n)
    half_b = checked_array("half_b", half_b, (0, 2), n)
    angles_b = checked_array("angles_b", angles_b, (0,), n)
    if np.any(half_a < 0) or np.any(half_b < 0):
        raise ValueError("half-extents must be >= 0")

    cos_a, sin_a = np.cos(angles_a), np.sin(angles_a)
    cos_b, sin_b = np.cos(angles_b), np.sin(angles_b)
    # |cos| and |sin| of the relative angle theta_B - theta_A, shared by all four axes.
    abs_cos = np.abs(cos_a * cos_b + sin_a * sin_b)
    abs_sin = np.abs(cos_a * sin_b - sin_a * cos_b)
    dx = centers_b[:, 0] - centers_a[:, 0]
    dy = centers_b[:, 1] - centers_a[:, 1]
    hax, hay = half_a[:, 0], half_a[:, 1]
    hbx, hby = half_b[:, 0], half_b[:, 1]

    # A's x axis (cos_a, sin_a) and y axis (-sin_a, cos_a).
    apart = np.abs(dx * cos_a + dy * sin_a) > hax + hbx * abs_cos + hby * abs_sin
    apart |= np.abs(dy * cos_a - dx * sin_a) > hay + hbx * abs_sin + hby * abs_cos
    # B's x and y axes.
    apart |= np.abs(dx * cos_b + dy * sin_b) > hbx + hax * abs_cos + hay * abs_sin
    apart |= np.abs(dy * cos_b - dx * sin_b) > hby + hax * abs_sin + hay * abs_cos
    return ~apart
