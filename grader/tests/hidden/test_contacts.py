"""Contacts, hidden side: expected contacts from the reference engine.

A random pair is used only when its contact is not a free choice: the reference gives
the same contact for (A, B) as for (B, A) flipped (so the 2 % preference for A's
reference face does not decide it), and pymunk does not find the pair within 1e-7 m
of touching.  Every returned field is compared
(:func:`grader.oracles.narrowphase_answers.contact_problem`), the feature ids too where
the docstrings fix them: the reference's ids, except for two circles (no ids promised),
AABBs touching at a corner (collide_aabb_aabb's id there is not collide_polygon_polygon's)
and shapes of zero size (two vertices at the same place: either one names the point).

The margin: pairs just apart are clipped as the soft step clips them (the reference's
choice of face, the student's reference_face_manifold with the margin), and a crate
lands on the ground in the reference's world stepped in the trusted process, the soft
step calling the student's reference_face_manifold through the sandbox for every pair
it clips (``test_landing_crate``).
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest

import solutions.shapes
from solutions.body import Body
from solutions.narrowphase.aabb_aabb import collide_aabb_aabb
from solutions.narrowphase.dispatch import collide
from solutions.narrowphase.polygon_polygon import (polygon_faces, reference_face_candidates,
                                                   reference_face_manifold, tolerance_scale)
from solutions.narrowphase import speculative
from solutions.narrowphase.speculative import SPECULATIVE_MARGIN
from solutions.world import World, WorldSettings

from grader.sandbox import codec
from grader.harness.compare import as_number, as_vector, show
from grader.harness.credit import check_cases, fail
from grader.oracles import narrowphase_cases as cases
from grader.oracles import plain
from grader.oracles import random_cases as rc
from grader.harness.compare import call_text
from grader.oracles.narrowphase_answers import contact_problem, pair_figure, without_feature_ids
from grader.oracles.pymunk_geometry import definite_overlap
from grader.tests.public.test_contacts import manifold_problem

AABBS = "narrowphase.aabb_aabb"
CIRCLES = "narrowphase.circle_circle"
CIRCLE_POLYGON = "narrowphase.circle_polygon"
POLYGONS = "narrowphase.polygon_polygon"
MANIFOLD = "reference_face_manifold"
FUNCTIONS = {("Circle", "Circle"): (CIRCLES, "collide_circle_circle"),
             ("Circle", "polygon"): (CIRCLE_POLYGON, "collide_circle_polygon"),
             ("polygon", "polygon"): (POLYGONS, "collide_polygon_polygon")}


def reference(shape: dict):
    return codec.decode_shape(shape, solutions.shapes)


def reference_contact(a: dict, b: dict, routine=collide, ids: bool = True) -> dict | None:
    """The reference's contact as plain data, with its feature ids where the docstrings
    fix them (``ids`` and not two circles or a single point between two AABBs)."""
    contact = codec.encode_contact(routine(reference(a), reference(b)))
    kinds = {a[codec.SHAPE_TAG], b[codec.SHAPE_TAG]}
    if not ids or kinds == {"Circle"} or (contact is not None and kinds == {"AABB"} and len(contact["points"]) < 2):
        return without_feature_ids(contact)
    return contact


def same(c1: dict | None, c2: dict | None) -> bool:
    """Same geometry (the feature ids of (B, A) name the other shape's features)."""
    if c1 is None or c2 is None:
        return c1 is None and c2 is None
    return contact_problem(without_feature_ids(c1), without_feature_ids(c2), atol=1e-9) is None


def defined_reference_contact(a: dict, b: dict):
    """The reference contact, or False when the pair is near touching or the contact
    depends on the order of A and B (a free choice of the method)."""
    if definite_overlap(a, b) is None:
        return False
    want = reference_contact(a, b)
    back = reference_contact(b, a)
    if back is not None:
        back = dict(back, normal=[0.0 - v for v in back["normal"]])
    return want if same(want, back) else False


def check_contacts(student, module: str, function: str, batch: list[tuple], label: str) -> None:
    answers = student.call_many(module, function, [(a, b) for a, b, _, _ in batch])

    def problem_of(case):
        (a, b, want, note), got = case
        problem = contact_problem(got, want)
        return None if problem is None else f"{problem} [{note}]"

    check_cases(zip(batch, answers), problem_of, label, category=lambda case: case[0][3],
                describe=lambda case: call_text(function, case[0][0], case[0][1]),
                figure_of=lambda case: pair_figure(case[0][0], case[0][1], f"{function}: {case[0][3]}",
                                                   case[0][2], case[1]))


@pytest.mark.points(1)
@pytest.mark.visibility("after_published")
def test_aabb_aabb(student):
    """Contact between two AABBs"""
    rng = np.random.default_rng(405)

    def box(spread=1.0):
        return plain.aabb_from_center(rng.uniform(-spread, spread, 2), rng.uniform(0.3, 1, 2))

    pairs = [(box(), box()) for _ in range(60)]
    pairs += [(cases.translated(box(), (-20, -15)), cases.translated(box(), (-20, -15))) for _ in range(15)]
    pairs += [(cases.translated(box(), (30, 12)), cases.translated(box(), (30, 12))) for _ in range(15)]
    batch = [(a, b, reference_contact(a, b, collide_aabb_aabb), "axis-aligned boxes") for a, b in pairs
             if definite_overlap(a, b) is not None]
    # Touching exactly: along a stretch (two points) and corner to corner (one point, as
    # the docstring says), on every side of A.
    for k in range(12):
        a, b, _ = cases.random_touching_boxes(rng, corner=k % 3 == 0, kinds=("aabb", "aabb"))
        batch.append((a, b, reference_contact(a, b, collide_aabb_aabb), "touching exactly: depth 0"))
    if not (any(c[2] is None for c in batch) and any(c[2] is not None and len(c[2]["points"]) == 1 for c in batch)):
        raise RuntimeError("the AABB cases must include apart boxes and corners touching (a problem of the test)")
    check_contacts(student, AABBS, "collide_aabb_aabb", batch, "axis-aligned boxes")


def random_shape(rng, kind: str, spread: float = 1.2) -> dict:
    if kind == "circle":
        return rc.random_circle(rng, spread)
    if kind == "obb":
        return rc.random_obb(rng, spread)
    if kind == "aabb":
        return plain.aabb_from_center(rng.uniform(-spread, spread, 2), rng.uniform(0.2, 1.5, 2))
    return rc.random_polygon(rng, rng.uniform(-spread, spread, 2), float(rng.uniform(0.3, 1.5)))


@lru_cache(maxsize=1)
def random_batches() -> dict:
    """(module, function) -> [(A, B, expected contact, note)]: the same for every
    submission, so built (with the reference's answers) once per grading process."""
    rng = np.random.default_rng(406)
    offsets = [(0, 0), (-30, -20), (25, 40), (-80, 60)]
    kinds = {("Circle", "Circle"): [("circle", "circle")],
             ("Circle", "polygon"): [("circle", "obb"), ("circle", "aabb"), ("circle", "poly")],
             ("polygon", "polygon"): [("obb", "obb"), ("obb", "poly"), ("poly", "poly"), ("aabb", "obb")]}
    out = {}
    for group, pairs_of in kinds.items():
        module, function = FUNCTIONS[group]
        pairs = [(cases.translated(random_shape(rng, ka), offset), cases.translated(random_shape(rng, kb), offset))
                 for ka, kb in pairs_of for offset in offsets for _ in range(40)]
        if group == ("Circle", "polygon"):
            pairs += [cases.random_inside_circle(rng, offset=offsets[k % 4]) for k in range(40)]
            pairs += [cases.random_corner_circle(rng, apart=False, offset=offsets[k % 4]) for k in range(40)]
        if group == ("polygon", "polygon"):
            pairs += [cases.random_face_face(rng, offset=offsets[k % 4]) for k in range(60)]
        out[(module, function)] = [(a, b, want, "random pair") for a, b in pairs
                                   for want in [defined_reference_contact(a, b)] if want is not False]
    return out


@lru_cache(maxsize=1)
def near_manifolds(count: int = 240) -> list[tuple]:
    """Boxes face to face moved apart by 1 to 18 mm, less than the soft step's margin (2 cm),
    and the clipping the soft step asks of them: (A, B, the arguments of
    reference_face_manifold for the reference face the reference chooses, with the margin,
    the reference's answer as [(point, depth, feature id)]); every point is kept with a
    negative depth."""
    rng = np.random.default_rng(407)
    offsets = [(0, 0), (-30, -20), (25, 40), (-80, 60)]
    out = []
    for k in range(count):
        a, b = cases.random_face_face(rng, offset=offsets[k % len(offsets)])
        gap = float(rng.uniform(0.001, 0.018))
        contact = collide(reference(a), reference(b))
        if contact is None:
            continue
        b = cases.translated(b, (contact.depth + gap) * contact.normal)
        polygon_a, polygon_b = polygon_faces(reference(a)), polygon_faces(reference(b))
        candidates = reference_face_candidates(polygon_a, polygon_b, SPECULATIVE_MARGIN)
        if not candidates:
            continue
        ref_name, _, face, (ref_vertices, ref_normals, ref_faces), incident = candidates[0]
        normal = ref_normals[int(np.flatnonzero(ref_faces == face)[0])]
        args = (ref_vertices, normal, face, *incident, ref_name, tolerance_scale(polygon_a[0], polygon_b[0]),
                SPECULATIVE_MARGIN)
        points, depths, ids = reference_face_manifold(*args)
        if points:
            out.append((a, b, args, [(tuple(p.tolist()), d, i) for p, d, i in zip(points, depths, ids)]))
    return out


@pytest.mark.points(2)
@pytest.mark.partial_credit
@pytest.mark.visibility("after_due_date")
def test_random_against_reference(student):
    """Contacts: many random pairs of every kind, near and far from the origin, and pairs just apart (the margin)"""
    everything = []
    for (module, function), batch in random_batches().items():
        answers = student.call_many(module, function, [(a, b) for a, b, _, _ in batch])
        everything += [(function, case, got) for case, got in zip(batch, answers)]
    near = near_manifolds()
    answers = student.call_many(POLYGONS, "reference_face_manifold", [args for _, _, args, _ in near])
    everything += [(MANIFOLD, case, got) for case, got in zip(near, answers)]

    def problem_of(item):
        function, case, got = item
        if function != MANIFOLD:
            return contact_problem(got, case[2])
        problem = manifold_problem(got, case[3])
        return None if problem is None else (f"{problem} [shapes apart by less than the soft step's margin, "
                                             f"{SPECULATIVE_MARGIN:g} m: each point is kept, its depth negative]")

    def describe(item):
        function, case, _ = item
        if function != MANIFOLD:
            return call_text(function, case[0], case[1])
        return (f"reference_face_manifold(..., ref_name={case[2][6]!r}, margin={case[2][8]:g}) as the soft step "
                f"calls it for the shapes {call_text('', case[0], case[1])}")

    check_cases(everything, problem_of, "random pairs of every kind", category=lambda item: item[0],
                describe=describe,
                figure_of=lambda item: pair_figure(item[1][0], item[1][1], f"{item[0]}: random pair",
                                                   None if item[0] == MANIFOLD else item[1][2],
                                                   None if item[0] == MANIFOLD else item[2]))


@pytest.mark.points(1)
@pytest.mark.visibility("after_due_date")
def test_degenerate_shapes(student):
    """Contacts: shapes of zero size (points, segments) and coincident centres"""
    point = lambda x, y: plain.circle((x, y), 0.0)  # noqa: E731
    segment = plain.obb((1, 1), (1.5, 0.0), 0.6)
    groups = {
        (CIRCLES, "collide_circle_circle"): [(plain.circle((0, 0), 1.0), point(0.5, 0.0)),
                                             (point(-2, 3), plain.circle((-2, 3.5), 1.0))],
        (CIRCLE_POLYGON, "collide_circle_polygon"): [
            (point(0.5, 0.25), plain.aabb((0, 0), (1, 1))), (plain.circle((1, 1.2), 0.3), segment),
            (plain.circle((1.25, 0.5), 0.5), plain.aabb((0, 0), (1, 1))), (plain.circle((2, 2), 1.5), plain.aabb((0, 0), (1, 1)))],
        (POLYGONS, "collide_polygon_polygon"): [(segment, plain.obb((1, 1.1), (0.3, 0.3), 0.6)),
                                                (plain.obb((0, 0), (1, 1), 0.0), plain.obb((0.5, 0.9), (0.0, 0.2), 0.0)),
                                                # Two boxes of zero size at the origin: every coordinate
                                                # is 0, so is the roundoff allowance (scale 0).
                                                (plain.obb((0, 0), (0, 0), 0.0), plain.obb((0, 0), (0, 0), 0.0)),
                                                (plain.obb((0, 0), (0, 0), 0.0), plain.obb((0, 0), (0, 0), 0.7))],
    }
    everything = []
    for (module, function), pairs in groups.items():
        answers = student.call_many(module, function, pairs)
        everything += [(function, a, b, reference_contact(a, b, ids=False), got)
                       for (a, b), got in zip(pairs, answers)]
    check_cases(everything, lambda item: contact_problem(item[4], item[3]), "shapes of zero size",
                describe=lambda item: call_text(item[0], item[1], item[2]),
                figure_of=lambda item: pair_figure(item[1], item[2], f"{item[0]}: shapes of zero size", item[3],
                                                   item[4]))


#: Pairs where the reference face rule or the roundoff allowance decides, with a note.
#: Allowances scale with the largest vertex coordinate (KEEP_POINT_TOL, 1e-12 m per m):
#: about 1e-6 m for shapes 1e6 m from the origin.
WIDE_GROUND = plain.polygon([(-1e6, -1), (1e6, -1), (1e6, 0), (-1e6, 0)])
EDGE_CASES = [
    # B's best face better than A's by 1 % (within the 2 % that lets A keep the reference
    # role), but A's side planes cut off all of B's incident face: B's face is used.
    (plain.polygon([(0.56, -0.18), (-0.3, 0.42), (-0.64, 0.19), (-0.74, -0.35), (-0.53, -0.63), (-0.05, -0.82)]),
     plain.polygon([(0.47, -0.45), (0.27, -0.18), (-0.23, 0.41), (-1.72, -0.03), (-2.0, -1.17), (-0.9, -2.02)]),
     "A's manifold is empty: the reference face is B's"),
    # A crate 0.01 m into a ground 2e6 m wide, its bottom face tilted so that its right end
    # is 1e-7 m above the ground: within the allowance, a second point of depth 0.
    (WIDE_GROUND, plain.polygon([(-0.5, -0.01), (0.5, 1e-7), (0.5, 1), (-0.5, 1)]),
     "coordinates up to 1e6 m: a point 1e-7 m above the reference face is kept"),
    (plain.polygon([(-0.5, -0.01), (0.5, 1e-7), (0.5, 1), (-0.5, 1)]), WIDE_GROUND,
     "coordinates up to 1e6 m: a point 1e-7 m above the reference face is kept"),
    # A crate over the ground's right end x = 1e6: its deepest vertex, 0.01 m deep, 1e-5 m
    # beyond the end; its bottom face rises by 0.05 per m.  The side plane cuts 5e-7 m of
    # depth off the point (within the allowance, A keeps the role: B's bottom face is only
    # 0.13 % better); the contact's depth is still A's face's penetration, 0.01.
    (WIDE_GROUND, plain.polygon([(1e6 + 1e-5 - 1, 0.04), (1e6 + 1e-5, -0.01), (1e6 + 1e-5, 1), (1e6 + 1e-5 - 1, 1)]),
     "the deepest vertex cut off by less than the allowance: depth = the face's penetration"),
]


@pytest.mark.points(1)
@pytest.mark.visibility("after_due_date")
def test_reference_face_edge_cases(student):
    """Contacts: the reference face when A's manifold is empty, roundoff allowances 1e6 m from the origin"""
    batch = [(a, b, reference_contact(a, b), note) for a, b, note in EDGE_CASES]
    check_contacts(student, POLYGONS, "collide_polygon_polygon", batch, "reference face edge cases")


# A world stepped with the student's clipping ------------------------------------------------------
LANDING_STEPS, LANDING_DT, LANDING_SUBSTEPS = 90, 1 / 60, 4
#: Metres and radians: a manifold right to rounding keeps the crate within 1e-13 of the
#: reference's path (measured with noise of 1e-14 on every point and depth); one that drops
#: the speculative points or clamps their depths at 0 strays by 1 to 4 cm.
LANDING_TOLERANCE = 1e-6
LANDING = "a crate landing on the ground, stepped with your reference_face_manifold"


def landing_crate(steps: int = LANDING_STEPS) -> np.ndarray:
    """A 1 x 0.5 m crate dropped from 0.4 m, turned by 0.25 rad, onto static ground, both
    convex polygons (so the soft step clips them with reference_face_manifold and its
    margin), stepped by the reference's world with the soft step: (x, y, angle) per step."""
    ground = Body.polygon([(-4, -1), (4, -1), (4, 0), (-4, 0)], is_static=True, friction=0.6)
    crate = Body.polygon([(-0.5, -0.25), (0.5, -0.25), (0.5, 0.25), (-0.5, 0.25)], position=(0.3, 0.9), angle=0.25,
                         friction=0.6)
    world = World([ground, crate], WorldSettings(soft_step=True, substeps=LANDING_SUBSTEPS))
    path = []
    for _ in range(steps):
        world.step(LANDING_DT)
        path.append([float(crate.position[0]), float(crate.position[1]), float(crate.angle)])
    return np.array(path)


@lru_cache(maxsize=1)
def reference_landing() -> np.ndarray:
    return landing_crate()


def as_feature_id(value):
    """A feature id back from plain data: lists become tuples (the solver matches ids as keys)."""
    return tuple(as_feature_id(v) for v in value) if isinstance(value, list) else value


def student_clipping(student, calls: list):
    """reference_face_manifold for the soft step: the student's, called through the sandbox;
    each call's arguments and answer are appended to ``calls``."""
    def clipping(*args):
        got = student.call(POLYGONS, "reference_face_manifold", *args)
        calls.append((args, got))
        shaped = isinstance(got, list) and len(got) == 3 and all(isinstance(part, list) for part in got)
        points = [as_vector(p, 2) for p in got[0]] if shaped else []
        depths = [as_number(d) for d in got[1]] if shaped else []
        if not (shaped and len(got[0]) == len(got[1]) == len(got[2]) <= 2
                and all(v is not None and np.all(np.isfinite(v)) for v in points)
                and all(d is not None and np.isfinite(d) for d in depths)):
            fail(f"{LANDING}: reference_face_manifold must return (points, depths, feature_ids), at most two finite "
                 f"points and a finite depth each, got {show(got)[:300]}")
        try:
            ids = [as_feature_id(i) for i in got[2]]
            hash(tuple(ids))
        except TypeError:
            fail(f"{LANDING}: feature ids must be ints, strings or tuples of them, got {show(got[2])[:300]}")
        return points, [float(d) for d in depths], ids
    return clipping


def first_wrong_clipping(calls: list) -> str:
    """The first call of the student's clipping whose answer is not the reference's, said."""
    for args, got in calls:
        points, depths, ids = reference_face_manifold(*args)
        problem = manifold_problem(got, [(tuple(p.tolist()), d, i) for p, d, i in zip(points, depths, ids)])
        if problem is not None:
            return (f"the first clipping that differs: reference_face_manifold(ref_vertices="
                    f"{show(np.asarray(args[0]).tolist())}, ref_normal={show(np.asarray(args[1]).tolist())}, "
                    f"ref_face={args[2]}, inc_vertices={show(np.asarray(args[3]).tolist())}, ..., "
                    f"margin={args[8]:g}): {problem}")
    return "every clipping matched the reference's to 1e-9"


@pytest.mark.points(4)
@pytest.mark.visibility("after_due_date")
@pytest.mark.title("Contacts: a crate landing on the ground, stepped with your clipping (the soft step's margin)")
def test_landing_crate(student, monkeypatch):
    calls: list = []
    monkeypatch.setattr(speculative, "reference_face_manifold", student_clipping(student, calls))
    path = landing_crate()
    want = reference_landing()
    apart = np.abs(path - want).max(axis=1)
    if not np.all(np.isfinite(path)) or apart.max() > LANDING_TOLERANCE:
        step = int(np.argmax(~np.isfinite(path).all(axis=1) | (apart > LANDING_TOLERANCE)))
        fail(f"{LANDING}: at step {step + 1} of {LANDING_STEPS} the crate is at (x, y, angle) = "
             f"{show(path[step].tolist())} where the reference's clipping puts it at {show(want[step].tolist())} "
             f"(tolerance {LANDING_TOLERANCE:g}); after {LANDING_STEPS} steps {show(path[-1].tolist())} against "
             f"{show(want[-1].tolist())}. The soft step asks for every point up to {SPECULATIVE_MARGIN:g} m above the "
             f"reference face, with its negative depth; {first_wrong_clipping(calls)}")
