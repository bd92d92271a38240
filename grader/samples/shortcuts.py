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

#: name -> the rewritten function(s): one systematic bug each.
SHORTCUTS: dict[str, tuple[Replacement, ...]] = {
    # Points above the reference face dropped whatever the margin (the soft step's
    # speculative points are lost), or kept with their depth clamped at 0 (they count as
    # touching, and the crate hovers).
    "manifold-ignores-margin": clipping(kept="separation <= roundoff"),
    "manifold-depth-clamped-at-0": clipping(depth="max(-separation, 0.0)"),
    "normal-rows-clamped-at-0": ROWS_CLAMPED_AT_0,
}
