"""A pyramid of boxes with hand-made contact manifolds: the solver's workload without a
narrow phase (for timing the solver kernel and testing it on many coupled contacts).
SI units; normals point up, from the lower body to the upper one."""
from __future__ import annotations

from ..body import Body
from ..contact import Contact


def pyramid_contacts(base: int = 20, size: float = 1.0, gap: float = 0.125,
                     depth: float = 0.001) -> tuple[list[Body], list[tuple[int, int, Contact]]]:
    """Bodies and hand-made 2-point manifolds of a pyramid of boxes on static ground.

    Row ``r`` (0 at the bottom) holds ``base - r`` boxes of side ``size`` (m), ``gap``
    (m) apart, each resting on the two boxes below it, every contact ``depth`` (m)
    deep.  ``base = 20`` gives 210 boxes and 800 contact points.  Used to time the
    solver without a narrow phase.

    >>> bodies, manifolds = pyramid_contacts(base=3)
    >>> len(bodies), len(manifolds), sum(len(c.points) for _, _, c in manifolds)
    (7, 9, 18)
    """
    bodies = [Body.box(2.0 * base * (size + gap), size, position=(0.0, -size / 2), is_static=True)]
    manifolds = []
    below: list[int] = []
    pitch = size + gap
    for row in range(base):
        this_row = []
        for column in range(base - row):
            x = (column - (base - row - 1) / 2) * pitch
            y = size / 2 + row * (size - depth)
            bodies.append(Body.box(size, size, position=(x, y), friction=0.6))
            index = len(bodies) - 1
            this_row.append(index)
            bottom = y - size / 2 + depth / 2
            supports = [0] if row == 0 else below[column:column + 2]
            for support in supports:
                left = max(x, float(bodies[support].position[0]) if support else x) - size / 2
                right = min(x, float(bodies[support].position[0]) if support else x) + size / 2
                manifolds.append((support, index, Contact((0.0, 1.0), depth, [(left, bottom), (right, bottom)],
                                                          feature_ids=("left", "right"))))
        below = this_row
    return bodies, manifolds
