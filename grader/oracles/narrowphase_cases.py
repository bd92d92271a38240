"""Pairs of plain shapes in named categories, for the SAT and contact tests.

Each category is built from a few numbers by a ``*_pair`` function, so the same
construction serves a seeded batch (numbers from a numpy Generator, ``random_*``) and a
Hypothesis strategy (numbers from strategies of round values, ``*_pairs``): a case that
Hypothesis shrinks stays in its category, because every example of the strategy is
built by the construction (and, where a construction cannot promise it by itself,
filtered by the brute-force check of :mod:`.brute_sat`).

The categories aim at the classic bugs: pairs that only one shape's axes separate
(SAT that forgets B's axes), polygons just apart that no edge direction separates
(edges taken for normals), circles off a box's corner that only the centre-to-vertex
axis separates, boxes touching exactly (strict ``<`` instead of ``<=``), shapes left of
or right of the origin (FLT_MIN and min-initialised-to-0), circles with their centre
inside a box (deep penetration), boxes face to face (two-point manifolds).

Exact touching is built from multiples of 1/8 m on axis-aligned edges (and from
Pythagorean triples for circles), so every method computes the same numbers with no
rounding at all and the answer "touching, depth 0" is defined.  Units: m, rad.
"""
from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st

from . import plain
from .brute_sat import axis_gaps, face_normals, face_separations, interval, separating_owners

#: Exact binary fractions used for touching cases (m).
EIGHTH = 0.125
#: Pythagorean triples: circles at these centre distances touch with no rounding.
TRIPLES = ((3, 4, 5), (5, 12, 13), (8, 15, 17), (7, 24, 25), (20, 21, 29), (0, 1, 1))
BOX_KINDS = ("aabb", "obb", "polygon")


def rotation(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def box(center, half_extents, angle: float, kind: str = "obb") -> dict:
    """A box as an OBB, an AABB (angle must be 0) or a ConvexPolygon of its corners."""
    shape = plain.obb(center, half_extents, angle)
    if kind == "obb":
        return shape
    if kind == "aabb":
        if angle != 0.0:
            raise ValueError("an AABB has angle 0")
        return plain.aabb_from_center(center, half_extents)
    if kind == "polygon":
        return plain.polygon(plain.vertices(shape))
    raise ValueError(kind)


# Touching exactly ----------------------------------------------------------------------
def touching_boxes_pair(center_a, half_a, half_b, side: int, slide: float, kinds=("obb", "obb")) -> tuple:
    """Two axis-aligned boxes that touch exactly, and their contact.

    B sits against A's face ``side`` (0 -y, 1 +x, 2 +y, 3 -x); ``slide`` in [-1, 1] moves
    it along that face, +-1 putting the boxes corner to corner.  Inputs must be
    multiples of 1/8 (m) and ``slide`` a multiple of 1/8 too, so nothing is rounded.

    Returns (A, B, contact): the normal is A's face normal (A to B), the depth 0 and
    the points the two ends of the stretch the faces share (one point corner to corner).
    """
    ca, ha, hb = np.asarray(center_a, float), np.asarray(half_a, float), np.asarray(half_b, float)
    normal = np.array([(0, -1), (1, 0), (0, 1), (-1, 0)][side], dtype=float)
    along = np.abs(normal[::-1])
    reach = float(along @ (ha + hb))
    cb = ca + normal * (ha + hb) + along * slide * reach
    level = ca + normal * ha                         # a point of A's face line
    lo = max(float(along @ (ca - ha)), float(along @ (cb - hb)))
    hi = min(float(along @ (ca + ha)), float(along @ (cb + hb)))
    ends = [lo, hi] if hi > lo else [lo]
    points = [level * np.abs(normal) + along * t for t in ends]
    return (box(ca, ha, 0.0, kinds[0]), box(cb, hb, 0.0, kinds[1]), plain.contact(normal + 0.0, 0.0, points))


def random_touching_boxes(rng: np.random.Generator, corner: bool = False, kinds=None) -> tuple:
    def eighths(lo, hi, size=None):
        return rng.integers(round(lo / EIGHTH), round(hi / EIGHTH) + 1, size) * EIGHTH

    kinds = kinds or (BOX_KINDS[rng.integers(3)], BOX_KINDS[rng.integers(3)])
    slide = float(rng.choice([-1.0, 1.0])) if corner else float(rng.integers(-7, 8)) * EIGHTH
    return touching_boxes_pair(eighths(-6, 6, 2), eighths(0.25, 1.5, 2), eighths(0.25, 1.5, 2), int(rng.integers(4)),
                               slide, kinds)


def touching_circles_pair(center_a, triple: int, scale: float, share: float, signs=(1, 1), swap: bool = False) -> tuple:
    """Two circles whose centres are a Pythagorean distance apart, touching exactly.

    ``scale`` a power of two, ``share`` in (0, 1) a multiple of 1/8: A's part of the
    distance (its radius).  Returns (A, B, contact): normal ``(c_b - c_a) / |c_b - c_a|``,
    depth 0, the point ``c_a + r_a n`` where they touch.
    """
    x, y, hyp = TRIPLES[triple]
    if swap:
        x, y = y, x
    ca = np.asarray(center_a, dtype=float)
    offset = np.array([signs[0] * x * scale, signs[1] * y * scale])
    ra = share * hyp * scale
    normal = offset / (hyp * scale)
    return (plain.circle(ca, ra), plain.circle(ca + offset, hyp * scale - ra),
            plain.contact(normal + 0.0, 0.0, [ca + ra * normal]))


def random_touching_circles(rng: np.random.Generator) -> tuple:
    triple = int(rng.integers(len(TRIPLES)))
    scale = float(rng.choice([0.0625, 0.125, 0.25])) if TRIPLES[triple][2] > 5 else float(rng.choice([0.25, 0.5, 1.0]))
    return touching_circles_pair(rng.integers(-40, 41, 2) * EIGHTH, triple, scale, float(rng.integers(1, 8)) * EIGHTH,
                                 tuple(rng.choice([-1, 1], 2)), bool(rng.integers(2)))


def touching_circle_box_pair(center_box, half, side: int, slide: float, radius: float, kind: str = "obb") -> tuple:
    """A circle touching the middle part of an axis-aligned box's face ``side`` exactly.

    ``slide`` in [-0.75, 0.75] is where along the face (multiples of 1/8: no rounding).
    Returns (circle, box, contact): the normal from the circle to the box (minus the
    face's outward normal), depth 0, the point where they touch.
    """
    cb, h = np.asarray(center_box, float), np.asarray(half, float)
    normal = np.array([(0, -1), (1, 0), (0, 1), (-1, 0)][side], dtype=float)
    along = np.abs(normal[::-1])
    center = cb + normal * (h + radius) + along * slide * float(along @ h)
    return (plain.circle(center, radius), box(cb, h, 0.0, kind),
            plain.contact(0.0 - normal, 0.0, [center - normal * radius]))


def random_touching_circle_box(rng: np.random.Generator) -> tuple:
    return touching_circle_box_pair(rng.integers(-40, 41, 2) * EIGHTH, rng.integers(2, 13, 2) * EIGHTH,
                                    int(rng.integers(4)), float(rng.integers(-6, 7)) * EIGHTH,
                                    float(rng.integers(1, 13)) * EIGHTH, BOX_KINDS[rng.integers(3)])


# Only one shape's axes separate ---------------------------------------------------------
def one_side_pair(center, half_a, angle_a: float, corner: int, half_b, turn: float, gap: float, slide: float,
                  kinds=("obb", "obb")) -> tuple:
    """Boxes A and B apart, separated by one of B's face normals and by none of A's.

    B is turned to face A's ``corner`` (B's -x face looks at it, ``turn`` rad off the
    corner's diagonal) and placed ``gap`` (m) beyond it, slid by ``slide`` (m) along
    its face.  With a small gap, B's wide face still overlaps A on both of A's axes, so
    SAT that tests A's axes only says they overlap.  Call with (B, A) for the pair that
    only A's axes separate.  Check with :func:`.brute_sat.separating_owners`.
    """
    ha = np.asarray(half_a, dtype=float)
    corner_local = ha * np.array([(-1, -1), (1, -1), (1, 1), (-1, 1)][corner], dtype=float)
    diagonal = np.sign(corner_local) / math.sqrt(2.0)
    rot_a = rotation(angle_a)
    m = rot_a @ rotation(turn) @ diagonal           # B's x axis, from A towards B
    apex = np.asarray(center, dtype=float) + rot_a @ corner_local
    hb = np.asarray(half_b, dtype=float)
    tangent = np.array([-m[1], m[0]])
    # A's extent along m is reached at the corner (turn < 45 degrees keeps it there).
    center_b = apex + m * (gap + hb[0]) + tangent * slide
    angle_b = math.atan2(m[1], m[0])
    a = box(center, ha, angle_a, kinds[0])
    return a, box(center_b, hb, angle_b, kinds[1])


def random_one_side(rng: np.random.Generator, spread: float = 3.0, offset=(0.0, 0.0), kinds=("obb", "obb")) -> tuple:
    """Seeded :func:`one_side_pair`: (A, B) that only B's axes separate (m)."""
    while True:
        ha = rng.uniform(0.3, 1.5, 2)
        hb = np.array([rng.uniform(0.2, 1.2), rng.uniform(0.8, 2.0)])
        a, b = one_side_pair(rng.uniform(-spread, spread, 2) + np.asarray(offset), ha, float(rng.uniform(-math.pi, math.pi)),
                             int(rng.integers(4)), hb, float(rng.uniform(-0.35, 0.35)),
                             float(rng.uniform(0.02, 0.25)) * float(min(ha.min(), hb[1])), float(rng.uniform(-0.3, 0.3)),
                             kinds)
        if separating_owners(a, b, margin=1e-3) == {"B"} and _min_gap(a, b) > 1e-3:
            return a, b


def _min_gap(a: dict, b: dict) -> float:
    """The largest separating gap over both shapes' face normals (m)."""
    return float(np.max(axis_gaps(a, b, np.vstack([face_normals(a), face_normals(b)]))))


def edge_directions(shape: dict) -> np.ndarray:
    """Unit directions (k, 2) of a polygonal shape's edges (not its normals)."""
    v = plain.vertices(shape)
    edges = np.roll(v, -1, axis=0) - v
    return edges / np.hypot(edges[:, 0], edges[:, 1])[:, None]


def close_apart_pair(a: dict, b: dict, gap: float) -> tuple:
    """A and B moved apart (or together) along their best separating face normal until
    the gap there is ``gap`` (m): a pair only just apart, which only face normals near
    that one separate (an edge direction, taken by mistake for a normal, does not)."""
    normal, separation = max(face_separations(a, b), key=lambda f: f[1])
    shift = normal * (gap - separation)
    if b["$shape"] == "OBB":
        return a, plain.obb(np.asarray(b["center"]) + shift, b["half_extents"], b["angle"])
    return a, plain.polygon(plain.vertices(b) + shift)


def random_close_apart(rng: np.random.Generator, spread: float = 1.5, offset=(0.0, 0.0)) -> tuple:
    """Seeded :func:`close_apart_pair` of random polygons (3 to 7 vertices), apart by 1 to
    5 % of their size, that no edge direction of either separates."""
    while True:
        a = plain.polygon(np.asarray(_random_polygon_vertices(rng, 1.0)) + rng.uniform(-spread, spread, 2) + offset)
        b = plain.polygon(np.asarray(_random_polygon_vertices(rng, 1.0)) + rng.uniform(-spread, spread, 2) + offset)
        a, b = close_apart_pair(a, b, float(rng.uniform(0.01, 0.05)))
        if (float(np.max(axis_gaps(a, b, np.vstack([edge_directions(a), edge_directions(b)])))) < -1e-3
                and _min_gap(a, b) > 5e-3):
            return a, b


def _random_polygon_vertices(rng: np.random.Generator, radius: float) -> np.ndarray:
    """3 to 7 CCW vertices on a circle of ``radius`` (m) around the origin, with no two
    closer than 0.2 rad."""
    while True:
        count = int(rng.integers(3, 8))
        angles = np.sort(rng.uniform(0, 2 * math.pi, count))
        if np.min(np.diff(np.append(angles, angles[0] + 2 * math.pi))) > 0.2:
            return np.column_stack([np.cos(angles), np.sin(angles)]) * radius


# Circles near a box ------------------------------------------------------------------------
def corner_circle_pair(center, half, angle: float, corner: int, turn: float, radius: float, reach: float,
                       kind: str = "obb") -> tuple:
    """A circle in the vertex region of a box's ``corner``, its centre ``reach`` radii
    from the corner along the corner's diagonal turned by ``turn`` (rad).

    ``reach`` in (1, 1.2] with ``|turn|`` <= 0.15: apart, and only the axis from the
    centre to the nearest vertex separates them (``reach cos(pi/4 - |turn|) < 1``);
    ``reach`` < 1: overlapping.
    """
    h = np.asarray(half, dtype=float)
    corner_local = h * np.array([(-1, -1), (1, -1), (1, 1), (-1, 1)][corner], dtype=float)
    direction = rotation(angle) @ rotation(turn) @ (np.sign(corner_local) / math.sqrt(2.0))
    apex = np.asarray(center, dtype=float) + rotation(angle) @ corner_local
    return plain.circle(apex + direction * reach * radius, radius), box(center, h, angle, kind)


def face_circle_pair(center, half, angle: float, side: int, slide: float, radius: float, distance: float,
                     kind: str = "obb") -> tuple:
    """A circle whose centre is ``distance`` (m) out of the box's face ``side`` (negative:
    inside the box), at ``slide`` in [-1, 1] along that face."""
    h = np.asarray(half, dtype=float)
    normal_local = np.array([(0, -1), (1, 0), (0, 1), (-1, 0)][side], dtype=float)
    along_local = np.abs(normal_local[::-1])
    local = normal_local * (float(np.abs(normal_local) @ h) + distance) + along_local * slide * float(along_local @ h)
    return plain.circle(np.asarray(center, dtype=float) + rotation(angle) @ local, radius), box(center, h, angle, kind)


def inside_circle_pair(center, half, angle: float, u: float, v: float, radius: float, kind: str = "obb") -> tuple:
    """A circle whose centre is inside the box, at local position ``(u hx, v hy)``
    with ``u, v`` in (-1, 1)."""
    h = np.asarray(half, dtype=float)
    local = np.array([u * h[0], v * h[1]])
    return plain.circle(np.asarray(center, dtype=float) + rotation(angle) @ local, radius), box(center, h, angle, kind)


def random_corner_circle(rng: np.random.Generator, apart: bool, spread: float = 2.0, offset=(0.0, 0.0)) -> tuple:
    """Seeded :func:`corner_circle_pair` (apart: only the vertex axis separates)."""
    reach = rng.uniform(1.03, 1.2) if apart else rng.uniform(0.2, 0.95)
    return corner_circle_pair(rng.uniform(-spread, spread, 2) + np.asarray(offset), rng.uniform(0.2, 1.5, 2),
                              float(rng.uniform(-math.pi, math.pi)), int(rng.integers(4)), float(rng.uniform(-0.15, 0.15)),
                              float(rng.uniform(0.2, 1.5)), float(reach), BOX_KINDS[1 + rng.integers(2)])


def random_face_circle(rng: np.random.Generator, apart: bool, spread: float = 2.0, offset=(0.0, 0.0)) -> tuple:
    """Seeded :func:`face_circle_pair`: the centre outside a face, apart or overlapping
    (by 2 % to 95 % of the radius)."""
    radius = float(rng.uniform(0.2, 1.5))
    distance = radius * (rng.uniform(1.02, 1.5) if apart else rng.uniform(0.05, 0.98))
    return face_circle_pair(rng.uniform(-spread, spread, 2) + np.asarray(offset), rng.uniform(0.2, 1.5, 2),
                            float(rng.uniform(-math.pi, math.pi)), int(rng.integers(4)), float(rng.uniform(-0.9, 0.9)),
                            radius, float(distance), BOX_KINDS[1 + rng.integers(2)])


def random_outside_polygon_circle(rng: np.random.Generator, spread: float = 1.0) -> tuple:
    """A circle whose centre is just outside a random convex polygon (3 to 7 vertices), by
    10 % to 90 % of its radius beyond the polygon's extent in a random direction: often
    in front of several faces at once, of which only the nearest holds the contact."""
    poly = plain.polygon(np.asarray(_random_polygon_vertices(rng, float(rng.uniform(0.5, 1.2))))
                         + rng.uniform(-spread, spread, 2))
    v = np.asarray(poly["vertices"], dtype=float)
    middle = v.mean(axis=0)
    angle = rng.uniform(0, 2 * math.pi)
    u = np.array([math.cos(angle), math.sin(angle)])
    radius = float(rng.uniform(0.2, 0.8))
    reach = float(np.max((v - middle) @ u))
    return plain.circle(middle + u * (reach + radius * rng.uniform(0.1, 0.9)), radius), poly


def random_inside_circle(rng: np.random.Generator, spread: float = 2.0, offset=(0.0, 0.0)) -> tuple:
    """Seeded :func:`inside_circle_pair` whose nearest face is clear."""
    while True:
        pair = inside_circle_pair(rng.uniform(-spread, spread, 2) + np.asarray(offset), rng.uniform(0.2, 1.5, 2),
                                  float(rng.uniform(-math.pi, math.pi)), *rng.uniform(-0.95, 0.95, 2),
                                  float(rng.uniform(0.05, 1.5)), BOX_KINDS[1 + rng.integers(2)])
        if nearest_face_is_clear(*pair):
            return pair


def nearest_face_is_clear(circle: dict, shape: dict, margin: float = 1e-3) -> bool:
    """For a centre inside a polygon: the nearest face is nearer than the second by ``margin`` (m)."""
    c = np.asarray(circle["center"], dtype=float)
    v = plain.vertices(shape)
    distances = np.sort(-np.einsum("kd,kd->k", c - v, face_normals(shape)))
    return bool(distances[0] > margin and distances[1] - distances[0] > margin)


# Boxes face to face -----------------------------------------------------------------------
def face_face_pair(center, half_a, angle: float, side: int, half_b, quarter_turns: int, depth: float, slide: float,
                   kinds=("obb", "obb")) -> tuple:
    """B parallel to A (turned by a multiple of 90 degrees) pushed ``depth`` (m) into A's
    face ``side``, slid by ``slide`` (m) along it: two parallel faces in contact."""
    ha, hb = np.asarray(half_a, float), np.asarray(half_b, float)
    normal_local = np.array([(0, -1), (1, 0), (0, 1), (-1, 0)][side], dtype=float)
    along_local = np.abs(normal_local[::-1])
    hb_world_local = hb if quarter_turns % 2 == 0 else hb[::-1]  # B's half-extents in A's frame
    reach = float(np.abs(normal_local) @ (ha + hb_world_local)) - depth
    local = normal_local * reach + along_local * slide
    center_b = np.asarray(center, dtype=float) + rotation(angle) @ local
    return (box(center, ha, angle, kinds[0]), box(center_b, hb, angle + quarter_turns * math.pi / 2, kinds[1]))


def random_face_face(rng: np.random.Generator, spread: float = 2.0, offset=(0.0, 0.0), kinds=("obb", "obb")) -> tuple:
    """Seeded :func:`face_face_pair`: 2 % to 30 % of the smaller box deep, the faces
    sharing a good part of their length (two contact points)."""
    ha = rng.uniform(0.3, 1.5, 2)
    hb = rng.uniform(0.3, 1.5, 2)
    side = int(rng.integers(4))
    turns = int(rng.integers(4))
    hb_along = float(np.abs(np.array([(0, -1), (1, 0), (0, 1), (-1, 0)][side])[::-1])
                     @ (hb if turns % 2 == 0 else hb[::-1]))
    ha_along = float(np.abs(np.array([(0, -1), (1, 0), (0, 1), (-1, 0)][side])[::-1]) @ ha)
    slide = float(rng.uniform(-1, 1)) * max(abs(ha_along - hb_along), 0.6 * min(ha_along, hb_along))
    depth = float(rng.uniform(0.02, 0.3)) * float(min(ha.min(), hb.min()))
    return face_face_pair(rng.uniform(-spread, spread, 2) + np.asarray(offset), ha, float(rng.uniform(-math.pi, math.pi)),
                          side, hb, turns, depth, slide, kinds)


# Hypothesis strategies of round numbers ----------------------------------------------------------
def rounded(lo: float, hi: float, digits: int = 2):
    """Round numbers in [lo, hi] with ``digits`` decimals (drawn as integers: cheap, and
    they shrink towards the simplest value in range)."""
    scale = 10 ** digits
    return st.integers(math.ceil(lo * scale), math.floor(hi * scale)).map(lambda k: k / scale)


coordinates = rounded(-4, 4)
halves = rounded(0.2, 1.5)
angles = rounded(-math.pi, math.pi)
corners = st.integers(0, 3)
sides = st.integers(0, 3)
box_kinds = st.sampled_from(BOX_KINDS[1:])  # OBB or ConvexPolygon: any angle


def one_side_pairs(spread: float = 4.0, apart: bool = True):
    """(A, B) that only B's face normals separate (filtered by brute force), or, with
    ``apart=False``, the same construction pushed into A's corner: overlapping."""
    gaps = rounded(0.05, 0.25) if apart else rounded(-0.25, -0.05)

    def in_category(ab) -> bool:
        if apart:
            return separating_owners(*ab, margin=1e-3) == {"B"} and _min_gap(*ab) > 1e-3
        return _min_gap(*ab) < -1e-3

    return st.builds(
        lambda x, y, hax, hay, a, k, hbx, hby, turn, gap, slide, kinds: one_side_pair(
            (x, y), (hax, hay), a, k, (hbx, hby), turn, gap * min(hax, hay, hby), slide, kinds),
        rounded(-spread, spread), rounded(-spread, spread), rounded(0.3, 1.5), rounded(0.3, 1.5), angles, corners,
        rounded(0.2, 1.2), rounded(0.8, 2.0), rounded(-0.35, 0.35), gaps, rounded(-0.3, 0.3),
        st.tuples(box_kinds, box_kinds),
    ).filter(in_category)


def corner_circle_pairs(apart: bool):
    """A circle off a box's corner: apart (only the vertex axis separates) or overlapping."""
    reach = rounded(1.03, 1.2) if apart else rounded(0.2, 0.95)
    return st.builds(lambda x, y, hx, hy, a, k, turn, r, f, kind: corner_circle_pair((x, y), (hx, hy), a, k, turn, r, f, kind),
                     coordinates, coordinates, halves, halves, angles, corners, rounded(-0.15, 0.15), rounded(0.2, 1.5), reach,
                     box_kinds)


def inside_circle_pairs():
    """A circle whose centre is inside a box, the nearest face clear by 1 mm."""
    return st.builds(lambda x, y, hx, hy, a, u, v, r, kind: inside_circle_pair((x, y), (hx, hy), a, u, v, r, kind),
                     coordinates, coordinates, halves, halves, angles, rounded(-0.95, 0.95), rounded(-0.95, 0.95),
                     rounded(0.1, 1.5), box_kinds).filter(lambda cb: nearest_face_is_clear(*cb))


def face_face_pairs():
    """Two boxes face to face (parallel faces overlapping along a stretch of 5 cm or more)."""
    def build(x, y, hax, hay, a, side, hbx, hby, turns, depth, slide, kinds):
        return face_face_pair((x, y), (hax, hay), a, side, (hbx, hby), turns, depth * min(hax, hay, hbx, hby), slide,
                              kinds)

    def faces_overlap(ab) -> bool:
        a, b = ab
        # The contact faces must share a stretch of at least 5 cm along the face.
        n = face_normals(a)
        best = None
        for normal in n:
            lo_a, hi_a = interval(a, normal)
            lo_b, hi_b = interval(b, normal)
            depth = min(hi_a - lo_b, hi_b - lo_a)
            if best is None or depth < best[0]:
                best = (depth, normal)
        tangent = np.array([-best[1][1], best[1][0]])
        lo_a, hi_a = interval(a, tangent)
        lo_b, hi_b = interval(b, tangent)
        return min(hi_a, hi_b) - max(lo_a, lo_b) > 0.05

    return st.builds(build, coordinates, coordinates, halves, halves, angles, sides, halves, halves, st.integers(0, 3),
                     rounded(0.02, 0.3), rounded(-1.5, 1.5), st.tuples(box_kinds, box_kinds)).filter(faces_overlap)


# Moving shapes ----------------------------------------------------------------------------------
def translated(shape: dict, offset) -> dict:
    """The same plain shape moved by ``offset`` (m)."""
    d = np.asarray(offset, dtype=float)
    kind = shape["$shape"]
    if kind == "Circle":
        return plain.circle(np.asarray(shape["center"], dtype=float) + d, shape["radius"])
    if kind == "OBB":
        return plain.obb(np.asarray(shape["center"], dtype=float) + d, shape["half_extents"], shape["angle"])
    if kind == "AABB":
        return plain.aabb(np.asarray(shape["min_corner"], dtype=float) + d, np.asarray(shape["max_corner"], dtype=float) + d)
    return plain.polygon(np.asarray(shape["vertices"], dtype=float) + d)


def far_pairs(rng: np.random.Generator, count: int, offset, make) -> list[tuple]:
    """``count`` pairs made by ``make(rng)`` and moved by ``offset`` (m)."""
    return [tuple(translated(s, offset) for s in make(rng)) for _ in range(count)]


def random_aligned_boxes(rng: np.random.Generator, spread: float = 1.2, kinds=BOX_KINDS) -> tuple:
    """Two boxes at angle 0 (as AABB, OBB or ConvexPolygon) near the origin (m): their
    axes are x and y, on which boxes far from the origin project all to one sign."""
    return tuple(box(rng.uniform(-spread, spread, 2), rng.uniform(0.2, 1.0, 2), 0.0, kinds[rng.integers(len(kinds))])
                 for _ in range(2))
