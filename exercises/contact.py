# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/contact.py on the instructor's side.
"""Contact data produced by the narrow phase.

A :class:`Contact` between shape A and shape B holds

- ``normal``: unit vector (2,) pointing from A to B;
- ``depth``: overlap along the normal, >= 0 (0 when the shapes touch);
- ``points``: (k, 2) world contact points, k = 1 or 2 (a face-face contact gives a
  2-point manifold); each point is the midpoint between the two surfaces there;
- ``depths``: (k,) overlap at each point, each >= 0 and at most ``depth`` (they can
  differ from it by rounding on edges a few nm long);
- ``feature_ids``: (k,) hashable keys, one per point, naming the features that touch
  (for example reference edge and incident vertex); the same features give the same
  key on the next step, which is what warm starting matches.  ``None`` when unknown;
- ``separations``: (k,) signed separation at each point (m, > 0 still apart, <= 0
  overlapping): the given depths negated before they are clamped at 0, so a
  speculative point (:mod:`~exercises.narrowphase.speculative`, given a negative
  depth) keeps how far apart it is while ``depths`` keeps the conventions above.

Moving B by ``depth * normal`` (or A by the opposite) separates the shapes.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class Contact:
    """One contact manifold between shape A and shape B; see the module docstring."""

    normal: np.ndarray
    depth: float
    points: np.ndarray
    depths: np.ndarray | None = None
    feature_ids: tuple | None = None
    separations: np.ndarray | None = None

    def __post_init__(self):
        normal = np.array(self.normal, dtype=float).reshape(2)
        points = np.array(self.points, dtype=float).reshape(-1, 2)
        depth = max(float(self.depth), 0.0)
        given = (np.full(len(points), float(self.depth)) if self.depths is None
                 else np.array(self.depths, dtype=float).reshape(-1))
        if len(given) != len(points):
            raise ValueError(f"{len(points)} contact points but {len(given)} depths")
        separations = -given if self.separations is None else np.array(self.separations, dtype=float).reshape(-1)
        if len(separations) != len(points):
            raise ValueError(f"{len(points)} contact points but {len(separations)} separations")
        depths = np.maximum(given, 0.0)
        if self.feature_ids is not None and len(self.feature_ids) != len(points):
            raise ValueError(f"{len(points)} contact points but {len(self.feature_ids)} feature ids")
        for arr in (normal, points, depths, separations):
            arr.setflags(write=False)
        object.__setattr__(self, "normal", normal)
        object.__setattr__(self, "depth", depth)
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "depths", depths)
        object.__setattr__(self, "separations", separations)

    def flipped(self) -> "Contact":
        """The same contact seen from B: normal negated, depth and points unchanged."""
        return Contact(0.0 - self.normal, self.depth, self.points, self.depths, self.feature_ids, self.separations)

    def __repr__(self):
        return (f"Contact(normal={np.round(self.normal, 12).tolist()}, depth={self.depth!r}, "
                f"points={self.points.tolist()})")
