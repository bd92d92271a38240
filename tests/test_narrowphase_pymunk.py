"""The narrow phase against pymunk's ``shapes_collide`` on thousands of seeded random pairs.

For every ordered pair of shape kinds (circle, AABB, OBB rotated at random, convex
polygon rotated at random) we draw ``PAIRS_PER_KIND`` pairs of shapes of 0.1..1.5 m
within a 4 m square, so that about half of them collide, and check:

- the yes/no answer of ``shapes_overlap`` and of ``collide`` against pymunk, except
  for pairs within ``TOUCH_BAND`` of touching, where both libraries are right to
  disagree by roundoff;
- for colliding pairs the normal, the depth, the number of contact points and the
  points themselves (a face-face contact is compared as a set of 2 points).

Tolerances.  Both libraries compute the same closed-form quantities in double
precision (edge normals, projections, clipped points on shapes of about 1 m), and on
this machine they agree to about 1e-15.  ``GEOMETRY_ATOL`` = 1e-8 m leaves room for a
different order of operations (pymunk reaches the final edge through GJK/EPA) while a
wrong feature, sign or clipping would be off by millimetres at least.  The one
intended difference is the reference face: we keep A's face unless B's is better by
``REFERENCE_FACE_RELATIVE_TOL`` of the depth (box2d-lite's hysteresis), where pymunk
takes the exact least penetration.  Then the normals differ, and the test checks that
our depth lies in that band above pymunk's, equals the brute-force overlap along our
normal, and that each point lies within half its depth of both shapes (it is the
midpoint of two boundary points that far apart).
"""
from __future__ import annotations

import numpy as np
import pytest

from solutions.narrowphase import polygon_polygon
from solutions.narrowphase.dispatch import collide, shapes_overlap
from solutions.shapes import Circle
from test_narrowphase_oracles import KINDS, overlap_along, pymunk_contact, random_shape, signed_gap

PAIRS_PER_KIND = 1500
#: m: see the module docstring.
GEOMETRY_ATOL = 1e-8
#: m: pairs whose brute-force gap is smaller than this are "touching" and skipped for
#: the yes/no comparison (random pairs essentially never land there).
TOUCH_BAND = 1e-9


def _match_points(ours, theirs_points):
    """Each of our points has a pymunk point at the same place with the same depth."""
    assert len(ours.points) == len(theirs_points), (ours, theirs_points)
    unused = list(theirs_points)
    for point, depth in zip(ours.points, ours.depths):
        distances = [float(np.hypot(*(point - q))) for q, _ in unused]
        k = int(np.argmin(distances))
        assert distances[k] <= GEOMETRY_ATOL, (ours, theirs_points)
        assert depth == pytest.approx(unused[k][1], abs=GEOMETRY_ATOL)
        unused.pop(k)


@pytest.mark.parametrize("kind_b", KINDS)
@pytest.mark.parametrize("kind_a", KINDS)
def test_agrees_with_pymunk_on_random_pairs(kind_a, kind_b):
    rng = np.random.default_rng(sum(map(ord, kind_a + "/" + kind_b)))
    counts = {"checked": 0, "colliding": 0, "same_normal": 0, "two_points": 0}
    for _ in range(PAIRS_PER_KIND):
        a, b = random_shape(rng, kind_a), random_shape(rng, kind_b)
        ours = collide(a, b)
        theirs = pymunk_contact(a, b)
        if abs(signed_gap(a, b)) < TOUCH_BAND:
            continue
        counts["checked"] += 1
        assert shapes_overlap(a, b) == (theirs is not None), (a, b)
        assert (ours is not None) == (theirs is not None), (a, b)
        if ours is None:
            continue
        counts["colliding"] += 1
        their_normal, their_points = theirs
        their_depth = max(d for _, d in their_points)
        np.testing.assert_allclose(np.hypot(*ours.normal), 1.0, atol=1e-12)
        assert ours.depth == pytest.approx(float(ours.depths.max()), abs=GEOMETRY_ATOL)
        if np.allclose(ours.normal, their_normal, rtol=0, atol=GEOMETRY_ATOL):
            counts["same_normal"] += 1
            assert ours.depth == pytest.approx(their_depth, abs=GEOMETRY_ATOL), (a, b)
            _match_points(ours, their_points)
            counts["two_points"] += len(ours.points) == 2
        else:
            # Reference-face hysteresis (polygon pairs only): see the module docstring.
            assert kind_a != "circle" and kind_b != "circle", (a, b, ours, theirs)
            # A keeps its face while depth_A - depth_B <= rtol * depth_A + atol * scale.
            highest = ((their_depth + polygon_polygon.REFERENCE_FACE_ABSOLUTE_TOL * 4.0)  # coordinates < 4 m
                       / (1.0 - polygon_polygon.REFERENCE_FACE_RELATIVE_TOL))
            assert their_depth - GEOMETRY_ATOL <= ours.depth <= highest + GEOMETRY_ATOL, (a, b)
            assert overlap_along(a, b, ours.normal) == pytest.approx(ours.depth, abs=GEOMETRY_ATOL)
            # Each point is the midpoint between a point on B's boundary and one on A's
            # reference face, depth_i apart: so it is within depth_i / 2 of both shapes.
            for point, depth in zip(ours.points, ours.depths):
                probe = Circle(point, 0.0)
                assert signed_gap(probe, a) <= depth / 2 + GEOMETRY_ATOL, (a, b, ours)
                assert signed_gap(probe, b) <= depth / 2 + GEOMETRY_ATOL, (a, b, ours)
    # The draw must exercise what it claims to: enough collisions, mostly exact matches,
    # and 2-point manifolds for pairs of polygons.
    assert counts["colliding"] >= PAIRS_PER_KIND // 5, counts
    assert counts["same_normal"] >= 0.85 * counts["colliding"], counts
    if kind_a != "circle" and kind_b != "circle" and "aabb" in (kind_a, kind_b) and kind_a == kind_b:
        assert counts["two_points"] == counts["same_normal"], counts
