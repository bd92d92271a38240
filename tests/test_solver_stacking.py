"""The block solver of ContactSolver (two-point manifolds as one 2x2 LCP) and stacking.

Oracles: the 2x2 system K x = -b built here from the Jacobian with numpy, the lever
rule of statics, a brute-force enumeration of the four active sets of the 2x2 linear
complementarity problem, and the comparison the ``block_solver`` switch exists to
show (a stack of boxes stays straight with it, wobbles without it).
"""
import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from solutions import scene_metrics as metrics
from solutions.body import Body
from solutions.contact import Contact
from solutions.response.contact_solver import ContactSolver, SolverSettings
from solutions.solver.constraint_rows import MAX_CONDITION_NUMBER
from solutions.solver.kernel import block_normal_impulses
from solutions.scenes import get_scene

G = 9.81      # m/s^2
DT = 1 / 60   # s
# One block solve, nothing else: no friction or position bias to change the velocities.
ONE_BLOCK_SOLVE = dict(iterations=1, position_correction="none", friction=False, restitution_threshold=0.0)


def cross(r, v):
    return r[0] * v[1] - r[1] * v[0]


def normal_system(body, points, normal):
    """K (1/kg) and the normal velocities b (m/s) of a body's contact points against a
    static body, from the Jacobian rows J_i = (n, r_i x n) and M^-1 = diag(1/m, 1/m, 1/I)."""
    jacobian = np.array([[*normal, cross(np.asarray(p) - body.position, normal)] for p in points])
    inverse_mass = np.diag([body.inverse_mass, body.inverse_mass, body.inverse_inertia])
    state = np.array([*body.velocity, body.angular_velocity])
    return jacobian @ inverse_mass @ jacobian.T, jacobian @ state


def lcp_by_enumeration(k, b):
    """Every active set of x >= 0, v = K x + b >= 0, x_i v_i = 0, solved with numpy;
    returns the distinct solutions found (a positive definite K has exactly one)."""
    found = []
    for active in itertools.chain.from_iterable(itertools.combinations(range(2), n) for n in range(3)):
        x = np.zeros(2)
        if active:
            x[list(active)] = np.linalg.solve(k[np.ix_(active, active)], -b[list(active)])
        v = k @ x + b
        scale = 1e-12 * (1.0 + np.abs(b).max())
        inactive = [i for i in range(2) if i not in active]
        if np.all(x >= -scale) and np.all(v[inactive] >= -scale):
            # b = 0, say, fits several sets with the same x; a b of a few 1e-13 lets rounding
            # accept two sets whose x differ by about |b| / det K: the same solution.
            same = 1e-9 * (1.0 + np.abs(b).max() / min(k[0, 0], k[1, 1]))
            if not any(np.allclose(x, other, rtol=1e-9, atol=same) for other in found):
                found.append(x)
    return found


def resting_box(mass=2.0, points=((-0.5, 0.0), (0.5, 0.0))):
    """A 1 m box of ``mass`` kg on static ground after one step of gravity from rest."""
    ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
    box = Body.box(1.0, 1.0, mass=mass, position=(0.0, 0.5), velocity=(0.0, -G * DT))
    return ground, box, Contact((0.0, 1.0), 0.0, points, feature_ids=(0, 1))


# ------------------------------------------------------------ one manifold
def test_block_solver_shares_the_weight_of_a_centred_box_exactly():
    ground, box, contact = resting_box()
    k, b = normal_system(box, contact.points, contact.normal)
    want = np.linalg.solve(k, -b)  # both points active
    solver = ContactSolver(SolverSettings(**ONE_BLOCK_SOLVE))
    solver.solve([ground, box], [(0, 1, contact)], DT)
    got = [impulse[3] for impulse in solver.contact_impulses]
    # 1e-12: a 2x2 solve in either order, rounding only.
    np.testing.assert_allclose(got, want, rtol=1e-12)
    np.testing.assert_allclose(got, [box.mass * G * DT / 2] * 2, rtol=1e-12)
    assert solver.stats.block_manifolds == 1
    np.testing.assert_allclose(box.velocity, [0.0, 0.0], atol=1e-15)
    assert abs(box.angular_velocity) < 1e-15
    # Point by point, one sweep: the first corner takes too much and the box turns.
    ground, box, contact = resting_box()
    ContactSolver(SolverSettings(**ONE_BLOCK_SOLVE, block_solver=False)).solve([ground, box], [(0, 1, contact)], DT)
    assert abs(box.angular_velocity) > 0.01


def test_block_solver_follows_the_lever_rule_off_centre():
    # Points at x = -0.5 and x = 0.2 under a centre at x = 0: statics says the
    # impulses are m g dt * (0.2, 0.5) / 0.7 (forces balance, torques balance).
    ground, box, contact = resting_box(mass=3.0, points=((-0.5, 0.0), (0.2, 0.0)))
    k, b = normal_system(box, contact.points, contact.normal)
    solver = ContactSolver(SolverSettings(**ONE_BLOCK_SOLVE))
    solver.solve([ground, box], [(0, 1, contact)], DT)
    got = [impulse[3] for impulse in solver.contact_impulses]
    np.testing.assert_allclose(got, np.linalg.solve(k, -b), rtol=1e-12)
    np.testing.assert_allclose(got, 3.0 * G * DT * np.array([0.2, 0.5]) / 0.7, rtol=1e-12)
    assert abs(box.angular_velocity) < 1e-14


@pytest.mark.parametrize("spin", [3.0, -3.0])
@pytest.mark.parametrize("backend", ["python", "numba"])
def test_tilted_landing_clamps_the_separating_corner_to_zero(spin, backend):
    # A box tilted by 0.05 rad lands on both bottom corners while turning: one corner
    # approaches, the other moves away, so the LCP leaves one impulse at exactly 0.
    angle = 0.05
    ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True)
    box = Body.box(1.0, 1.0, mass=1.5, position=(0.0, 0.5), angle=angle, velocity=(0.3, -0.5),
                   angular_velocity=spin)
    c, s = math.cos(angle), math.sin(angle)
    corners = [box.position + np.array([c * x + s * 0.5, s * x - c * 0.5]) for x in (-0.5, 0.5)]
    contact = Contact((0.0, 1.0), 0.0, corners, feature_ids=(0, 1))
    k, b = normal_system(box, contact.points, contact.normal)
    assert min(b) < 0.0 < max(b)       # one corner closes, the other opens
    (want,) = lcp_by_enumeration(k, b)
    solver = ContactSolver(SolverSettings(**ONE_BLOCK_SOLVE), backend=backend)
    solver.solve([ground, box], [(0, 1, contact)], DT)
    got = np.array([impulse[3] for impulse in solver.contact_impulses])
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-15)
    closing = int(np.argmin(b))
    assert got[1 - closing] == 0.0 < got[closing]
    _, after = normal_system(box, contact.points, contact.normal)
    assert abs(after[closing]) < 1e-12 and after[1 - closing] > 0.0


@settings(max_examples=300, deadline=None)
@given(st.floats(0.01, 10), st.floats(0.0, 10), st.floats(-2, 2), st.floats(-2, 2),
       st.floats(-5, 5), st.floats(-5, 5))
def test_block_normal_impulses_match_the_enumerated_lcp(inverse_mass, inverse_inertia, r1, r2, b1, b2):
    # K of two points on one body against a static one, lever arms r1, r2 across n.
    k = inverse_mass + inverse_inertia * np.array([[r1 * r1, r1 * r2], [r1 * r2, r2 * r2]])
    if max(k[0, 0], k[1, 1]) ** 2 >= MAX_CONDITION_NUMBER * np.linalg.det(k):
        return  # the solver would go point by point
    b = np.array([b1, b2])
    (want,) = lcp_by_enumeration(k, b)
    got = block_normal_impulses(k[0, 0], k[0, 1], k[1, 1], b1, b2)
    # Rounding of a 2x2 solve with cond(K) < 1000, relative to the largest impulse b / k.
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * (1 + np.abs(b).max() / min(k[0, 0], k[1, 1])))


def test_ill_conditioned_manifolds_are_solved_point_by_point():
    # Two points 1 micrometre apart (nearly the same row of the Jacobian), and a box
    # that cannot turn (K singular): no block solve, and the box still stops.
    for points, rotation in ((((0.0, 0.0), (1e-6, 0.0)), True), (((-0.5, 0.0), (0.5, 0.0)), False)):
        ground, box, contact = resting_box(points=points)
        solver = ContactSolver(SolverSettings(iterations=20, position_correction="none", rotation=rotation))
        solver.solve([ground, box], [(0, 1, contact)], DT)
        assert solver.stats.block_manifolds == 0
        assert abs(box.velocity[1]) < 1e-9
        assert sum(impulse[3] for impulse in solver.contact_impulses) == pytest.approx(box.mass * G * DT, rel=1e-9)


# ------------------------------------------------------------------ stacking
def stack_run(block_solver=True, order="manifolds", steps=90, name="stack_10", iterations=10):
    """Largest drift (m) seen and largest |angle| (rad) of a named stack scene."""
    scene = get_scene(name)
    world = scene.build_world(iterations=iterations, block_solver=block_solver, order=order)
    start = metrics.start_positions(world.bodies)
    worst_drift = worst_angle = 0.0
    for _ in range(steps):
        world.step(scene.dt)
        worst_drift = max(worst_drift, metrics.max_drift(world.bodies, start))
        worst_angle = max(worst_angle, max(abs(body.angle) for body in world.bodies))
    return worst_drift, worst_angle


def test_block_solver_keeps_a_stack_of_ten_straight():
    # 10 boxes, 10 iterations, 1.5 s.  With the block solver every face-face manifold
    # is solved symmetrically, so the stack only settles straight down (about one
    # slop, 5 mm, per contact at most); point by point it turns and wobbles.
    on_drift, on_angle = stack_run(True)
    off_drift, off_angle = stack_run(False)
    assert on_angle < 1e-9 < 1e-4 < off_angle
    assert on_drift < 0.05
    assert 2 * on_drift < off_drift


def test_sweeping_in_manifold_order_lets_a_stack_sink_less_than_by_colours():
    # The stack's contacts are listed bottom-up.  In that order one sweep carries an
    # impulse from the ground to the top; by colours (every other contact, then the
    # rest) it climbs about two contacts per sweep, so the cold start sinks further.
    in_order, _ = stack_run(order="manifolds", steps=60)
    by_colours, _ = stack_run(order="colours", steps=60)
    assert 1.5 * in_order < by_colours
