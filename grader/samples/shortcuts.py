"""Shortcuts a student may take in one exercise function: systematic bugs the example
class (:mod:`grader.samples.example_class`) does not hold, each a whole function as a
student writes it (:class:`~grader.samples.example_class.Replacement`).

They are graded by ``tests/test_grading_integrity.py`` and counted in the per-function
loss table (``python -m tools.function_losses``): each must lose at least half of the
points of the tests that reach its function.
"""
from __future__ import annotations

from .example_class import Replacement

#: The reference's reference_face_manifold as a student writes it, with three places to
#: change: KEPT (the condition on a clipped point), DEPTH (its depth) and UNIQUE (the check
#: for a point already kept).
CLIPPING = '''
    def reference_face_manifold(ref_vertices, ref_normal, ref_face, inc_vertices, inc_normals, inc_faces,
                                ref_name, scale, margin=0.0):
        n = ref_normal
        tangent = np.array([-n[1], n[0]])
        i1, i2 = ref_face, (ref_face + 1) % len(ref_vertices)
        v1, v2 = ref_vertices[i1], ref_vertices[i2]
        j = incident_face(inc_normals, inc_faces, n)
        j2 = (j + 1) % len(inc_vertices)
        segment = [(inc_vertices[j], (ref_name, ref_face, j, j)), (inc_vertices[j2], (ref_name, ref_face, j, j2))]
        roundoff = KEEP_POINT_TOL * scale
        segment = clip_segment_to_half_plane(segment, tangent, float(tangent @ v2), roundoff)
        segment = clip_segment_to_half_plane(segment, -tangent, float(-tangent @ v1), roundoff)
        points, depths, feature_ids = [], [], []
        for point, feature in segment:
            separation = float(n @ (point - v1))
            midpoint = point - 0.5 * separation * n
            if KEPT and UNIQUE:
                points.append(midpoint)
                depths.append(DEPTH)
                feature_ids.append(feature)
        return points, depths, feature_ids
    '''


def clipping(kept: str = "separation <= margin + roundoff", depth: str = "-separation",
             unique: str = "not any(float(np.max(np.abs(midpoint - q))) <= roundoff for q in points)") -> tuple:
    """reference_face_manifold rewritten: the reference's, with the three places given."""
    source = CLIPPING.replace("KEPT", kept).replace("DEPTH", depth).replace("UNIQUE", unique)
    return (Replacement("narrowphase.polygon_polygon", "reference_face_manifold", source),)


#: An apply_normal_impulse that clamps every row's accumulated impulse at 0, ignoring its
#: lower bound: a joint row (lower = -inf) never pulls.
ROWS_CLAMPED_AT_0 = (Replacement("solver.contact_point", "apply_normal_impulse", '''
    def apply_normal_impulse(velocity_a, velocity_b, point, normal_total, target=0.0, mass_scale=1.0,
                             impulse_scale=0.0):
        vxa, vya, wa = velocity_a
        vxb, vyb, wb = velocity_b
        nx, ny, rn_a, rn_b, _, _, ima, imb, iia, iib, mass_normal, _, _, lower = point
        normal_velocity = (vxb - vxa) * nx + (vyb - vya) * ny + wb * rn_b - wa * rn_a
        change = mass_normal * mass_scale * (target - normal_velocity) - impulse_scale * normal_total
        new_total = max(normal_total + change, 0.0)
        change = new_total - normal_total
        return ((vxa - ima * change * nx, vya - ima * change * ny, wa - iia * rn_a * change),
                (vxb + imb * change * nx, vyb + imb * change * ny, wb + iib * rn_b * change), new_total)
    '''),)

#: reference_face_manifold without the check for a repeated point: a zero-size incident face
#: gives its one point twice (a bug of degenerate shapes only, not a systematic one).
MANIFOLD_REPEATS_A_POINT = clipping(unique="True")

#: Systematic bugs of the exercise functions no example-class sample rewrites, one each.
UNCOVERED = {
    # Tangent impulses bounded by mu alone, not mu times the accumulated normal impulse.
    "friction-bound-without-normal": (Replacement("solver.contact_point", "apply_friction_impulse", '''
        def apply_friction_impulse(velocity_a, velocity_b, point, normal_total, tangent_total):
            vxa, vya, wa = velocity_a
            vxb, vyb, wb = velocity_b
            nx, ny, _, _, rt_a, rt_b, ima, imb, iia, iib, _, mass_tangent, friction, _ = point
            tangent_velocity = (vxb - vxa) * ny - (vyb - vya) * nx + wb * rt_b - wa * rt_a
            bound = friction
            new_total = min(max(tangent_total - mass_tangent * tangent_velocity, -bound), bound)
            change = new_total - tangent_total
            return ((vxa - ima * change * ny, vya + ima * change * nx, wa - iia * rt_a * change),
                    (vxb + imb * change * ny, vyb - imb * change * nx, wb + iib * rt_b * change), new_total)
        '''),),
    # The normal from B's centre to A's.
    "circle-normal-b-to-a": (Replacement("narrowphase.circle_circle", "collide_circle_circle", '''
        def collide_circle_circle(a, b):
            offset = a.center - b.center
            distance = math.hypot(offset[0], offset[1])
            reach = a.radius + b.radius
            if distance > reach:
                return None
            normal = np.array(COINCIDENT_CENTRES_NORMAL) if distance <= COINCIDENT_CENTRES_ATOL else offset / distance
            point = (a.center - a.radius * normal + b.center + b.radius * normal) / 2
            return Contact(normal, reach - distance, [point], feature_ids=(("circle", "circle"),))
        '''),),
    # The common velocity as the plain mean of the two, whatever the masses.
    "inelastic-plain-mean": (Replacement("response.momentum_1d", "perfectly_inelastic_1d", '''
        def perfectly_inelastic_1d(m1, v1, m2, v2):
            _checked_pair(m1, v1, m2, v2)
            return (v1 + v2) / 2
        '''),),
    # Only the x axis tested.
    "aabb-x-axis-only": (Replacement("narrowphase.aabb_aabb", "aabbs_overlap", '''
        def aabbs_overlap(a, b):
            return not (a.max_corner[0] < b.min_corner[0] or b.max_corner[0] < a.min_corner[0])
        '''),),
    # Only A's two axes tested.
    "obb-only-a-axes": (Replacement("narrowphase.polygon_polygon", "obbs_overlap", '''
        def obbs_overlap(a, b):
            vertices_a, vertices_b = a.vertices(), b.vertices()
            return all(intervals_overlap(project_vertices(vertices_a, axis), project_vertices(vertices_b, axis))
                       for axis in box_axes(a))
        '''),),
    # A face's separation from the other polygon's farthest vertex instead of its deepest.
    "face-separation-farthest-vertex": (Replacement("narrowphase.polygon_polygon", "max_face_separation", '''
        def max_face_separation(ref_vertices, ref_normals, ref_faces, other_vertices):
            starts = ref_vertices[ref_faces]
            offsets = other_vertices[None, :, :] - starts[:, None, :]
            separations = np.einsum("kmd,kd->km", offsets, ref_normals).max(axis=1)
            best = int(np.argmax(separations))
            return float(separations[best]), int(ref_faces[best])
        '''),),
    # A's best face always the reference, B's never tried.
    "reference-face-always-a": (Replacement("narrowphase.polygon_polygon", "reference_face_candidates", '''
        def reference_face_candidates(polygon_a, polygon_b, margin=0.0):
            separation_a, face_a = max_face_separation(*polygon_a, polygon_b[0])
            separation_b, _ = max_face_separation(*polygon_b, polygon_a[0])
            if separation_a > margin or separation_b > margin:
                return []
            return [("A", separation_a, face_a, polygon_a, polygon_b)]
        '''),),
    # The crossing point measured from the wrong end of the segment.
    "clip-crossing-from-wrong-end": (Replacement("narrowphase.polygon_polygon", "clip_segment_to_half_plane", '''
        def clip_segment_to_half_plane(points, plane_normal, plane_offset, tolerance=0.0):
            distances = [float(plane_normal @ point) - plane_offset for point, _ in points]
            kept = [pair for pair, distance in zip(points, distances) if distance <= tolerance]
            if len(points) == 2 and len(kept) == 1 and distances[0] * distances[1] < 0.0:
                (p0, id0), (p1, id1) = points
                fraction = distances[1] / (distances[1] - distances[0])
                kept.append((p0 + fraction * (p1 - p0), id1 if distances[1] > 0.0 else id0))
            return kept
        '''),),
    # Every body filed at the deepest node that holds it, but no leaf ever split: one node.
    "quadtree-never-splits": (Replacement("broadphase.quadtree", "Quadtree.insert", '''
        def insert(self, index: int, box) -> None:
            box = self.check_new_body(index, box)
            node = self.root
            while not node.is_leaf:
                child = self.child_holding(node, box)
                if child is None:
                    break
                node = child
            node.bodies.append(index)
        '''),),
}

#: name -> the rewritten function(s): one systematic bug each.
SHORTCUTS: dict[str, tuple[Replacement, ...]] = {
    # Points above the reference face dropped whatever the margin (the soft step's
    # speculative points are lost), or kept with their depth clamped at 0 (they count as
    # touching, and the crate hovers).
    "manifold-ignores-margin": clipping(kept="separation <= roundoff"),
    "manifold-depth-clamped-at-0": clipping(depth="max(-separation, 0.0)"),
    "normal-rows-clamped-at-0": ROWS_CLAMPED_AT_0,
    **UNCOVERED,
}

#: Exercise functions that call a bug's function only where the bug does no harm, so the
#: tests reaching them cannot see it and are not at stake: the sweeps of
#: solver/contact_sweeps.py (and the step around them) hand apply_normal_impulse contact
#: rows alone (lower bound 0, where clamping at 0 is right).
BLIND_CALLERS: dict[str, set[str]] = {
    "normal-rows-clamped-at-0": {"solver.contact_sweeps.prestep_point", "solver.contact_sweeps.contact_target",
                                 "solver.contact_sweeps.sweep_contacts", "solver.contact_sweeps.step_bodies"},
}
