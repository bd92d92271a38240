"""Checks of the rigid-body impulse: closed forms from sympy, conservation laws, the
reference engine, and a scene driven by the student's resolver (speed and error)."""
from __future__ import annotations

import copy
import math
from functools import lru_cache

import numpy as np
import sympy as sp

from solutions.body import Body
from solutions.contact import Contact
from solutions.response.impulse import effective_mass_inverse, relative_normal_velocity, resolve_collision
from solutions.response.positional_correction import correct_positions

from ..compare import number, show, vector
from ..outcome import Outcome, StudentCallFailed
from . import check
from .cases import random_body, unit_vector

MODULE = "response.impulse"


@lru_cache(maxsize=None)
def impulse_closed_form():
    """j for two rigid bodies with angular terms, solved by sympy from
    v_rel' . n = -e v_rel . n with one impulse +j n on B and -j n on A."""
    ma, mb, ia, ib, e, j = sp.symbols("m_A m_B I_A I_B e j", positive=True)
    vax, vay, vbx, vby, wa, wb, rax, ray, rbx, rby, nx, ny = sp.symbols("vax vay vbx vby wa wb rax ray rbx rby nx ny",
                                                                        real=True)
    n = sp.Matrix([nx, ny])

    def point_velocity(vx, vy, w, rx, ry):
        return sp.Matrix([vx - w * ry, vy + w * rx])

    ra_x_n, rb_x_n = rax * ny - ray * nx, rbx * ny - rby * nx
    before = (point_velocity(vbx, vby, wb, rbx, rby) - point_velocity(vax, vay, wa, rax, ray)).dot(n)
    after = (point_velocity(vbx + j * nx / mb, vby + j * ny / mb, wb + rb_x_n * j / ib, rbx, rby)
             - point_velocity(vax - j * nx / ma, vay - j * ny / ma, wa - ra_x_n * j / ia, rax, ray)).dot(n)
    solution = sp.solve(sp.Eq(after, -e * before), j)[0]
    symbols = (ma, mb, ia, ib, e, vax, vay, vbx, vby, wa, wb, rax, ray, rbx, rby, nx, ny)
    return sp.lambdify(symbols, solution, "math")


def random_contact_case(rng):
    """Two dynamic bodies, a point between them, a unit normal, with the bodies approaching."""
    while True:
        a, b = random_body(rng), random_body(rng)
        point = (a.position + b.position) / 2 + rng.normal(0, 0.2, 2)
        normal = unit_vector(rng)
        if relative_normal_velocity(a, b, point, normal) < -0.1:
            return a, b, point, normal


def expected_j(a, b, point, normal, e):
    ra, rb = point - a.position, point - b.position
    return impulse_closed_form()(a.mass, b.mass, a.inertia, b.inertia, e, *a.velocity, *b.velocity,
                                 a.angular_velocity, b.angular_velocity, *ra, *rb, *normal)


def state(body_data) -> tuple[np.ndarray, float]:
    return np.array(body_data["velocity"], dtype=float), float(body_data["angular_velocity"])


@check("impulse.relative_normal_velocity")
def check_relative_velocity(student):
    rng = np.random.default_rng(601)
    cases = [random_contact_case(rng) for _ in range(20)]
    answers = student.call_many(MODULE, "relative_normal_velocity", cases)
    for (a, b, p, n), got in zip(cases, answers):
        problem = number("v_n", got, relative_normal_velocity(a, b, p, n), rtol=1e-9, atol=1e-9)
        if problem:
            return Outcome.failed(f"{problem}: use the velocities of the contact point, v + w x r, with r "
                                  "measured from each centre of mass, and (v_B - v_A) . n")
    return Outcome.passed(f"{len(cases)} cases agree")


@check("impulse.effective_mass")
def check_effective_mass(student):
    rng = np.random.default_rng(602)
    cases = [random_contact_case(rng) for _ in range(20)]
    cases.append((random_body(rng), random_body(rng, static=True), np.zeros(2), np.array([0.0, 1.0])))
    answers = student.call_many(MODULE, "effective_mass_inverse", cases)
    for (a, b, p, n), got in zip(cases, answers):
        problem = number("1/m_A + 1/m_B + (r_A x n)^2/I_A + (r_B x n)^2/I_B", got,
                         effective_mass_inverse(a, b, p, n), rtol=1e-9, atol=1e-12)
        if problem:
            return Outcome.failed(problem)
    return Outcome.passed(f"{len(cases)} cases agree")


@check("impulse.magnitude")
def check_magnitude(student):
    rng = np.random.default_rng(603)
    cases = []
    for _ in range(25):
        a, b, p, n = random_contact_case(rng)
        cases.append((a, b, p, n, float(rng.uniform(0, 1))))
    answers = student.call_many(MODULE, "normal_impulse_magnitude", cases)
    for (a, b, p, n, e), got in zip(cases, answers):
        want = expected_j(a, b, p, n, e)
        problem = number("j", got, want, rtol=1e-9, atol=1e-12)
        if problem:
            return Outcome.failed(f"{problem}; j = -(1 + e) v_rel.n / (1/m_A + 1/m_B + (r_A x n)^2/I_A + "
                                  "(r_B x n)^2/I_B) (sympy)")
    return Outcome.passed(f"{len(cases)} impulses agree with the sympy closed form")


def momenta(bodies_data, masses, inertias, positions) -> tuple[np.ndarray, float]:
    """Total linear momentum and angular momentum about the origin."""
    linear, angular = np.zeros(2), 0.0
    for data, m, inertia, x in zip(bodies_data, masses, inertias, positions):
        v, w = state(data)
        linear += m * v
        angular += inertia * w + m * (x[0] * v[1] - x[1] * v[0])
    return linear, angular


@check("impulse.apply_impulse")
def check_apply(student):
    rng = np.random.default_rng(604)
    for _ in range(10):
        a, b, p, n = random_contact_case(rng)
        impulse = float(rng.uniform(0.1, 3)) * n
        _, after = student.call_with_state(MODULE, "apply_impulse", a, b, p, impulse)
        want_a, want_b = copy.deepcopy(a), copy.deepcopy(b)
        for body, sign in ((want_a, -1.0), (want_b, 1.0)):
            r = p - body.position
            body.velocity = body.velocity + sign * impulse / body.mass
            body.angular_velocity += sign * (r[0] * impulse[1] - r[1] * impulse[0]) / body.inertia
        for label, data, want in (("A", after[0], want_a), ("B", after[1], want_b)):
            if not isinstance(data, dict):
                return Outcome.failed("apply_impulse must change the bodies it is given")
            v, w = state(data)
            problem = (vector(f"velocity of {label}", v.tolist(), want.velocity)
                       or number(f"angular velocity of {label}", w, want.angular_velocity))
            if problem:
                return Outcome.failed(f"{problem}: +P goes to B and -P to A, each turned by r x P / I")
    return Outcome.passed("10 impulses applied correctly")


@check("impulse.resolve_conserves_momentum")
def check_conservation(student):
    # Independent oracle: one impulse, +P on B and -P on A, conserves linear momentum and
    # angular momentum about any point, and with e <= 1 gains no kinetic energy.
    rng = np.random.default_rng(605)
    for _ in range(12):
        a, b, p, n = random_contact_case(rng)
        a.friction = b.friction = float(rng.uniform(0, 0.8))
        contact = Contact(n, 0.0, [p])
        masses, inertias, positions = (a.mass, b.mass), (a.inertia, b.inertia), (a.position, b.position)
        before = [{"velocity": x.velocity.tolist(), "angular_velocity": x.angular_velocity} for x in (a, b)]
        energy_before = a.kinetic_energy() + b.kinetic_energy()
        _, after = student.call_with_state(MODULE, "resolve_collision", a, b, contact)
        if not all(isinstance(x, dict) for x in after[:2]):
            return Outcome.failed("resolve_collision must change the velocities of the bodies it is given")
        l0, h0 = momenta(before, masses, inertias, positions)
        l1, h1 = momenta(after[:2], masses, inertias, positions)
        problem = vector("total linear momentum after", l1.tolist(), l0, atol=1e-9, rtol=1e-9)
        if problem is None:
            problem = number("angular momentum about the origin after", h1, h0, rtol=1e-9, atol=1e-9)
        if problem:
            return Outcome.failed(f"{problem}: momentum must be conserved; apply ONE impulse, +P to B and -P to A "
                                  "(erratum 22: computing a separate impulse for each body breaks this)")
        energy = sum(0.5 * m * float(state(d)[0] @ state(d)[0]) + 0.5 * i * state(d)[1] ** 2
                     for d, m, i in zip(after[:2], masses, inertias))
        if energy > energy_before * (1 + 1e-9) + 1e-12:
            return Outcome.failed(f"kinetic energy grew from {energy_before:.6g} J to {energy:.6g} J")
    return Outcome.passed("12 collisions conserve momentum and gain no energy")


@check("impulse.resolve_collision")
def check_resolve(student):
    rng = np.random.default_rng(606)
    for k in range(12):
        a, b, p, n = random_contact_case(rng)
        if k % 2:
            a.friction = b.friction = 0.0
        contact = Contact(n, 0.0, [p])
        want_a, want_b = copy.deepcopy(a), copy.deepcopy(b)
        resolve_collision(want_a, want_b, contact)
        _, after = student.call_with_state(MODULE, "resolve_collision", a, b, contact)
        for label, data, want in (("A", after[0], want_a), ("B", after[1], want_b)):
            v, w = state(data)
            problem = (vector(f"velocity of {label}", v.tolist(), want.velocity, atol=1e-9, rtol=1e-9)
                       or number(f"angular velocity of {label}", w, want.angular_velocity, atol=1e-9, rtol=1e-9))
            if problem:
                friction = f" with friction mu = {a.friction * b.friction:.3g}" if a.friction else " without friction"
                return Outcome.failed(f"collision{friction}, e = {a.restitution * b.restitution:.3g}: {problem}")
    return Outcome.passed("12 collisions agree with the reference")


@check("impulse.correct_positions")
def check_correction(student):
    rng = np.random.default_rng(607)
    for static_b in (False, False, True):
        a, b = random_body(rng), random_body(rng, static=static_b)
        n = unit_vector(rng)
        depth = float(rng.uniform(0.02, 0.3))
        want_a, want_b = copy.deepcopy(a), copy.deepcopy(b)
        correct_positions(want_a, want_b, n, depth, 0.8, 0.01)
        _, after = student.call_with_state("response.positional_correction", "correct_positions", a, b, n, depth,
                                           0.8, 0.01)
        for label, data, want in (("A", after[0], want_a), ("B", after[1], want_b)):
            problem = vector(f"position of {label}", data["position"], want.position, atol=1e-12, rtol=1e-9)
            if problem:
                return Outcome.failed(f"depth {depth:.4g} m, masses {a.mass:.3g} and "
                                      f"{'static' if static_b else f'{b.mass:.3g}'} kg: {problem}; move each body by "
                                      "its share of inverse mass of percent * (depth - slop)")
    return Outcome.passed("3 corrections agree")


@check("impulse.scene")
def check_scene(student, reference=None):
    """Balls dropped in a box, stepped with the student's resolve_collision and
    correct_positions; speed against the reference, error against reference and pymunk."""
    from .scene_error import compare_scene
    return compare_scene(student, reference)
