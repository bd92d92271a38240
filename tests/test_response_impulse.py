"""Rigid-body impulses and positional correction against sympy derivations.

solutions.response.impulse and solutions.response.positional_correction; the oracle
is sympy solving the impulse equations with their angular terms, and conservation
laws checked on the bodies.
"""
import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from solutions.body import Body
from solutions.contact import Contact
from solutions.response.impulse import (
    apply_impulse,
    effective_mass_inverse,
    normal_impulse_magnitude,
    relative_normal_velocity,
    resolve_collision,
    solve_small_lcp,
)
from solutions.response.positional_correction import correct_positions


def cross(ax, ay, bx, by):
    return ax * by - ay * bx


def derive_two_body_impulse():
    """j such that the relative normal velocity at the point becomes -e times its
    value before, with linear and angular changes of both bodies; returned as a
    function of inverse masses so that a static body is 1/m = 1/I = 0."""
    m_a, m_b, i_a, i_b = sp.symbols("m_A m_B I_A I_B", positive=True)
    vax, vay, wa, vbx, vby, wb = sp.symbols("v_Ax v_Ay w_A v_Bx v_By w_B", real=True)
    rax, ray, rbx, rby, nx, ny, e, j = sp.symbols("r_Ax r_Ay r_Bx r_By n_x n_y e j", real=True)
    rn_a, rn_b = cross(rax, ray, nx, ny), cross(rbx, rby, nx, ny)

    def normal_velocity(vax, vay, wa, vbx, vby, wb):
        # point velocity v + w x r = (v_x - w r_y, v_y + w r_x), r from the centre of mass
        return ((vbx - wb * rby) - (vax - wa * ray)) * nx + ((vby + wb * rbx) - (vay + wa * rax)) * ny

    before = normal_velocity(vax, vay, wa, vbx, vby, wb)
    after = normal_velocity(vax - j * nx / m_a, vay - j * ny / m_a, wa - rn_a * j / i_a,
                            vbx + j * nx / m_b, vby + j * ny / m_b, wb + rn_b * j / i_b)
    (j_solution,) = sp.solve(sp.Eq(after, -e * before), j)
    ima, imb, iia, iib = sp.symbols("ima imb iia iib", nonnegative=True)
    j_inverse = sp.cancel(j_solution.subs({m_a: 1 / ima, m_b: 1 / imb, i_a: 1 / iia, i_b: 1 / iib}))
    args = (ima, imb, iia, iib, vax, vay, wa, vbx, vby, wb, rax, ray, rbx, rby, nx, ny, e)
    return sp.lambdify(args, j_inverse), sp.lambdify(args[4:], before)


J_ORACLE, NORMAL_VELOCITY_ORACLE = derive_two_body_impulse()


def random_body(rng, static=False, fixed_rotation=False):
    kind = rng.integers(3)
    common = dict(mass=rng.uniform(0.1, 10.0), position=rng.uniform(-3, 3, 2), angle=rng.uniform(-3, 3),
                  velocity=rng.uniform(-5, 5, 2), angular_velocity=rng.uniform(-5, 5),
                  is_static=static, fixed_rotation=fixed_rotation)
    if static:
        common.update(velocity=(0.0, 0.0), angular_velocity=0.0)
    if kind == 0:
        return Body.circle(rng.uniform(0.1, 1.0), **common)
    if kind == 1:
        return Body.box(rng.uniform(0.1, 2.0), rng.uniform(0.1, 2.0), **common)
    return Body.polygon([(0.0, 0.0), (1.0, 0.2), (0.6, 1.1)], **common)


def oracle_args(a, b, point, normal, e):
    ra, rb = np.asarray(point) - a.position, np.asarray(point) - b.position
    return (a.inverse_mass, b.inverse_mass, a.inverse_inertia, b.inverse_inertia,
            *a.velocity, a.angular_velocity, *b.velocity, b.angular_velocity, *ra, *rb, *normal, e)


def random_pair(rng):
    """Two bodies, a contact point and a unit normal along which they approach."""
    static_a = rng.random() < 0.25
    a = random_body(rng, static=static_a, fixed_rotation=rng.random() < 0.15)
    b = random_body(rng, fixed_rotation=rng.random() < 0.15)
    point = rng.uniform(-3, 3, 2)
    angle = rng.uniform(0, 2 * np.pi)
    normal = np.array([np.cos(angle), np.sin(angle)])
    if relative_normal_velocity(a, b, point, normal) > 0:
        normal = -normal
    return a, b, point, normal


def momenta(bodies):
    """Total linear momentum and angular momentum about the origin of dynamic bodies."""
    linear = sum(b.mass * b.velocity for b in bodies if not b.is_static)
    angular = sum(b.mass * cross(*b.position, *b.velocity) + (0.0 if math.isinf(b.inertia) else b.inertia * b.angular_velocity)
                  for b in bodies if not b.is_static)
    return np.asarray(linear, dtype=float), float(angular)


def energy(bodies):
    return sum(b.kinetic_energy() for b in bodies)


# ---------------------------------------------------------------- sympy oracle
def test_normal_impulse_matches_sympy_derivation():
    rng = np.random.default_rng(7)
    for _ in range(300):
        a, b, point, normal = random_pair(rng)
        e = rng.uniform(0, 1)
        args = oracle_args(a, b, point, normal, e)
        assert relative_normal_velocity(a, b, point, normal) == pytest.approx(NORMAL_VELOCITY_ORACLE(*args[4:]), rel=1e-12, abs=1e-12)
        want = max(J_ORACLE(*args), 0.0)
        assert normal_impulse_magnitude(a, b, point, normal, e) == pytest.approx(want, rel=1e-10, abs=1e-12)


def test_effective_mass_inverse_has_the_angular_terms():
    rng = np.random.default_rng(8)
    for _ in range(100):
        a, b, point, normal = random_pair(rng)
        k = effective_mass_inverse(a, b, point, normal)
        # A unit impulse along n changes v_n by exactly k.
        before = relative_normal_velocity(a, b, point, normal)
        apply_impulse(a, b, point, normal)
        assert relative_normal_velocity(a, b, point, normal) - before == pytest.approx(k, rel=1e-10)


def test_separating_contact_and_two_static_bodies_get_no_impulse():
    rng = np.random.default_rng(9)
    a, b, point, normal = random_pair(rng)
    assert normal_impulse_magnitude(a, b, point, -normal, 0.5) == 0.0
    wall = Body.box(1.0, 1.0, is_static=True)
    floor = Body.box(1.0, 1.0, is_static=True, position=(0.0, -1.0))
    assert effective_mass_inverse(floor, wall, (0.0, -0.5), (0.0, 1.0)) == 0.0
    assert normal_impulse_magnitude(floor, wall, (0.0, -0.5), (0.0, 1.0), 1.0) == 0.0


def test_closing_speed_uses_point_velocities_not_the_notes_formula():
    # Erratum 18: v_a.(p_b - p_a) + v_b.(p_a - p_b) is |p_b - p_a| times the closing speed.
    a = Body.circle(1.0, position=(0.0, 0.0), velocity=(3.0, 0.0))
    b = Body.circle(1.0, position=(4.0, 0.0), velocity=(-1.0, 0.0))
    notes = float(a.velocity @ (b.position - a.position) + b.velocity @ (a.position - b.position))
    closing_speed = -relative_normal_velocity(a, b, (2.0, 0.0), (1.0, 0.0))
    assert closing_speed == 4.0
    assert notes == 4.0 * closing_speed
    # A spinning disc's contact point moves although its centre does not.
    spinning = Body.circle(1.0, position=(0.0, 0.0), angular_velocity=2.0)
    ground = Body.box(10.0, 1.0, position=(0.0, -1.5), is_static=True)
    assert relative_normal_velocity(ground, spinning, (0.0, -1.0), (0.0, 1.0)) == 0.0
    assert relative_normal_velocity(ground, spinning, (-1.0, 0.0), (1.0, 0.0)) == pytest.approx(0.0)
    assert relative_normal_velocity(ground, spinning, (0.0, -1.0), (1.0, 0.0)) == pytest.approx(2.0)


# -------------------------------------------------------- conservation laws
@settings(max_examples=150, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.0, 1.0))
def test_apply_impulse_conserves_momentum_and_normal_impulse_gains_no_energy(seed, e):
    # Free bodies: a fixed rotation is an outside constraint that takes up torque.
    rng = np.random.default_rng(seed)
    a, b = random_body(rng), random_body(rng)
    point = rng.uniform(-3, 3, 2)
    normal = np.array([1.0, 0.0]) if rng.random() < 0.5 else np.array([0.6, -0.8])
    if relative_normal_velocity(a, b, point, normal) > 0:
        normal = -normal
    linear, angular = momenta([a, b])
    kinetic = energy([a, b])
    v_n = NORMAL_VELOCITY_ORACLE(*oracle_args(a, b, point, normal, e)[4:])
    j = normal_impulse_magnitude(a, b, point, normal, e)
    apply_impulse(a, b, point, j * normal)
    linear_after, angular_after = momenta([a, b])
    scale = sum(abs(x.mass) * (np.linalg.norm(x.velocity) * (1 + np.linalg.norm(x.position)) + 1) for x in (a, b))
    np.testing.assert_allclose(linear_after, linear, atol=1e-12 * scale)
    assert angular_after == pytest.approx(angular, abs=1e-11 * scale)
    assert energy([a, b]) <= kinetic * (1 + 1e-12) + 1e-12
    if e == 1.0:
        assert energy([a, b]) == pytest.approx(kinetic, rel=1e-9)
    # The restitution law holds at the point (v_n <= 0 here).
    v_n_after = NORMAL_VELOCITY_ORACLE(*oracle_args(a, b, point, normal, e)[4:])
    assert v_n_after == pytest.approx(-e * v_n, rel=1e-9, abs=1e-9)


def test_static_body_does_not_move_and_fixed_rotation_does_not_turn():
    rng = np.random.default_rng(3)
    for _ in range(20):
        wall = random_body(rng, static=True)
        slider = random_body(rng, fixed_rotation=True)
        spin = slider.angular_velocity
        impulse = rng.uniform(-3, 3, 2)
        speed = slider.velocity.copy()
        apply_impulse(wall, slider, rng.uniform(-1, 1, 2), impulse)
        assert wall.velocity.tolist() == [0.0, 0.0] and wall.angular_velocity == 0.0
        assert slider.angular_velocity == spin
        np.testing.assert_allclose(slider.velocity, speed + impulse / slider.mass, rtol=1e-14)


def separate_impulse_per_body(a, b, point, normal, e):
    """The notes' procedure (erratum 22): an impulse for A as if B could not move,
    then the same computation for B.  Spot the bug."""
    v_n = relative_normal_velocity(a, b, point, normal)
    for body, sign in ((a, -1.0), (b, 1.0)):
        r = np.asarray(point) - body.position
        k_alone = body.inverse_mass + body.inverse_inertia * cross(*r, *normal) ** 2
        j = -(1 + e) * v_n / k_alone
        body.velocity = body.velocity + sign * body.inverse_mass * j * normal
        body.angular_velocity += sign * body.inverse_inertia * cross(*r, *(j * normal))


def test_separate_impulse_per_body_triples_the_speeds():
    # sympy: with k_A j_A = k_B j_B = -(1 + e) v_n the separation speed is (1 + 2e) v_n.
    v_n, e = sp.symbols("v_n e")
    after_bug = v_n + 2 * (-(1 + e) * v_n)
    assert sp.simplify(after_bug / (-e * v_n) - (1 + 2 * e) / e) == 0
    factor = float(((1 + 2 * e) / e).subs(e, 1))
    assert factor == 3.0
    # Two equal discs head on at +-2 m/s, e = 1.
    def pair():
        return (Body.circle(0.5, position=(-0.5, 0.0), velocity=(2.0, 0.0)),
                Body.circle(0.5, position=(0.5, 0.0), velocity=(-2.0, 0.0)))
    right_a, right_b = pair()
    apply_impulse(right_a, right_b, (0.0, 0.0), normal_impulse_magnitude(right_a, right_b, (0.0, 0.0), (1.0, 0.0), 1.0) * np.array([1.0, 0.0]))
    bug_a, bug_b = pair()
    separate_impulse_per_body(bug_a, bug_b, (0.0, 0.0), np.array([1.0, 0.0]), 1.0)
    assert right_a.velocity.tolist() == [-2.0, 0.0]
    assert np.linalg.norm(bug_a.velocity) / np.linalg.norm(right_a.velocity) == pytest.approx(factor)
    assert energy([bug_a, bug_b]) / energy([right_a, right_b]) == pytest.approx(factor**2)
    # Any bodies: the separation speed is 3 times the approach speed, and the two
    # impulses are not equal and opposite (unless k_A = k_B): momentum is not conserved.
    rng = np.random.default_rng(11)
    for _ in range(50):
        a, b, point, normal = random_pair(rng)
        if a.is_static:
            continue
        before_speed = relative_normal_velocity(a, b, point, normal)
        linear, _ = momenta([a, b])
        separate_impulse_per_body(a, b, point, normal, 1.0)
        assert relative_normal_velocity(a, b, point, normal) == pytest.approx(-factor * before_speed, rel=1e-9)
        assert np.linalg.norm(momenta([a, b])[0] - linear) > 1e-6 * abs(before_speed) * (a.mass + b.mass)


# ------------------------------------------------------- resolve_collision
def test_resolve_collision_single_point_is_the_restitution_law():
    rng = np.random.default_rng(12)
    for _ in range(100):
        a, b, point, normal = random_pair(rng)
        e = rng.uniform(0, 1)
        v_n = relative_normal_velocity(a, b, point, normal)
        want = max(J_ORACLE(*oracle_args(a, b, point, normal, e)), 0.0)
        normal_impulses, tangent_impulses = resolve_collision(a, b, Contact(normal, 0.0, [point]), restitution=e, friction=0.0)
        assert normal_impulses[0] == pytest.approx(want, rel=1e-9, abs=1e-12)
        assert tangent_impulses[0] == 0.0
        assert relative_normal_velocity(a, b, point, normal) == pytest.approx(-e * v_n, rel=1e-9, abs=1e-9)


def test_resolve_collision_combines_coefficients_as_products():
    def scene():
        ground = Body.box(10.0, 1.0, position=(0.0, -0.5), is_static=True, restitution=0.5, friction=0.8)
        ball = Body.circle(0.5, position=(0.0, 0.5), velocity=(3.0, -2.0), restitution=0.6, friction=0.25)
        return ground, ball, Contact((0.0, 1.0), 0.0, [(0.0, 0.0)])
    default = scene()
    resolve_collision(*default)
    explicit = scene()
    resolve_collision(*explicit, restitution=0.5 * 0.6, friction=0.8 * 0.25)
    assert default[1].velocity.tolist() == explicit[1].velocity.tolist()
    assert default[1].velocity[1] == pytest.approx(0.3 * 2.0)


def test_two_point_manifold_satisfies_the_complementarity_conditions():
    rng = np.random.default_rng(13)
    for _ in range(200):
        a, b, point, normal = random_pair(rng)
        second = point + rng.uniform(-1, 1) * np.array([-normal[1], normal[0]])
        points = np.array([point, second])
        e = rng.uniform(0, 1)
        before = np.array([relative_normal_velocity(a, b, p, normal) for p in points])
        target = np.where(before < 0, -e * before, 0.0)
        impulses, _ = resolve_collision(a, b, Contact(normal, 0.0, points), restitution=e, friction=0.0)
        after = np.array([relative_normal_velocity(a, b, p, normal) for p in points])
        scale = 1e-8 * (1 + np.abs(before).max())
        assert np.all(impulses >= 0)
        assert np.all(after >= target - scale)                      # nothing left approaching
        assert np.all(np.abs(impulses * (after - target)) <= scale * (1 + impulses))  # push only where needed


def test_box_landing_flat_bounces_without_spin():
    for mass, width, e in ((1.0, 1.0, 0.5), (7.5, 3.0, 0.0), (0.2, 0.4, 1.0)):
        ground = Body.box(20.0, 1.0, position=(0.0, -0.5), is_static=True)
        box = Body.box(width, 0.5, mass=mass, position=(0.0, 0.25), velocity=(0.0, -3.0))
        corners = Contact((0.0, 1.0), 0.0, [(-width / 2, 0.0), (width / 2, 0.0)])
        impulses, _ = resolve_collision(ground, box, corners, restitution=e)
        assert box.angular_velocity == pytest.approx(0.0, abs=1e-12)
        assert box.velocity[1] == pytest.approx(3.0 * e, abs=1e-12)
        assert impulses.sum() == pytest.approx(mass * 3.0 * (1 + e))
        assert impulses[0] == pytest.approx(impulses[1])


def test_friction_on_a_disc_matches_coulomb_stick_and_slip():
    # sympy: disc of mass m, radius R (I = m R^2 / 2) hits static ground at the
    # bottom point; t = (n_y, -n_x) = (1, 0).  Sticking stops the contact point:
    # v_x' + w' R = 0; sliding clamps the friction impulse to mu j_n.
    m, radius, vx, vy, w, e, mu = sp.symbols("m R v_x v_y w e mu", real=True)
    inertia = m * radius**2 / 2
    jn = -(1 + e) * m * vy
    jt = sp.symbols("j_t", real=True)
    slip_speed = vx + w * radius  # tangential velocity of the contact point
    (stick,) = sp.solve(sp.Eq(vx + jt / m + (w + radius * jt / inertia) * radius, 0), jt)
    assert sp.simplify(stick + m * slip_speed / 3) == 0
    args = (m, radius, vx, vy, w, e, mu)
    stick_f = sp.lambdify(args, stick)
    bound_f = sp.lambdify(args, mu * jn)
    rng = np.random.default_rng(14)
    regimes = set()
    for _ in range(100):
        values = (rng.uniform(0.5, 5), rng.uniform(0.1, 1), rng.uniform(-5, 5), rng.uniform(-5, -0.5),
                  rng.uniform(-5, 5), rng.uniform(0, 1), rng.uniform(0, 1))
        mass, r, sx, sy, sw, se, smu = values
        ground = Body.box(20.0, 1.0, position=(0.0, -0.5), is_static=True)
        disc = Body.circle(r, mass=mass, position=(0.0, r), velocity=(sx, sy), angular_velocity=sw)
        _, tangent = resolve_collision(ground, disc, Contact((0.0, 1.0), 0.0, [(0.0, 0.0)]), restitution=se, friction=smu)
        want = float(np.clip(stick_f(*values), -bound_f(*values), bound_f(*values)))
        regimes.add(abs(want) < bound_f(*values))
        assert tangent[0] == pytest.approx(want, rel=1e-10, abs=1e-12)
        assert disc.velocity[0] == pytest.approx(sx + want / mass, rel=1e-10, abs=1e-12)
    assert regimes == {True, False}  # both sticking and sliding were exercised


@pytest.mark.parametrize("bad", [dict(restitution=1.2), dict(restitution=-0.5), dict(friction=-1.0), dict(friction=math.nan)])
def test_resolve_collision_rejects_bad_coefficients(bad):
    ground = Body.box(20.0, 1.0, is_static=True)
    ball = Body.circle(0.5, position=(0.0, 1.0), velocity=(0.0, -1.0))
    with pytest.raises(ValueError):
        resolve_collision(ground, ball, Contact((0.0, 1.0), 0.0, [(0.0, 0.5)]), **bad)


def test_normal_must_be_a_unit_vector():
    a, b = Body.circle(1.0), Body.circle(1.0, position=(2.0, 0.0))
    with pytest.raises(ValueError):
        relative_normal_velocity(a, b, (1.0, 0.0), (2.0, 0.0))
    with pytest.raises(ValueError):
        normal_impulse_magnitude(a, b, (1.0, 0.0), (1.0, 0.0), 2.0)


def test_small_lcp_against_brute_force():
    # Brute force: among all active sets, the solutions that satisfy every condition.
    rng = np.random.default_rng(15)
    for _ in range(200):
        jac = rng.normal(size=(3, 3))
        matrix = jac @ jac.T + 0.1 * np.eye(3)
        wanted = rng.normal(size=3)
        got = solve_small_lcp(matrix, wanted)
        slack = matrix @ got - wanted
        assert np.all(got >= 0) and np.all(slack >= -1e-9) and abs(got @ slack) <= 1e-9


# ---------------------------------------------------- positional correction
@settings(max_examples=150, deadline=None)
@given(st.floats(0.1, 10), st.floats(0.1, 10), st.floats(0.0, 0.5), st.floats(0.0, 1.0), st.floats(0.0, 0.05),
       st.floats(0, 2 * np.pi), st.booleans())
def test_correct_positions_splits_by_inverse_mass(mass_a, mass_b, depth, percent, slop, angle, a_static):
    normal = np.array([np.cos(angle), np.sin(angle)])
    a = Body.circle(0.5, mass=mass_a, position=(1.0, 2.0), is_static=a_static)
    b = Body.circle(0.5, mass=mass_b, position=np.array([1.0, 2.0]) + (1.0 - depth) * normal)
    centre_of_mass = (mass_a * a.position + mass_b * b.position) / (mass_a + mass_b)
    moved_a, moved_b = correct_positions(a, b, normal, depth, percent=percent, slop=slop)
    overlap_after = 1.0 - np.linalg.norm(b.position - a.position)  # from the circles' geometry
    assert overlap_after == pytest.approx(depth - percent * max(depth - slop, 0.0), abs=1e-12)
    if a_static:
        assert a.position.tolist() == [1.0, 2.0] and moved_a.tolist() == [0.0, 0.0]
    else:
        np.testing.assert_allclose(mass_a * moved_a + mass_b * moved_b, 0.0, atol=1e-12)
        np.testing.assert_allclose((mass_a * a.position + mass_b * b.position) / (mass_a + mass_b), centre_of_mass, atol=1e-12)
        np.testing.assert_allclose(np.linalg.norm(moved_a) * mass_a, np.linalg.norm(moved_b) * mass_b, atol=1e-12)


def test_correct_positions_leaves_touching_and_static_pairs_alone():
    a, b = Body.circle(0.5), Body.circle(0.5, position=(1.0, 0.0))
    assert [d.tolist() for d in correct_positions(a, b, (1.0, 0.0), 0.0)] == [[0.0, 0.0], [0.0, 0.0]]
    assert [d.tolist() for d in correct_positions(a, b, (1.0, 0.0), 0.009)] == [[0.0, 0.0], [0.0, 0.0]]  # within slop
    walls = Body.circle(0.5, is_static=True), Body.circle(0.5, position=(0.9, 0.0), is_static=True)
    correct_positions(*walls, (1.0, 0.0), 0.1)
    assert walls[1].position.tolist() == [0.9, 0.0]
    with pytest.raises(ValueError):
        correct_positions(a, b, (1.0, 0.0), 0.1, percent=1.5)
    with pytest.raises(ValueError):
        correct_positions(a, b, (1.0, 0.0), 0.1, slop=-0.1)
