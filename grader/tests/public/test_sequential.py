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
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import pytest
import sympy as sp

from grader.harness.compare import number, show
from grader.harness.credit import check_cases

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
