# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/solver/sweep_order.py on the instructor's
# side.
"""The order in which the solver kernel visits the constraint groups (Gauss-Seidel order).

Sequential impulses give different answers for different visiting orders: an impulse
travels along a stack as far as the order lets it in one sweep.  :func:`sweep_order`
chooses the order (and the batches of groups that share no movable body).
"""
from __future__ import annotations

import numpy as np


def sweep_order(body_a: np.ndarray, body_b: np.ndarray, movable: np.ndarray,
                order: str = "manifolds") -> tuple[np.ndarray, np.ndarray]:
    """Order in which the sweeps visit the manifolds, in batches that share no movable body.

    The manifolds of one batch share no movable body, so they can be solved at the
    same time (a parallel or vectorised solver may) with the same result as one after
    the other (:func:`exercises.solver.kernel.solve_constraints` visits them in this order).  Static bodies may appear in many manifolds of one batch:
    their velocity never changes.

    - ``"manifolds"``: Gauss-Seidel in the given order, as Box2D and box2d-lite sweep
      their contact lists.  Each manifold goes into the batch after the last one that
      holds an earlier manifold sharing one of its movable bodies, so solving batch by
      batch is solving in the given order.  A chain (a stack) is then one manifold
      per batch, and one sweep carries an impulse from one end of it to the other.
    - ``"colours"``: greedy colouring: each manifold, in the given order, takes the
      smallest colour not yet used by a movable body it touches.  Fewer, larger
      batches (what a parallel solver needs), but a chain becomes red-black
      (every other contact, then the rest) and an impulse travels only about one
      contact per colour and sweep.

    Parameters
    ----------
    body_a, body_b : numpy.ndarray of int, shape (m,)
        Local body numbers of each manifold.
    movable : numpy.ndarray of bool, shape (n,)
        Whether each body can move (finite mass or inertia).
    order : str
        ``"manifolds"`` or ``"colours"``.

    Returns
    -------
    order : numpy.ndarray of int, shape (m,)
        Manifold indices, batch by batch (stable within a batch).
    bounds : numpy.ndarray of int, shape (batches + 1,)
        Batch ``c`` is ``order[bounds[c]:bounds[c + 1]]``.

    Examples
    --------
    Manifolds 0-1, 1-2 and 0-2 between a static body 0 and movable bodies 1 and 2.
    In the given order, manifold 1 must wait for manifold 0 (body 1) and manifold 2
    for manifold 1 (body 2); by colours, manifolds 0 and 2 share only the static
    body and go together, manifold 1 comes after them.

    >>> pairs = np.array([0, 1, 0]), np.array([1, 2, 2]), np.array([False, True, True])
    >>> [(o.tolist(), b.tolist()) for o, b in (sweep_order(*pairs), sweep_order(*pairs, order="colours"))]
    [([0, 1, 2], [0, 1, 2, 3]), ([0, 2, 1], [0, 2, 3])]
    """
    if order not in ("manifolds", "colours"):
        raise ValueError(f"order must be 'manifolds' or 'colours', got {order!r}")
    movable = movable.tolist()
    batch = []
    if order == "manifolds":
        after = [0] * len(movable)  # the first batch a new manifold of each body may join
        for i, j in zip(body_a.tolist(), body_b.tolist()):
            c = max(after[i] if movable[i] else 0, after[j] if movable[j] else 0)
            batch.append(c)
            for k in (i, j):
                if movable[k]:
                    after[k] = c + 1
    else:
        used = [0] * len(movable)  # bit c set: the body already has a manifold of colour c
        for i, j in zip(body_a.tolist(), body_b.tolist()):
            taken = (used[i] if movable[i] else 0) | (used[j] if movable[j] else 0)
            c = ((~taken) & (taken + 1)).bit_length() - 1  # lowest free colour
            batch.append(c)
            for k in (i, j):
                if movable[k]:
                    used[k] |= 1 << c
    batch = np.array(batch, dtype=int)
    indices = np.argsort(batch, kind="stable")
    bounds = np.searchsorted(batch[indices], np.arange(batch.max(initial=-1) + 2))
    return indices, bounds
