"""Sequential impulses: one contact point's normal and friction impulses, each with
accumulated clamping (solver/contact_point.py).

Expected answers come from the physics, written here and derived with sympy: the
inverse effective mass ``K = J M^-1 J^T`` of a row is derived from its Jacobian ``J``
over the six velocities ``(vx_A, vy_A, w_A, vx_B, vy_B, w_B)`` and checked against
the ``mass_normal`` / ``mass_tangent`` each case hands over; the velocity change of
an impulse ``P`` is ``M^-1 J^T P``; the unclamped impulse brings the row's velocity to
its target (normal) or to 0 (friction); clamping keeps the *accumulated* impulse in
``[lower, inf)`` (normal: ``lower`` is 0 for a contact, ``-inf`` for a joint row, which may
pull) or ``[-mu P, mu P]`` (friction, Coulomb).  Small cases are
worked out by hand in the comments.  Every returned value is compared: both bodies'
``(vx, vy, w)`` and the new accumulated impulse.

The prestep, targets, sweeps and step (solver/contact_sweeps.py) are compared with the
same expressions on cases, then graded by scenes of upright bodies
(:mod:`grader.oracles.upright_scenes`) stepped here, in the trusted process, with the
student's functions called through the sandbox: around ``prestep_point`` and
``sweep_contacts``, or by ``step_bodies`` alone.
"""
from __future__ import annotations

import copy
import math
from functools import lru_cache

import numpy as np
import pytest
import sympy as sp

from grader.harness.compare import number, show
from grader.harness.credit import check_cases, fail
from grader.oracles import upright_scenes as scenes

MODULE = "solver.contact_point"
FIELDS = ("nx", "ny", "rn_a", "rn_b", "rt_a", "rt_b", "ima", "imb", "iia", "iib", "mass_normal", "mass_tangent",
          "friction", "lower")
TOLERANCE = 1e-9


@lru_cache(maxsize=None)
def row_algebra():
    """Lambdified from sympy: ``K`` of a row along unit ``(dx, dy)`` with lever-arm terms
    ``ra = r_A x d``, ``rb = r_B x d``, and the row velocity ``J v``."""
    dx, dy, ra, rb, ima, imb, iia, iib = sp.symbols("dx dy ra rb ima imb iia iib", real=True)
    v = sp.Matrix(sp.symbols("vxa vya wa vxb vyb wb", real=True))
    jacobian = sp.Matrix([[-dx, -dy, -ra, dx, dy, rb]])
    inverse_mass = sp.diag(ima, ima, iia, imb, imb, iib)
    k = sp.simplify((jacobian * inverse_mass * jacobian.T)[0])
    response = inverse_mass * jacobian.T            # velocity change per unit impulse
    return (sp.lambdify((dx, dy, ra, rb, ima, imb, iia, iib), k, "math"),
            sp.lambdify((dx, dy, ra, rb, *v), (jacobian * v)[0], "math"),
            sp.lambdify((dx, dy, ra, rb, ima, imb, iia, iib), list(response), "math"))


def point_of(nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib, friction, lower=0.0) -> list[float]:
    """A contact point's 14 fields, its effective masses derived from the Jacobians."""
    k, _, _ = row_algebra()
    kn = k(nx, ny, rn_a, rn_b, ima, imb, iia, iib)
    kt = k(ny, -nx, rt_a, rt_b, ima, imb, iia, iib)
    return [nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib, 1 / kn if kn > 0 else 0.0,
            1 / kt if kt > 0 else 0.0, friction, lower]


def expected_normal(va, vb, point, total, target=0.0, mass_scale=1.0, impulse_scale=0.0):
    nx, ny, rn_a, rn_b, _, _, ima, imb, iia, iib, mass_normal, _, _, lower = point
    _, row_velocity, response = row_algebra()
    vn = row_velocity(nx, ny, rn_a, rn_b, *va, *vb)
    new_total = max(total + mass_normal * mass_scale * (target - vn) - impulse_scale * total, lower)
    change = new_total - total
    dv = [change * r for r in response(nx, ny, rn_a, rn_b, ima, imb, iia, iib)]
    return [list(np.add(va, dv[:3])), list(np.add(vb, dv[3:])), new_total]


def expected_friction(va, vb, point, normal_total, total):
    nx, ny, _, _, rt_a, rt_b, ima, imb, iia, iib, _, mass_tangent, mu, _ = point
    _, row_velocity, response = row_algebra()
    vt = row_velocity(ny, -nx, rt_a, rt_b, *va, *vb)
    bound = mu * normal_total
    new_total = min(max(total - mass_tangent * vt, -bound), bound)
    change = new_total - total
    dv = [change * r for r in response(ny, -nx, rt_a, rt_b, ima, imb, iia, iib)]
    return [list(np.add(va, dv[:3])), list(np.add(vb, dv[3:])), new_total]


def answer_problem(got, want, function: str) -> str | None:
    if not isinstance(got, list) or len(got) != 3 or not all(isinstance(v, list) and len(v) == 3 for v in got[:2]):
        return f"{function} must return ((vx_A, vy_A, w_A), (vx_B, vy_B, w_B), accumulated impulse), got {show(got)}"
    for body, got_v, want_v in (("A", got[0], want[0]), ("B", got[1], want[1])):
        for name, g, w in zip(("vx", "vy", "w"), got_v, want_v):
            problem = number(f"{name} of {body}", g, w, rtol=TOLERANCE, atol=TOLERANCE)
            if problem:
                return problem
    return number("the new accumulated impulse", got[2], want[2], rtol=TOLERANCE, atol=TOLERANCE)


def describe(function: str, case) -> str:
    args = case[0]
    point = dict(zip(FIELDS, args[2]))
    others = ", ".join(show(a) for a in args[3:])
    return f"{function}(velocity_a={show(args[0])}, velocity_b={show(args[1])}, point={show(point)}, {others})"


def check(student, function: str, cases: list[tuple], expect, label: str) -> None:
    answers = student.call_many(MODULE, function, [list(args) for args, _ in cases])

    def problem_of(case_answer) -> str | None:
        (args, note), got = case_answer
        problem = answer_problem(got, expect(*args), function)
        return None if problem is None else f"{problem} [{note}]"

    check_cases(list(zip(cases, answers)), problem_of, label, describe=lambda ca: describe(function, ca[0]),
                category=lambda ca: ca[0][1])


# Hand-worked points.  A disc of 1 kg, radius 0.5 m (1/I = 2 is used for a round
# number), resting on static ground A with the point straight below its centre:
# n = (0, 1), r_B = (0, -0.5): rn_B = r x n = 0, rt_B = r x t = 0.5 with t = (1, 0).
DISC = point_of(0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, 2.0, 0.3)
# A 1 kg box that cannot turn, on static ground, mu = 0.5.
BOX = point_of(0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.5)
# Two free bodies (1 kg and 2 kg) meeting along n = (1, 0) at a point off both centres:
# r_A = (0.5, 0.2) so rn_A = 0.5*0 - 0.2*1 = -0.2; r_B = (-0.5, 0.3): rn_B = -0.3.
OFF_CENTRE = point_of(1.0, 0.0, -0.2, -0.3, -0.5, 0.5, 1.0, 0.5, 3.0, 1.5, 0.8)
# A joint row (lower = -inf) between the same bodies: it may pull.
JOINT = point_of(1.0, 0.0, -0.2, -0.3, 0.0, 0.0, 1.0, 0.5, 3.0, 1.5, 0.0, -math.inf)

NORMAL_CASES = [
    # Falling at 2 m/s: an impulse of m v = 2 N s stops it (K = 1: rn_B = 0).
    (((0, 0, 0), (0, -2, 0), DISC, 0.0), "a disc falling on the ground"),
    # Already moving apart, nothing accumulated: no impulse (a contact never pulls).
    (((0, 0, 0), (0, 1.5, 0), DISC, 0.0), "a separating contact"),
    # Moving apart at 3 m/s with 2 N s accumulated: only 2 N s can be taken back.
    (((0, 0, 0), (0, 3, 0), DISC, 2.0), "taking back the whole accumulated impulse"),
    # Moving apart at 0.5 m/s with 2 N s accumulated: 0.5 N s is taken back, 1.5 stays.
    (((0, 0, 0), (0, 0.5, 0), DISC, 2.0), "taking back part of the accumulated impulse"),
    # Restitution target 1 m/s for a disc falling at 2 m/s: 3 N s.
    (((0, 0, 0), (0, -2, 0), DISC, 0.0, 1.0), "a restitution target"),
    # Soft scales: dP = 1 * 0.8 * (0 - (-2)) - 0.2 * 1 = 1.4, total 2.4.
    (((0, 0, 0), (0, -2, 0), DISC, 1.0, 0.0, 0.8, 0.2), "a soft contact"),
    # Two moving bodies, off-centre: every velocity component changes.
    (((1.0, 0.2, 0.5), (-1.0, 0.1, -0.4), OFF_CENTRE, 0.0), "two free bodies, off centre"),
    (((1.0, 0.2, 0.5), (-1.0, 0.1, -0.4), OFF_CENTRE, 0.3), "two free bodies, warm started"),
    # A joint row separating: it pulls (the total goes negative).
    (((-1.0, 0.0, 0.0), (1.0, 0.0, 0.0), JOINT, 0.0), "a joint row pulling"),
]

FRICTION_CASES = [
    # The box sliding at 3 m/s, P = 2 N s, mu = 0.5: the total stops at -1 N s (slips).
    (((0, 0, 0), (3, 0, 0), BOX, 2.0, 0.0), "sliding beyond the Coulomb bound"),
    # Sliding at 0.4 m/s: 0.4 N s stops it, within the bound of 1 N s (sticks).
    (((0, 0, 0), (0.4, 0, 0), BOX, 2.0, 0.0), "sticking within the bound"),
    # Sliding the other way: the bound is symmetric.
    (((0, 0, 0), (-3, 0, 0), BOX, 2.0, 0.0), "sliding the other way"),
    # Accumulated -0.9 N s, still sliding at 0.3 m/s: the total may only reach -1 N s.
    (((0, 0, 0), (0.3, 0, 0), BOX, 2.0, -0.9), "accumulated friction at the bound"),
    # The bound follows the normal total: it shrank to 0.5 N s, so -0.9 comes back to -0.25.
    (((0, 0, 0), (0.0, 0, 0), BOX, 0.5, -0.9), "a normal total that shrank"),
    # No normal impulse, no friction.
    (((0, 0, 0), (3, 0, 0), BOX, 0.0, 0.0), "no normal impulse"),
    # The disc spinning on the spot: the contact point slides, friction stops the spin.
    (((0, 0, 0), (0, 0, 4.0), DISC, 5.0, 0.0), "a spinning disc"),
    (((1.0, 0.2, 0.5), (-1.0, 0.1, -0.4), OFF_CENTRE, 0.6, 0.0), "two free bodies, off centre"),
]


def random_cases(seed: int, count: int, friction: bool) -> list[tuple]:
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(count):
        angle = rng.uniform(0.0, 2 * math.pi)
        static_a = rng.random() < 0.3
        ima, iia = (0.0, 0.0) if static_a else (rng.uniform(0.1, 2.0), rng.uniform(0.2, 6.0))
        point = point_of(math.cos(angle), math.sin(angle), *rng.uniform(-0.8, 0.8, 4), ima, rng.uniform(0.1, 2.0),
                         iia, rng.uniform(0.2, 6.0), float(rng.uniform(0.0, 1.0)))
        va = [0.0, 0.0, 0.0] if static_a else [float(v) for v in rng.normal(0.0, 1.0, 3)]
        vb = [float(v) for v in rng.normal(0.0, 1.0, 3)]
        kind = "static A" if static_a else "two free bodies"
        if friction:
            cases.append(((va, vb, point, float(rng.uniform(0.0, 2.0)), float(rng.uniform(-0.5, 0.5))), kind))
        else:
            scales = (float(rng.uniform(-0.5, 0.5)), 1.0, 0.0) if rng.random() < 0.6 else (
                float(rng.uniform(-0.5, 0.5)), float(rng.uniform(0.2, 0.9)), float(rng.uniform(0.0, 0.3)))
            cases.append(((va, vb, point, float(rng.uniform(0.0, 1.0)), *scales), kind))
    return cases


def random_joint_rows(seed: int, count: int) -> list[tuple]:
    """Normal visits of random joint rows (``lower = -inf``, no friction): the accumulated
    impulse may go negative (the row pulls), as a distance joint's does."""
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(count):
        angle = rng.uniform(0.0, 2 * math.pi)
        ima, imb = rng.uniform(0.1, 2.0, 2)
        iia, iib = rng.uniform(0.2, 6.0, 2)
        point = point_of(math.cos(angle), math.sin(angle), *rng.uniform(-0.8, 0.8, 2), 0.0, 0.0, float(ima),
                         float(imb), float(iia), float(iib), 0.0, -math.inf)
        va, vb = ([float(v) for v in rng.normal(0.0, 1.0, 3)] for _ in range(2))
        scales = (float(rng.uniform(-0.5, 0.5)), 1.0, 0.0) if rng.random() < 0.6 else (
            float(rng.uniform(-0.5, 0.5)), float(rng.uniform(0.2, 0.9)), float(rng.uniform(0.0, 0.3)))
        cases.append(((va, vb, point, float(rng.uniform(-1.0, 1.0)), *scales), "a joint row (lower = -inf)"))
    return cases


@pytest.mark.points(2)
@pytest.mark.title("Sequential impulses, normal: hand-worked points (stop, separate, take back, restitution, soft, "
                   "joint)")
def test_normal_worked_examples(student):
    check(student, "apply_normal_impulse", NORMAL_CASES, expected_normal, "hand-worked normal visits")


@pytest.mark.points(2)
@pytest.mark.partial_credit
@pytest.mark.title("Sequential impulses, normal: random points, rigid and soft, contacts and joint rows")
def test_normal_random(student):
    check(student, "apply_normal_impulse", random_cases(801, 30, friction=False) + random_joint_rows(803, 15),
          expected_normal, "random normal visits")


@pytest.mark.points(2)
@pytest.mark.title("Sequential impulses, friction: hand-worked points (slip, stick, the Coulomb bound)")
def test_friction_worked_examples(student):
    check(student, "apply_friction_impulse", FRICTION_CASES, expected_friction, "hand-worked friction visits")


@pytest.mark.points(2)
@pytest.mark.partial_credit
@pytest.mark.title("Sequential impulses, friction: random points")
def test_friction_random(student):
    check(student, "apply_friction_impulse", random_cases(802, 30, friction=True), expected_friction,
          "random friction visits")


@pytest.mark.points(1)
@pytest.mark.title("Sequential impulses: many visits converge on a resting box's two corners")
def test_visits_converge(student):
    """A 1 kg, 1 m box on static ground after one step of gravity at 60 Hz, its two
    corner points visited in turn: the accumulated impulses converge to m g h / 2 each
    and the box comes to rest (the answer of the 2x2 complementarity problem)."""
    h, g = 1 / 60, 9.81
    corners = [point_of(0.0, 1.0, 0.0, r, 0.0, 0.5, 0.0, 1.0, 0.0, 6.0, 0.5) for r in (-0.5, 0.5)]
    velocity_a, velocity_b = [0.0, 0.0, 0.0], [0.0, -g * h, 0.0]
    totals = [0.0, 0.0]
    for sweep in range(60):
        for k, point in enumerate(corners):
            answer = student.call(MODULE, "apply_normal_impulse", velocity_a, velocity_b, point, totals[k])
            problem = answer_problem(answer, expected_normal(velocity_a, velocity_b, point, totals[k]),
                                     "apply_normal_impulse")
            assert problem is None, (f"sweep {sweep}, corner {k}: {problem} "
                                     f"[{describe('apply_normal_impulse', ((velocity_a, velocity_b, point, totals[k]), ''))}]")
            velocity_a, velocity_b, totals[k] = answer
    assert abs(totals[0] - g * h / 2) < 1e-9 and abs(totals[1] - g * h / 2) < 1e-9, \
        f"after 60 sweeps the corners carry {totals} N s, not m g h / 2 = {g * h / 2:.6f} N s each"
    assert max(abs(v) for v in velocity_b) < 1e-9, f"the box still moves: {velocity_b}"


# The prestep and the sweeps (solver/contact_sweeps.py) ----------------------------------
SWEEPS = "solver.contact_sweeps"
PRESTEP_FIELDS = ("point", "normal", "centre_a", "centre_b", "ima", "imb", "iia", "iib", "friction")


def expected_prestep(point, normal, centre_a, centre_b, ima, imb, iia, iib, friction):
    """The 14 fields: lever arms r = p - centre crossed with n and t = (ny, -nx), the
    effective masses from the Jacobians (sympy, :func:`point_of`), ``lower = 0``."""
    nx, ny = normal
    arms = [(point[0] - c[0], point[1] - c[1]) for c in (centre_a, centre_b)]
    rn = [rx * ny - ry * nx for rx, ry in arms]
    rt = [rx * -nx - ry * ny for rx, ry in arms]
    return point_of(nx, ny, rn[0], rn[1], rt[0], rt[1], ima, imb, iia, iib, friction)


def prestep_cases(seed: int, count: int) -> list[tuple]:
    # A disc of radius 0.5 m (1 kg, 1/I = 8) on static ground: m_n = 1 kg, m_t = 1/3 kg.
    cases = [(([0.0, 0.0], [0.0, 1.0], [0.0, -0.5], [0.0, 0.5], 0.0, 1.0, 0.0, 8.0, 0.6), "a disc on the ground"),
             # A box corner off centre: the normal lever arm spins it (rn_B = -0.5 m).
             (([-0.5, 0.0], [0.0, 1.0], [0.0, -0.5], [0.0, 0.5], 0.0, 1.0, 0.0, 6.0, 0.5), "a box's corner"),
             # Two static bodies: nothing moves, both effective masses are 0.
             (([0.0, 0.0], [1.0, 0.0], [-1.0, 0.0], [1.0, 0.0], 0.0, 0.0, 0.0, 0.0, 0.5), "two static bodies"),
             # A body that cannot turn (1/I = 0): the lever arms count for nothing.
             (([0.3, 0.1], [0.6, 0.8], [0.0, 0.0], [1.0, 1.0], 0.5, 0.25, 0.0, 0.0, 0.2), "no rotation")]
    rng = np.random.default_rng(seed)
    for _ in range(count):
        angle = rng.uniform(0.0, 2 * math.pi)
        static_a = rng.random() < 0.3
        ima, iia = (0.0, 0.0) if static_a else (float(rng.uniform(0.1, 2.0)), float(rng.uniform(0.2, 6.0)))
        centres = [[float(x) for x in rng.uniform(-2.0, 2.0, 2)] for _ in range(2)]
        cases.append(((([float(x) for x in rng.uniform(-2.0, 2.0, 2)]), [math.cos(angle), math.sin(angle)],
                       *centres, ima, float(rng.uniform(0.1, 2.0)), iia, float(rng.uniform(0.2, 6.0)),
                       float(rng.uniform(0.0, 1.0))), "static A" if static_a else "two free bodies"))
    return cases


def point_problem(got, want) -> str | None:
    if not isinstance(got, list) or len(got) != len(FIELDS):
        return f"prestep_point must return a ContactPoint (its {len(FIELDS)} fields), got {show(got)}"
    for name, g, w in zip(FIELDS, got, want):
        problem = number(name, g, w, rtol=TOLERANCE, atol=TOLERANCE)
        if problem:
            return problem
    return None


def describe_call(function: str, args, names) -> str:
    return f"{function}(" + ", ".join(f"{n}={show(a)}" for n, a in zip(names, args)) + ")"


@pytest.mark.points(2)
@pytest.mark.partial_credit
@pytest.mark.title("Prestep: a contact point's lever arms and effective masses (hand-worked and random points)")
def test_prestep_point(student):
    cases = prestep_cases(811, 30)
    answers = student.call_many(SWEEPS, "prestep_point", [list(args) for args, _ in cases])

    def problem_of(case_answer):
        (args, note), got = case_answer
        problem = point_problem(got, expected_prestep(*args))
        return None if problem is None else f"{problem} [{note}]"

    check_cases(list(zip(cases, answers)), problem_of, "prestep points",
                describe=lambda ca: describe_call("prestep_point", ca[0][0], PRESTEP_FIELDS),
                category=lambda ca: ca[0][1])


TARGET_FIELDS = ("normal_velocity", "restitution", "depth", "dt", "restitution_threshold", "bias_factor", "slop",
                 "max_push")


def expected_target(normal_velocity, restitution, depth, dt, threshold, bias_factor, slop, max_push):
    """The larger of the bounce (only above the threshold) and the capped Baumgarte push."""
    return scenes.target_speed(normal_velocity, restitution, depth,
                               scenes.SceneSettings(dt=dt, restitution_threshold=threshold, bias_factor=bias_factor,
                                                    slop=slop, max_push=max_push))


TARGET_CASES = [
    ((-4.0, 0.5, 0.0, 1 / 60, 1.0, 0.0, 0.005, 3.0), "a fast impact bounces at e times its speed"),
    ((-0.5, 0.5, 0.0, 1 / 60, 1.0, 0.0, 0.005, 3.0), "a slow impact (a resting contact) does not bounce"),
    ((-0.5, 0.5, 0.0, 1 / 60, 0.2, 0.0, 0.005, 3.0), "a lower threshold lets it bounce"),
    ((-1.0, 0.5, 0.0, 1 / 60, 1.0, 0.0, 0.005, 3.0), "closing exactly at the threshold: no bounce"),
    ((2.0, 0.5, 0.0, 1 / 60, 1.0, 0.0, 0.005, 3.0), "a separating point: no bounce"),
    ((0.0, 0.0, 0.105, 0.01, 1.0, 0.2, 0.005, 3.0), "an overlap is pushed out"),
    ((0.0, 0.0, 0.004, 0.01, 1.0, 0.2, 0.005, 3.0), "an overlap within the slop is left"),
    ((0.0, 0.0, 0.105, 0.01, 1.0, 0.2, 0.005, 1.0), "the push is capped"),
    ((0.0, 0.0, 0.105, 0.01, 1.0, 0.0, 0.005, 3.0), "no push without a bias factor"),
    ((-3.0, 0.5, 0.105, 0.01, 1.0, 0.2, 0.005, 3.0), "bounce and push: the larger"),
    ((-3.0, 0.8, 0.105, 0.01, 1.0, 0.2, 0.005, 3.0), "bounce and push: the larger (the bounce)"),
]


def random_targets(seed: int, count: int) -> list[tuple]:
    rng = np.random.default_rng(seed)
    return [((float(rng.uniform(-5.0, 2.0)), float(rng.uniform(0.0, 1.0)), float(rng.uniform(-0.01, 0.2)),
              float(rng.choice([1 / 60, 1 / 240, 0.01])), float(rng.uniform(0.0, 2.0)), float(rng.uniform(0.0, 0.5)),
              float(rng.uniform(0.0, 0.02)), float(rng.uniform(0.5, 5.0))), "random") for _ in range(count)]


@pytest.mark.points(2)
@pytest.mark.partial_credit
@pytest.mark.title("Prestep: the target velocity (restitution threshold, Baumgarte push)")
def test_contact_target(student):
    cases = TARGET_CASES + random_targets(812, 40)
    answers = student.call_many(SWEEPS, "contact_target", [list(args) for args, _ in cases])

    def problem_of(case_answer):
        (args, note), got = case_answer
        problem = number("the target (m/s)", got, expected_target(*args), rtol=TOLERANCE, atol=TOLERANCE)
        return None if problem is None else f"{problem} [{note}]"

    check_cases(list(zip(cases, answers)), problem_of, "contact targets",
                describe=lambda ca: describe_call("contact_target", ca[0][0], TARGET_FIELDS),
                category=lambda ca: ca[0][1])


def expected_sweeps(velocity, manifolds, settings):
    """Every point's target from the velocities as given (before the warm start), the
    warm start, then per sweep and manifold every friction visit, then every normal
    visit (the visits of this module's expected_friction / expected_normal)."""
    dt, iterations, threshold, bias_factor, slop, max_push = settings
    constants = scenes.SceneSettings(dt=dt, restitution_threshold=threshold, bias_factor=bias_factor, slop=slop,
                                     max_push=max_push)
    velocity = [list(v) for v in velocity]
    normal = [list(m[5]) for m in manifolds]
    tangent = [list(m[6]) for m in manifolds]
    _, row_velocity, response = row_algebra()
    targets = [[scenes.target_speed(row_velocity(*point[:4], *velocity[a], *velocity[b]), restitution, depth,
                                    constants) for point, depth in zip(points, depths)]
               for a, b, points, restitution, depths, _, _ in manifolds]
    for m, (a, b, points, *_) in enumerate(manifolds):
        for k, point in enumerate(points):
            nx, ny, rn_a, rn_b, rt_a, rt_b, ima, imb, iia, iib = point[:10]
            dn = response(nx, ny, rn_a, rn_b, ima, imb, iia, iib)
            dt_ = response(ny, -nx, rt_a, rt_b, ima, imb, iia, iib)
            change = [normal[m][k] * x + tangent[m][k] * y for x, y in zip(dn, dt_)]
            velocity[a] = list(np.add(velocity[a], change[:3]))
            velocity[b] = list(np.add(velocity[b], change[3:]))
    for _ in range(iterations):
        for m, (a, b, points, *_) in enumerate(manifolds):
            for k, point in enumerate(points):
                velocity[a], velocity[b], tangent[m][k] = expected_friction(velocity[a], velocity[b], point,
                                                                            normal[m][k], tangent[m][k])
            for k, point in enumerate(points):
                velocity[a], velocity[b], normal[m][k] = expected_normal(velocity[a], velocity[b], point,
                                                                         normal[m][k], targets[m][k])
    return velocity, normal, tangent


def random_sweep_cases(seed: int, count: int) -> list[tuple]:
    """Three bodies (0 static), two or three manifolds of one or two points each; bounces
    (thresholds from 0.2 m/s) and, in every other case, pushes out of the overlaps."""
    rng = np.random.default_rng(seed)
    cases = []
    for index in range(count):
        velocity = [[0.0, 0.0, 0.0]] + [[float(v) for v in rng.normal(0.0, 1.0, 3)] for _ in range(2)]
        inverse = [(0.0, 0.0)] + [(float(rng.uniform(0.2, 2.0)), float(rng.uniform(0.5, 6.0))) for _ in range(2)]
        manifolds = []
        for a, b in [(0, 1), (1, 2), (0, 2)][:2 + index % 2]:
            angle = rng.uniform(0.0, 2 * math.pi)
            count_points = 1 + int(rng.random() < 0.6)
            points = [point_of(math.cos(angle), math.sin(angle), *[float(x) for x in rng.uniform(-0.6, 0.6, 4)],
                               inverse[a][0], inverse[b][0], inverse[a][1], inverse[b][1],
                               float(rng.uniform(0.0, 1.0))) for _ in range(count_points)]
            manifolds.append([a, b, points, float(rng.uniform(0.0, 1.0)),
                              [float(x) for x in rng.uniform(0.0, 0.05, count_points)],
                              [float(x) for x in rng.uniform(0.0, 0.3, count_points)],
                              [float(x) for x in rng.uniform(-0.1, 0.1, count_points)]])
        settings = [1 / 60, int(rng.integers(0, 5)), float(rng.uniform(0.2, 1.5)), 0.2 * (index % 2), 0.005, 3.0]
        cases.append(((velocity, manifolds, settings), "warm started, pushed" if index % 2 else "warm started"))
    return cases


def sweep_problem(got, want) -> str | None:
    if not (isinstance(got, list) and len(got) == 3 and isinstance(got[0], list) and len(got[0]) == len(want[0])):
        return f"sweep_contacts must return (velocities, normal totals, tangent totals), got {show(got)[:300]}"
    for i, (g, w) in enumerate(zip(got[0], want[0])):
        if not isinstance(g, list) or len(g) != 3:
            return f"the velocity of body {i} must be (vx, vy, w), got {show(g)}"
        for name, x, y in zip(("vx", "vy", "w"), g, w):
            problem = number(f"{name} of body {i}", x, y, rtol=1e-7, atol=1e-7)
            if problem:
                return problem
    for label, got_totals, want_totals in (("normal", got[1], want[1]), ("friction", got[2], want[2])):
        if not isinstance(got_totals, list) or len(got_totals) != len(want_totals):
            return f"the {label} totals must be one list per manifold, got {show(got_totals)[:200]}"
        for m, (g, w) in enumerate(zip(got_totals, want_totals)):
            if not isinstance(g, list) or len(g) != len(w):
                return f"manifold {m}: one accumulated {label} impulse per point expected, got {show(g)}"
            for k, (x, y) in enumerate(zip(g, w)):
                problem = number(f"manifold {m}, point {k}: the accumulated {label} impulse", x, y, rtol=1e-7,
                                 atol=1e-7)
                if problem:
                    return problem
    return None


@pytest.mark.points(2)
@pytest.mark.partial_credit
@pytest.mark.title("Sweeps: targets, warm start, then friction and normal visits manifold by manifold "
                   "(random manifolds)")
def test_sweep_contacts(student):
    # A disc falling at 2 m/s, remembering 2 N s: the warm start alone stops it.
    disc = point_of(0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 0.0, 1.0, 0.0, 8.0, 0.5)
    falling = [[0.0, 0.0, 0.0], [0.0, -2.0, 0.0]]

    def settings(iterations, threshold=1.0, bias_factor=0.0):
        return [1 / 60, iterations, threshold, bias_factor, 0.005, 3.0]

    cases = [((falling, [[0, 1, [disc], 0.0, [0.0], [2.0], [0.0]]], settings(0)), "warm start only"),
             ((falling, [[0, 1, [disc], 0.0, [0.0], [0.0], [0.0]]], settings(1)), "one sweep"),
             # e = 0.5 above the threshold: it leaves at 1 m/s, after one sweep as after two.
             ((falling, [[0, 1, [disc], 0.5, [0.0], [0.0], [0.0]]], settings(1)), "a bounce, one sweep"),
             ((falling, [[0, 1, [disc], 0.5, [0.0], [0.0], [0.0]]], settings(2)), "a bounce, two sweeps"),
             # 2 cm deep: pushed out at 0.2 x 0.015 m / h = 0.18 m/s.
             ((falling, [[0, 1, [disc], 0.0, [0.02], [0.0], [0.0]]], settings(3, bias_factor=0.2)), "a push"),
             (([[0.0, 0.0, 0.0], [1.0, -2.0, 0.0]], [[0, 1, [disc], 0.5, [0.0], [0.0], [0.3]]], settings(3)),
              "sliding, bouncing, warm started")] + random_sweep_cases(813, 25)
    answers = student.call_many(SWEEPS, "sweep_contacts", [list(args) for args, _ in cases])

    def problem_of(case_answer):
        (args, note), got = case_answer
        problem = sweep_problem(got, expected_sweeps(*args))
        return None if problem is None else f"{problem} [{note}]"

    check_cases(list(zip(cases, answers)), problem_of, "sweeps",
                describe=lambda ca: describe_call("sweep_contacts", ca[0][0], ("velocity", "manifolds",
                                                                               "settings")),
                category=lambda ca: ca[0][1])


# The step (step_bodies) ----------------------------------------------------------------
STEP_FIELDS = ("bodies", "pairs", "gravity", "settings")
POSE_NAMES = ("x", "y", "angle", "vx", "vy", "w")


def gravity_applied(bodies, gravity, dt) -> list[list[float]]:
    """Every body's velocity after gravity: bodies with mass (1/m > 0) only."""
    return [[vx + dt * gravity[0], vy + dt * gravity[1], w] if ima > 0.0 else [vx, vy, w]
            for _, _, _, vx, vy, w, ima, _ in bodies]


def moved_by(bodies, velocity, dt) -> list[list[float]]:
    return [[x + dt * v[0], y + dt * v[1], angle + dt * v[2], *v] for (x, y, angle, *_), v in zip(bodies, velocity)]


def expected_step(bodies, pairs, gravity, settings):
    """Gravity, the prestep of every point, the sweeps (targets first), then the positions
    moved with the velocities the sweeps leave (this module's expected_* functions)."""
    dt = settings[0]
    velocity = gravity_applied(bodies, gravity, dt)
    manifolds = [[a, b, [expected_prestep(point, normal, bodies[a][:2], bodies[b][:2], bodies[a][6], bodies[b][6],
                                          bodies[a][7], bodies[b][7], friction) for point in points],
                  restitution, depths, normal_total, tangent_total]
                 for a, b, normal, points, depths, friction, restitution, normal_total, tangent_total in pairs]
    velocity, normal, tangent = expected_sweeps(velocity, manifolds, settings)
    return moved_by(bodies, velocity, dt), normal, tangent


def step_problem(got, args) -> str | None:
    """What is wrong with ``got``, step_bodies' answer to ``args``; a body moved with the
    velocities before the sweeps is named as such."""
    bodies, pairs, gravity, settings = args
    want = expected_step(*args)
    if not (isinstance(got, list) and len(got) == 3 and isinstance(got[0], list) and len(got[0]) == len(bodies)
            and all(isinstance(row, list) and len(row) == 6 for row in got[0])):
        return (f"step_bodies must return ({len(bodies)} rows (x, y, angle, vx, vy, w), normal totals, tangent "
                f"totals), got {show(got)[:300]}")
    problem = sweep_problem([[row[3:] for row in got[0]], got[1], got[2]],
                            [[row[3:] for row in want[0]], want[1], want[2]])
    if problem:
        return f"after the sweeps: {problem}"
    unsolved = moved_by(bodies, gravity_applied(bodies, gravity, settings[0]), settings[0])
    for i, (row, wanted, early) in enumerate(zip(got[0], want[0], unsolved)):
        for name, x, y, z in list(zip(POSE_NAMES, row, wanted, early))[:3]:
            if number(f"{name} of body {i}", x, y, rtol=1e-7, atol=1e-7):
                hint = ("it moved with its velocity before the contacts were solved (after gravity only); a body "
                        "moves with the velocity the sweeps leave" if abs(x - z) <= 1e-9 * (1 + abs(z))
                        else "x, y and angle move by dt times the new vx, vy and w")
                return f"{name} of body {i} is {x:.9g}, {y:.9g} expected: {hint}"
    return None


def random_step_cases(seed: int, count: int) -> list[tuple]:
    """The static ground (body 0) and two or three bodies with mass, some that cannot
    turn, in one to three touching pairs of one or two points, warm started."""
    rng = np.random.default_rng(seed)
    cases = []
    for index in range(count):
        moving = 2 + index % 2
        bodies = [[0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]]
        for _ in range(moving):
            turns = rng.random() < 0.7
            bodies.append([*(float(x) for x in rng.uniform(-2.0, 2.0, 2)), float(rng.uniform(-1.0, 1.0)),
                           *(float(v) for v in rng.normal(0.0, 1.0, 3)), float(rng.uniform(0.2, 2.0)),
                           float(rng.uniform(0.5, 6.0)) if turns else 0.0])
            if not turns:
                bodies[-1][5] = 0.0
        pairs = []
        for a, b in [(0, 1), (1, 2), (0, 2), (2, 3)][:1 + index % 3 + (moving == 3)]:
            angle = float(rng.uniform(0.0, 2 * math.pi))
            count_points = 1 + int(rng.random() < 0.6)
            pairs.append([a, b, [math.cos(angle), math.sin(angle)],
                          [[float(x) for x in rng.uniform(-2.0, 2.0, 2)] for _ in range(count_points)],
                          [float(x) for x in rng.uniform(0.0, 0.05, count_points)], float(rng.uniform(0.0, 1.0)),
                          float(rng.uniform(0.0, 1.0)), [float(x) for x in rng.uniform(0.0, 0.3, count_points)],
                          [float(x) for x in rng.uniform(-0.1, 0.1, count_points)]])
        gravity = [0.0, -9.81] if index % 4 else [float(g) for g in rng.normal(0.0, 5.0, 2)]
        settings = [float(rng.choice([1 / 60, 1 / 120])), int(rng.integers(0, 5)), float(rng.uniform(0.2, 1.5)),
                    0.2 * (index % 2), 0.005, 3.0]
        cases.append(((bodies, pairs, gravity, settings), "random bodies and pairs"))
    return cases


#: The ground (body 0, static, its centre 1 m below its surface y = 0) and a 1 kg disc of
#: radius 0.5 m (1/I = 8) or a 1 kg box of 1 m that cannot turn, each on it.
GROUND = [0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
STEP = [1 / 60, 10, 1.0, 0.2, 0.005, 3.0]
STEP_CASES = [
    # Resting: gravity makes the disc close at g h = 0.1635 m/s, m g h stops it, it stays.
    (([GROUND, [0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 8.0]], [[0, 1, [0.0, 1.0], [[0.0, 0.0]], [0.0], 0.5, 0.0, [0.0],
                                                              [0.0]]], [0.0, -9.81], STEP), "a disc resting"),
    # Touching nothing: it falls at g h after the step, and has moved h g h down.
    (([GROUND, [0.0, 3.0, 0.0, 0.0, 0.0, 0.0, 1.0, 8.0]], [], [0.0, -9.81], STEP), "falling freely"),
    # The box resting on its two corners, warm started with m g h / 2 each: nothing moves.
    (([GROUND, [0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0]],
      [[0, 1, [0.0, 1.0], [[-0.5, 0.0], [0.5, 0.0]], [0.0, 0.0], 0.5, 0.0, [9.81 / 120, 9.81 / 120], [0.0, 0.0]]],
      [0.0, -9.81], STEP), "a box resting, warm started"),
    # Landing at 3 m/s with e = 0.5: it leaves at 1.5 m/s and rises by h 1.5 m/s.
    (([GROUND, [0.0, 0.5, 0.0, 0.0, -3.0 + 9.81 / 60, 0.0, 1.0, 8.0]],
      [[0, 1, [0.0, 1.0], [[0.0, 0.0]], [0.0], 0.5, 0.5, [0.0], [0.0]]], [0.0, -9.81], STEP), "a bounce"),
    # Sliding at 2 m/s, mu = 0.5: friction takes mu m g h off its speed.
    (([GROUND, [0.0, 0.5, 0.0, 2.0, 0.0, 0.0, 1.0, 0.0]],
      [[0, 1, [0.0, 1.0], [[-0.5, 0.0], [0.5, 0.0]], [0.0, 0.0], 0.5, 0.0, [0.0, 0.0], [0.0, 0.0]]],
      [0.0, -9.81], STEP), "a box sliding"),
]


@pytest.mark.points(2)
@pytest.mark.partial_credit
@pytest.mark.title("Step: gravity, prestep, sweeps, then positions moved with the solved velocities (hand-worked "
                   "and random bodies)")
def test_step_bodies(student):
    cases = STEP_CASES + random_step_cases(814, 25)
    answers = student.call_many(SWEEPS, "step_bodies", [list(args) for args, _ in cases])

    def problem_of(case_answer):
        (args, note), got = case_answer
        problem = step_problem(got, args)
        return None if problem is None else f"{problem} [{note}]"

    check_cases(list(zip(cases, answers)), problem_of, "steps",
                describe=lambda ca: describe_call("step_bodies", ca[0][0], STEP_FIELDS), category=lambda ca: ca[0][1])


def scene_calls(student, scene: str):
    """``call_many`` for :mod:`grader.oracles.upright_scenes`: the student's functions
    through the sandbox, their answers checked for shape before the scene uses them."""
    def call_many(name, cases):
        answers = student.call_many(SWEEPS, name, [list(case) for case in cases])
        try:
            if name == "prestep_point":
                ok = all(len(a) == len(FIELDS) and all(map(math.isfinite, a)) for a in answers)
            elif name == "contact_target":
                ok = all(math.isfinite(a) for a in answers)
            else:       # sweep_contacts: velocities; step_bodies: poses and velocities
                rows, normal, tangent = answers[0]
                width = 6 if name == "step_bodies" else 3
                ok = (len(rows) == len(cases[0][0]) and all(len(v) == width and all(map(math.isfinite, v))
                                                             for v in rows)
                      and len(normal) == len(tangent) == len(cases[0][1])
                      and all(all(map(math.isfinite, n)) for n in normal + tangent))
        except (TypeError, ValueError):
            ok = False
        if not ok:
            fail(f"{scene}: {name} returned {show(answers)[:300]}, not what its docstring says")
        return answers
    return call_many


@pytest.mark.points(2)
@pytest.mark.title("Scene: a stack of ten boxes carries the complementarity answer (10 sweeps, 1 s)")
def test_stack_loads(student):
    """Ten 1 kg boxes that cannot turn, stacked on the ground; contact k from the bottom
    carries the weight of the boxes above it, (10 - k) m g h per step."""
    scene = "the stack of ten boxes"
    boxes = [scenes.Upright(1.0, 0.5, 0.5, y=0.5 + k, friction=0.6, turns=False) for k in range(10)]
    settings, memory = scenes.SceneSettings(iterations=10, bias_factor=0.0), {}
    for _ in range(60):
        manifolds = scenes.step_scene(boxes, scene_calls(student, scene), settings, memory, stacked=True)
    loads = [sum(normal) for _, _, normal in manifolds]
    want = [(10 - k) * scenes.G * settings.dt for k in range(10)]
    worst = int(np.argmax([abs(g - w) / w for g, w in zip(loads, want)] + [0.0] * (10 - len(loads))))
    if len(loads) != 10 or abs(loads[worst] - want[worst]) > 1e-3 * want[worst]:
        fail(f"{scene} after 1 s: contact {worst} from the ground carries "
             f"{loads[worst] if worst < len(loads) else 0.0:.6g} N s a step, the weight of the {10 - worst} boxes "
             f"above it is {want[worst]:.6g} N s (all: {np.round(loads, 5).tolist()})")
    speed = max(abs(box.velocity[1]) for box in boxes)
    assert speed < 2e-3, f"{scene} after 1 s: a box still moves at {speed:.3g} m/s"


@pytest.mark.points(2)
@pytest.mark.title("Scene: warm started, the stack stands with 4 sweeps a step (cold, it sinks)")
def test_warm_started_stack(student):
    """With last step's impulses given back first, four sweeps a step hold the ten boxes:
    after 2 s none moves faster than 1 cm/s and the top one sank less than 10 cm.  Cold
    (no warm start) the same sweeps let the stack sink by metres."""
    scene = "the stack of ten boxes with 4 sweeps a step"
    boxes = [scenes.Upright(1.0, 0.5, 0.5, y=0.5 + k, friction=0.6, turns=False) for k in range(10)]
    settings, memory = scenes.SceneSettings(iterations=4, bias_factor=0.0), {}
    for _ in range(120):
        scenes.step_scene(boxes, scene_calls(student, scene), settings, memory, stacked=True)
    sunk = 9.5 - boxes[-1].y
    speed = max(abs(box.velocity[1]) for box in boxes)
    assert sunk < 0.1 and speed < 1e-2, (f"{scene} after 2 s: the top box sank {sunk:.3f} m and a box moves at "
                                         f"{speed:.3g} m/s (warm started, it sinks a few cm and rests)")


@pytest.mark.points(2)
@pytest.mark.title("Scene: a box sliding at 3 m/s stops after v^2 / (2 mu g) (friction)")
def test_sliding_box_stops(student):
    scene = "the box sliding at 3 m/s (mu = 0.5)"
    box = scenes.Upright(1.0, 0.5, 0.5, y=0.5, velocity=[3.0, 0.0, 0.0], friction=0.5)
    settings, memory = scenes.SceneSettings(), {}
    for _ in range(200):
        scenes.step_scene([box], scene_calls(student, scene), settings, memory)
    want = 3.0 ** 2 / (2 * 0.5 * scenes.G) - 3.0 * settings.dt / 2      # the stepped distance
    assert abs(box.x - want) < 0.01 * want and abs(box.velocity[0]) < 1e-6, (
        f"{scene}: it stopped after {box.x:.4f} m (v = {box.velocity[0]:.3g} m/s); Coulomb friction stops it "
        f"after {want:.4f} m")


@pytest.mark.points(2)
@pytest.mark.title("Scene: a ball kicked up off the ground rises v^2 / 2g (a contact never pulls), lands and bounces "
                   "at e v")
def test_kicked_ball_rises(student):
    """A ball (e = 0.5) resting on the ground kicked up at 4 m/s: it rises the stepped
    v^2 / 2g - v h / 2, lands at about 4 m/s and leaves at half of that, up to the
    height the exact stepped path (:func:`upright_scenes.vertical_paths`) reaches."""
    scene = "the ball kicked up at 4 m/s (e = 0.5)"
    ball = scenes.Upright(1.0, radius=0.5, y=0.5, velocity=[0.0, 4.0, 0.0], restitution=0.5)
    settings, memory, heights = scenes.SceneSettings(), {}, []
    exact = [0.5 - step[0][0] for step in scenes.vertical_paths([ball], settings, 80)]      # the centre's y (m)
    for _ in range(80):
        scenes.step_scene([ball], scene_calls(student, scene), settings, memory)
        heights.append(ball.y)
    landing = next(k for k in range(1, 80) if exact[k] < exact[k - 1] and exact[k + 1] > exact[k])
    want = 4.0 ** 2 / (2 * scenes.G) - 4.0 * settings.dt / 2
    top = max(heights[:landing])
    assert abs(top - 0.5 - want) < 1e-3, f"{scene}: it rose {top - 0.5:.4f} m, {want:.4f} m expected"
    rebound, want_rebound = max(heights[landing:]) - 0.5, max(exact[landing:]) - 0.5
    assert abs(rebound - want_rebound) < 1e-6, (
        f"{scene}: after landing at about 4 m/s it bounced {rebound:.4f} m high, {want_rebound:.4f} m expected "
        "(it leaves at e times its closing speed, measured before the sweeps)")


@pytest.mark.points(1)
@pytest.mark.title("Scene: a resting ball with e = 0.5 stays on the ground (the restitution threshold)")
def test_resting_ball_stays(student):
    scene = "the ball resting on the ground (e = 0.5)"
    ball = scenes.Upright(1.0, radius=0.5, y=0.5, restitution=0.5)
    settings, memory, heights = scenes.SceneSettings(), {}, []
    for _ in range(120):
        scenes.step_scene([ball], scene_calls(student, scene), settings, memory)
        heights.append(ball.y - 0.5)
    assert max(map(abs, heights)) < 1e-4, (f"{scene}: its centre moves between {min(heights) * 1e3:+.2f} and "
                                           f"{max(heights) * 1e3:+.2f} mm: gravity's {scenes.G / 60:.3f} m/s a step "
                                           "must not bounce")


@pytest.mark.points(2)
@pytest.mark.title("Scene: a ball hitting the ground at 5 m/s leaves at e v whatever the number of sweeps")
def test_bounce_whatever_the_sweeps(student):
    for iterations in (1, 2, 3, 10):
        ball = scenes.Upright(1.0, radius=0.5, y=0.5, velocity=[0.0, -5.0 + scenes.G / 60, 0.0], restitution=0.8)
        scenes.step_scene([ball], scene_calls(student, "the bouncing ball"),
                          scenes.SceneSettings(iterations=iterations), {})
        assert abs(ball.velocity[1] - 4.0) < 1e-9, (
            f"the ball hitting the ground at 5 m/s with e = 0.8 leaves at {ball.velocity[1]:+.4f} m/s after "
            f"{iterations} sweeps, +4 m/s expected: the target is set once, from the velocity before any impulse; "
            "measured again during the sweeps, it sees the bounce the first sweep made and asks for none")


@pytest.mark.points(2)
@pytest.mark.title("Scene, your step: a box resting on the ground, a ball dropped onto it and a box sliding at 2 m/s "
                   "come to rest within the slop, the slider after v^2 / (2 mu g) (step_bodies, 2 s)")
def test_step_rests_within_the_slop(student):
    """Stepped by step_bodies alone: a 1 m box that cannot turn, resting on the ground, a
    ball dropped from 0.5 m (e = 0) and a box sliding at 2 m/s (mu = 0.5).  The push
    takes 20 % of an overlap beyond the 5 mm slop a step, so all rest with their overlaps
    within the slop; friction, mu times the normal impulse, stops the slider after the
    stepped v^2 / (2 mu g) - v h / 2.  A body moved before its contact is solved sinks by
    g h^2 every step and rests where the push balances that, 5 mm + g h^2 / 0.2 = 18.6 mm
    deep."""
    scene = "the box resting on the ground, the ball dropped onto it and the box sliding at 2 m/s"
    bodies = [scenes.Upright(1.0, 0.5, 0.5, x=0.0, y=0.5, turns=False), scenes.Upright(1.0, radius=0.5, x=3.0, y=1.0),
              scenes.Upright(1.0, 0.5, 0.5, x=6.0, y=0.5, velocity=[2.0, 0.0, 0.0], turns=False)]
    settings, memory, deepest = scenes.SceneSettings(), {}, [0.0, 0.0, 0.0]
    for step in range(120):
        scenes.step_scene_whole(bodies, scene_calls(student, scene), settings, memory)
        if step >= 60:
            deepest = [max(d, o) for d, o in zip(deepest, scenes.overlaps(bodies))]
    sink = scenes.G * settings.dt ** 2
    balance = settings.slop + sink / settings.bias_factor      # where the push balances g h^2 a step
    if max(deepest) > settings.slop + 1e-3:
        why = (f" They rest where a push of 20 % of the overlap beyond the slop balances a sinking of g h^2 = "
               f"{sink * 1e3:.2f} mm a step, {balance * 1e3:.1f} mm deep: the bodies move before their contacts are "
               "solved. The step is gravity, then the sweeps, then the positions, with the velocities the sweeps "
               "leave." if all(abs(d - balance) < 1e-3 for d in deepest) else "")
        fail(f"{scene}: in the second second the resting box overlaps the ground by up to {deepest[0] * 1e3:.2f} mm, "
             f"the ball by {deepest[1] * 1e3:.2f} mm and the slider by {deepest[2] * 1e3:.2f} mm; resting, they stay "
             f"within the slop, {settings.slop * 1e3:.0f} mm." + why)
    slid = bodies[2].x - 6.0
    want = 2.0 ** 2 / (2 * 0.5 * scenes.G) - 2.0 * settings.dt / 2      # the stepped distance
    assert abs(slid - want) < 0.01 * want, (f"{scene}: the slider stopped after {slid:.4f} m; friction, mu = 0.5 "
                                            f"times the normal impulse, stops it after {want:.4f} m")
    speed = max(abs(v) for body in bodies for v in body.velocity)
    assert speed < 1e-3, f"{scene}: after 2 s a body still moves at {speed:.3g} m/s"


@pytest.mark.points(2)
@pytest.mark.title("Scene, your step: two balls and a box dropped onto the ground bounce at e times their landing "
                   "speed, then settle (step_bodies, 2 s)")
def test_step_drops_bounce(student):
    """Stepped by step_bodies alone: balls dropped from 1 m (e = 0.6) and 0.5 m (e = 0.9)
    and a box that cannot turn from 0.8 m (e = 0.5), each alone over the ground.  Every
    landing faster than the threshold leaves at e times its closing speed, whatever the
    sweeps do after the first; slower ones stop, and the overlaps are pushed out."""
    bodies = [scenes.Upright(1.0, radius=0.5, x=0.0, y=1.5, restitution=0.6),
              scenes.Upright(1.0, radius=0.3, x=2.0, y=0.8, restitution=0.9),
              scenes.Upright(2.0, 0.4, 0.25, x=4.0, y=1.05, restitution=0.5, turns=False)]
    follow_targets(student, "the two balls and the box dropped onto the ground (e = 0.6, 0.9, 0.5)", bodies,
                   scenes.SceneSettings(), 120,
                   "a landing faster than the threshold leaves at e times its closing speed, measured once before "
                   "the sweeps, then kept; gravity, the sweeps, then the positions with the new velocities; "
                   + PUSH_HINT, whole=True)



# Scenes of contact_target alone --------------------------------------------------------
# Bodies that move only up and down, each alone on the ground, every contact point as
# deep: the oracle solves their contact exactly (the sweeps would bring the velocity to
# the target, or leave a faster one), so only contact_target is graded by these scenes.
def follow_targets(student, scene: str, bodies: list, settings, steps: int, hint: str, whole: bool = False) -> None:
    """Step ``bodies`` with the student's targets (``whole``: with their ``step_bodies``)
    and compare every body's overlap and velocity, step by step, with the physics'
    (:func:`upright_scenes.vertical_paths`)."""
    want = scenes.vertical_paths(bodies, settings, steps)
    if whole:
        stepped, memory, got = copy.deepcopy(bodies), {}, []
        for _ in range(steps):
            scenes.step_scene_whole(stepped, scene_calls(student, scene), settings, memory)
            got.append([(depth, body.velocity[1]) for depth, body in zip(scenes.overlaps(stepped), stepped)])
    else:
        got = scenes.vertical_paths(bodies, settings, steps, scene_calls(student, scene))
    for step, (got_step, want_step) in enumerate(zip(got, want)):
        for index, ((depth, velocity), (want_depth, want_velocity)) in enumerate(zip(got_step, want_step)):
            if abs(depth - want_depth) > 1e-9 or abs(velocity - want_velocity) > 1e-9:
                which = f"body {index + 1}" if len(bodies) > 1 else "it"
                fail(f"{scene}, step {step + 1}: {which} overlaps the ground by {depth * 1e3:+.3f} mm and moves at "
                     f"{velocity:+.4f} m/s; {want_depth * 1e3:+.3f} mm and {want_velocity:+.4f} m/s expected "
                     f"({hint})")


PUSH_HINT = "an overlap beyond the slop is pushed out at bias_factor (overlap - slop) / h, at most max_push"


def landing_ball(speed: float, restitution: float, above: float = 0.001, x: float = 0.0, dt: float = 1 / 60):
    """A 1 kg ball of radius 0.5 m, its lowest point ``above`` m over the ground, that
    touches the ground on the second step closing at ``speed`` (m/s, gravity included)."""
    return scenes.Upright(1.0, radius=0.5, x=x, y=0.5 + above, velocity=[0.0, -speed + 2 * scenes.G * dt, 0.0],
                          restitution=restitution)


@pytest.mark.points(2)
@pytest.mark.title("Scene: a ball landing at 0.9 m/s, below the restitution threshold, does not bounce (e = 0.8)")
def test_slow_landing_stays(student):
    """It touches 11 mm deep: it stops there, then the push lifts it to the slop."""
    follow_targets(student, "the ball landing at 0.9 m/s (threshold 1 m/s, e = 0.8)", [landing_ball(0.9, 0.8)],
                   scenes.SceneSettings(), 60, f"closing slower than the threshold, it does not bounce; {PUSH_HINT}")


@pytest.mark.points(2)
@pytest.mark.title("Scene: a ball landing at 1.2 m/s, above the threshold, leaves at e v; landing again below it, "
                   "it stays")
def test_landing_above_threshold_bounces(student):
    follow_targets(student, "the ball landing at 1.2 m/s (threshold 1 m/s, e = 0.6)", [landing_ball(1.2, 0.6)],
                   scenes.SceneSettings(), 60,
                   f"it leaves at 0.6 x 1.2 = 0.72 m/s, lands again below the threshold and stays; {PUSH_HINT}")


@pytest.mark.points(2)
@pytest.mark.title("Scene: a box sunk 30 cm into the ground rises at the capped push of 1 m/s and stops at the slop")
def test_sunk_box_pushed_out(student):
    """A 1 m box (e = 0.5) that cannot turn, its bottom 0.3 m below the ground, at rest:
    the push wants 0.2 x 0.295 m / h = 3.5 m/s, capped at 1 m/s, until the overlap
    beyond the slop is below 8 cm; then 20 % of it a step; it never leaves the ground."""
    box = scenes.Upright(1.0, 0.5, 0.5, y=0.2, restitution=0.5, turns=False)
    follow_targets(student, "the box sunk 30 cm into the ground (max_push = 1 m/s)", [box],
                   scenes.SceneSettings(max_push=1.0), 60,
                   f"{PUSH_HINT}; closing slowly after, the box does not bounce")


@pytest.mark.points(2)
@pytest.mark.title("Scene: five bodies resting on the ground with e = 0.3 to 1, three of them spawned 1 to 4 cm deep, "
                   "rise to the slop and stay")
def test_resting_bodies_stay(student):
    """Gravity makes a resting contact close at g h = 0.16 m/s every step, below the
    threshold: none of them bounces, whatever its e; the overlaps beyond the slop are
    pushed out."""
    bodies = [scenes.Upright(1.0, 0.5, 0.5, x=0.0, y=0.5, restitution=1.0, turns=False),
              scenes.Upright(1.0, radius=0.5, x=2.0, y=0.5, restitution=0.5),
              scenes.Upright(2.0, 0.4, 0.25, x=4.0, y=0.23, restitution=0.8, turns=False),
              scenes.Upright(1.0, radius=0.3, x=6.0, y=0.26, restitution=0.3),
              scenes.Upright(1.0, 0.5, 0.5, x=8.0, y=0.49, restitution=0.6, turns=False)]
    follow_targets(student, "the five resting bodies (e = 1, 0.5, 0.8, 0.3, 0.6)", bodies, scenes.SceneSettings(), 60,
                   f"a contact closing slower than the threshold does not bounce; {PUSH_HINT}")
