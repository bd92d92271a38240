"""Rigid-body impulses and positional correction against sympy closed forms.

Every expected value comes from :mod:`grader.oracles.impulse_sympy`, which solves the
impulse-momentum equations with sympy (linear and angular momentum of both bodies,
the restitution law on the relative normal velocity, the friction law on the
tangential one) and never imports the reference engine; a few cases carry literal
answers worked by hand (see their comments).  Conventions checked: the normal points
from A to B, lever arms are measured from each centre of mass, the impulse goes +P to
B and -P to A, a static body has 1/m = 1/I = 0, a fixed rotation 1/I = 0, and a pair's
restitution and friction are the products e_A e_B and mu_A mu_B.

The seeded cases cover both dynamic bodies, one static body (A or B), fixed rotation,
one- and two-point manifolds, approaching and separating contacts (and v_n = 0
exactly), velocities and normals in every direction, restitution 0 and 1, friction
off, sticking and sliding.  The limit cases are worked by hand: two static bodies
closing in, k = 1 exactly, friction exactly at the Coulomb limit, infinite friction,
depth - slop of 0 and of 1 m.  Every returned value and every field of both bodies after
the call is compared; NaN or infinite answers never pass.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from grader.harness.compare import number, show, vector
from grader.harness.credit import check_cases, fail
from grader.oracles import impulse_sympy as oracle
from grader.oracles import plain
from grader.oracles.random_cases import unit_vector

MODULE = "response.impulse"
CORRECTION = "response.positional_correction"
#: Velocities (m/s), impulses (N s) and positions (m) of order 1..100 computed in another
#: order of floating-point operations agree far better than this.
RTOL, ATOL = 1e-9, 1e-9
#: Fields a function must leave alone keep their exact value (up to this).
EXACT = 1e-12


# Bodies and contacts ------------------------------------------------------------------------
def make_body(rng: np.random.Generator, kind: str, position=(0.0, 0.0), shape: str | None = None) -> dict:
    """A disc or box (kind: "dynamic", "static", "fixed" rotation) with velocities in
    any direction.  A static body keeps a mass value (1/m must still be 0) and no
    velocity; a fixed-rotation body has no spin."""
    shape = shape or ("circle" if rng.random() < 0.5 else "box")
    local = (plain.circle((0, 0), float(rng.uniform(0.2, 0.9))) if shape == "circle"
             else plain.obb((0, 0), (float(rng.uniform(0.2, 0.9)), float(rng.uniform(0.15, 0.6))), 0.0))
    static, fixed = kind == "static", kind == "fixed"
    return plain.body(local, mass=float(rng.uniform(0.3, 5.0)), position=position, angle=float(rng.uniform(-3, 3)),
                      velocity=(0.0, 0.0) if static else rng.normal(0, 3, 2),
                      angular_velocity=0.0 if static or fixed else float(rng.normal(0, 2.5)),
                      restitution=float(rng.uniform(0.1, 1.0)), friction=float(rng.uniform(0.1, 1.2)),
                      is_static=static, fixed_rotation=fixed)


def reversed_motion(body: dict) -> dict:
    """The body moving the other way (0.0 - v: no negative zeros in messages)."""
    return {**body, "velocity": [0.0 - body["velocity"][0], 0.0 - body["velocity"][1]],
            "angular_velocity": 0.0 - body["angular_velocity"]}


def contact_pair(rng: np.random.Generator, kinds: tuple[str, str], motion: str = "approach",
                 points: int = 1) -> tuple[dict, dict, dict]:
    """Bodies A and B side by side along a random normal n (A to B), the contact point(s)
    between them off the line of centres, and the motion chosen so that the contact
    approaches (v_n < 0 at the first point) or separates (v_n > 0 at every point)."""
    while True:
        n = unit_vector(rng)
        t = np.array([n[1], -n[0]])
        a = make_body(rng, kinds[0], position=rng.uniform(-3, 3, 2))
        gap = float(rng.uniform(0.6, 1.6))
        b = make_body(rng, kinds[1], position=np.asarray(a["position"]) + gap * n + rng.normal(0, 0.2, 2))
        middle = (np.asarray(a["position"]) + np.asarray(b["position"])) / 2
        if points == 1:
            chosen = [middle + float(rng.uniform(-0.5, 0.5)) * t]
        else:
            offset, half = float(rng.uniform(-0.2, 0.2)), float(rng.uniform(0.2, 0.6))
            chosen = [middle + (offset - half) * t, middle + (offset + half) * t]
        contact = plain.contact(n, float(rng.uniform(0.0, 0.1)), chosen)
        v_n = [oracle.relative_normal_velocity(a, b, p, n) for p in chosen]
        if motion == "approach" and v_n[0] > 0:
            a, b = reversed_motion(a), reversed_motion(b)
            v_n = [-v for v in v_n]
        if motion == "separate" and max(v_n) < 0:
            a, b = reversed_motion(a), reversed_motion(b)
            v_n = [-v for v in v_n]
        good = v_n[0] < -0.05 if motion == "approach" else min(v_n) > 0.05
        if good and (points == 1 or well_conditioned(a, b, contact)):
            return a, b, contact


def well_conditioned(a: dict, b: dict, contact: dict) -> bool:
    """Two points whose normal impulses are unique and stable (some body turns)."""
    matrix = oracle.response_matrix(a, b, contact["points"], contact["normal"])
    return bool(np.linalg.cond(matrix) < 1e6)


#: Which bodies can move: both dynamic, A or B static, fixed rotations.
SINGLE_KINDS = [("dynamic", "dynamic"), ("static", "dynamic"), ("dynamic", "static"), ("fixed", "dynamic"),
                ("dynamic", "fixed"), ("fixed", "static"), ("static", "fixed"), ("fixed", "fixed")]
#: Two-point manifolds need a body that turns, or the split between the points is not unique.
PAIR_KINDS = [("dynamic", "dynamic"), ("static", "dynamic"), ("dynamic", "static"), ("fixed", "dynamic"),
              ("dynamic", "fixed")]


def ground_and(body: dict) -> tuple[dict, dict]:
    """Static ground (A, a 10 m x 1 m box centred at (0, -0.5), mass value 3 kg) and ``body`` (B)."""
    ground = plain.body(plain.obb((0, 0), (5.0, 0.5), 0.0), mass=3.0, position=(0.0, -0.5), is_static=True,
                        restitution=1.0, friction=1.0)
    return ground, body


# Describing cases and comparing bodies -----------------------------------------------------
def show_inputs(a: dict, b: dict, *rest) -> str:
    shown = ", ".join(oracle.show_contact(x) if isinstance(x, dict) else show(to_plain(x)) for x in rest)
    return f"(A: {oracle.show_body(a)}; B: {oracle.show_body(b)}; {shown})"


def to_plain(value):
    if isinstance(value, np.ndarray):
        return [float(v) for v in value]
    if isinstance(value, (list, tuple)):
        return type(value)(to_plain(v) for v in value)
    if isinstance(value, (np.floating, np.integer)):
        return float(value)
    return value


def normal_velocities(a: dict, b: dict, contact: dict) -> str:
    values = [oracle.relative_normal_velocity(a, b, p, contact["normal"]) for p in contact["points"]]
    return "v_n = (v_B(p) - v_A(p)) . n = [" + ", ".join(f"{v:.6g}" for v in values) + "] m/s"


def body_problem(label: str, got, want: dict, changed: tuple[str, ...]) -> str | None:
    """Every field of body ``label`` after the call: ``changed`` fields to the oracle's
    value within RTOL/ATOL, every other field exactly as before."""
    if not isinstance(got, dict):
        return f"body {label} did not come back as a body, got {show(got)}"
    for name in ("velocity", "position"):
        tolerance = (ATOL, RTOL) if name in changed else (EXACT, 0.0)
        problem = vector(f"{name} of {label}", got.get(name), want[name], atol=tolerance[0], rtol=tolerance[1])
        if problem:
            return problem if name in changed else f"{problem}: this call must not change the {name}"
    for name in ("angular_velocity", "angle", "mass", "restitution", "friction"):
        tolerance = (ATOL, RTOL) if name in changed else (EXACT, 0.0)
        problem = number(f"{name} of {label}", got.get(name), want[name], atol=tolerance[0], rtol=tolerance[1])
        if problem:
            return problem if name in changed else f"{problem}: this call must not change the {name}"
    for name in ("is_static", "fixed_rotation", "is_bullet"):
        if got.get(name) is not want[name]:
            return f"{name} of {label}: expected {want[name]}, got {show(got.get(name))}: this call must not change it"
    if got.get("shape") != want["shape"]:
        return f"the shape of {label} changed: expected {show(want['shape'])}, got {show(got.get('shape'))}"
    return None


# Relative normal velocity -----------------------------------------------------------------
def velocity_cases() -> list[tuple]:
    rng = np.random.default_rng(601)
    cases = []
    # Worked by hand (docstring): ground at rest, ball falling at 2 m/s, n = +y: v_n = -2.
    ground, ball = ground_and(plain.body(plain.circle((0, 0), 0.5), position=(0.0, 1.0), velocity=(0.0, -2.0)))
    cases.append((ground, ball, [0.0, 0.5], [0.0, 1.0]))
    # By hand: the centres separate along x (v_A = (-0.1, 0), v_B = (0.1, 0)) but B spins at
    # w = 2 rad/s; r_B = p - x_B = (-0.5, 0.5), w x r_B = (-1, -1), v_B(p) = (-0.9, -1):
    # v_n = (-0.9 - (-0.1)) * 1 = -0.8, the point approaches.
    a = plain.body(plain.circle((0, 0), 0.5), position=(0.0, 0.0), velocity=(-0.1, 0.0))
    b = plain.body(plain.circle((0, 0), 0.5), position=(1.0, 0.0), velocity=(0.1, 0.0), angular_velocity=2.0)
    cases.append((a, b, [0.5, 0.5], [1.0, 0.0]))
    # By hand: lever arm from the centre of mass, not from the origin.  A at (2, 3) with
    # v = (0, 1), w = 1; p = (2, 4): r_A = (0, 1), w x r_A = (-1, 0), v_A(p) = (-1, 1);
    # B static: v_n = -(v_A(p) . (0, 1)) = -1.
    a = plain.body(plain.circle((0, 0), 0.6), position=(2.0, 3.0), velocity=(0.0, 1.0), angular_velocity=1.0)
    b = plain.body(plain.circle((0, 0), 0.6), position=(2.0, 5.0), is_static=True)
    cases.append((a, b, [2.0, 4.0], [0.0, 1.0]))
    # By hand: sliding along the ground, exactly v_n = 0.
    ground, box = ground_and(plain.body(plain.obb((0, 0), (0.5, 0.5), 0.0), position=(0.0, 0.5), velocity=(2.0, 0.0)))
    cases.append((ground, box, [0.3, 0.0], [0.0, 1.0]))
    for k in range(24):
        a, b, contact = contact_pair(rng, SINGLE_KINDS[k % len(SINGLE_KINDS)], "approach" if k % 3 else "separate")
        cases.append((a, b, contact["points"][0], contact["normal"]))
    return cases


@pytest.mark.points(1)
@pytest.mark.title("Relative normal velocity at the contact point")
def test_relative_normal_velocity(student):
    """v_n = (v_B + w_B x r_B - v_A - w_A x r_A) . n, approaching and separating."""
    cases = velocity_cases()
    answers = student.call_many(MODULE, "relative_normal_velocity", cases)

    def problem(case_answer):
        (a, b, p, n), got = case_answer
        found = number("v_n", got, oracle.relative_normal_velocity(a, b, p, n), rtol=RTOL, atol=ATOL)
        return found and (f"{found}; use the velocity of each body's material point at p, v + w x r with r = p - x "
                          "from the centre of mass, and (v_B(p) - v_A(p)) . n (negative while approaching)")

    check_cases(zip(cases, answers), problem, "relative_normal_velocity",
                describe=lambda ca: f"relative_normal_velocity{show_inputs(*ca[0][:2], ca[0][2], ca[0][3])}")


# Inverse effective mass ---------------------------------------------------------------------
def effective_mass_cases() -> list[tuple]:
    rng = np.random.default_rng(602)
    # By hand (docstring): 2 kg disc above static ground, impulse through its centre: k = 1/2.
    ground, ball = ground_and(plain.body(plain.circle((0, 0), 0.5), mass=2.0, position=(0.0, 1.0)))
    cases = [(ground, ball, [0.0, 0.5], [0.0, 1.0])]
    # By hand: two static bodies: k = 0 (no 1/m from their mass values).
    cases.append((ground, {**ball, "is_static": True, "velocity": [0.0, 0.0]}, [0.0, 0.5], [0.0, 1.0]))
    for k in range(26):
        a, b, contact = contact_pair(rng, SINGLE_KINDS[k % len(SINGLE_KINDS)], "approach" if k % 2 else "separate")
        cases.append((a, b, contact["points"][0], contact["normal"]))
    # The point on A's line of action (r_A x n = 0): only B's angular term remains.
    a, b, contact = contact_pair(rng, ("dynamic", "dynamic"))
    n = np.asarray(contact["normal"])
    cases.append((a, b, (np.asarray(a["position"]) + 0.7 * n).tolist(), contact["normal"]))
    return cases


@pytest.mark.points(1)
@pytest.mark.title("Inverse effective mass along the normal")
def test_effective_mass(student):
    """k = 1/m_A + 1/m_B + (r_A x n)^2/I_A + (r_B x n)^2/I_B, static and fixed-rotation terms 0."""
    cases = effective_mass_cases()
    answers = student.call_many(MODULE, "effective_mass_inverse", cases)

    def problem(case_answer):
        (a, b, p, n), got = case_answer
        return number("1/m_A + 1/m_B + (r_A x n)^2/I_A + (r_B x n)^2/I_B", got,
                      oracle.effective_mass_inverse(a, b, p, n), rtol=RTOL, atol=1e-12)

    check_cases(zip(cases, answers), problem, "effective_mass_inverse",
                describe=lambda ca: f"effective_mass_inverse{show_inputs(*ca[0][:2], ca[0][2], ca[0][3])} "
                                    "(a static body has 1/m = 1/I = 0, a fixed rotation 1/I = 0)")


# Impulse magnitude ------------------------------------------------------------------------------
def magnitude_cases() -> list[tuple]:
    rng = np.random.default_rng(603)
    # By hand (docstring): 2 kg ball hits static ground at 3 m/s, e = 0.5: j = 1.5 * 3 * 2 = 9.
    ground, ball = ground_and(plain.body(plain.circle((0, 0), 0.5), mass=2.0, position=(0.0, 1.0),
                                         velocity=(0.0, -3.0)))
    cases = [(ground, ball, [0.0, 0.5], [0.0, 1.0], 0.5)]
    # Separating at 3 m/s: j = 0 (never pull).
    cases.append((ground, reversed_motion(ball), [0.0, 0.5], [0.0, 1.0], 0.5))
    # Sliding along the ground, v_n = 0 exactly: j = 0.
    cases.append((ground, {**ball, "velocity": [2.5, 0.0]}, [0.0, 0.5], [0.0, 1.0], 1.0))
    # Two static bodies: j = 0 (k = 0, no division).
    cases.append((ground, {**ground, "position": [0.0, 0.5]}, [0.0, 0.0], [0.0, 1.0], 0.5))
    for k in range(30):
        motion = "separate" if k % 4 == 3 else "approach"
        a, b, contact = contact_pair(rng, SINGLE_KINDS[k % len(SINGLE_KINDS)], motion)
        e = (0.0, 1.0, float(rng.uniform(0, 1)))[k % 3]
        cases.append((a, b, contact["points"][0], contact["normal"], e))
    return cases


def magnitude_problem(case: tuple, got) -> str | None:
    a, b, p, n, e = case
    want = oracle.normal_impulse(a, b, p, n, e)
    found = number("j", got, want, rtol=RTOL, atol=1e-12)
    if not found:
        return None
    v_n = oracle.relative_normal_velocity(a, b, p, n)
    if v_n >= 0:
        return (f"{found}; here v_n = {v_n:.6g} m/s >= 0 (separating or sliding): a contact pushes, never "
                "pulls, so j = 0")
    k = oracle.effective_mass_inverse(a, b, p, n)
    if k == 0:
        return (f"{found}; both bodies are static (k = 0 1/kg, here v_n = {v_n:.6g} m/s): no impulse can move "
                "them, so j = 0 (and no division by k)")
    return (f"{found}; v_n = {v_n:.6g} m/s, k = {k:.6g} 1/kg: "
            "j = -(1 + e) v_n / k with k = 1/m_A + 1/m_B + (r_A x n)^2/I_A + (r_B x n)^2/I_B (sympy)")


@pytest.mark.points(2)
@pytest.mark.title("Impulse magnitude with angular terms (sympy)")
def test_magnitude(student):
    """j = -(1 + e) v_n / k for approaching contacts, 0 for separating ones."""
    cases = magnitude_cases()
    answers = student.call_many(MODULE, "normal_impulse_magnitude", cases)
    check_cases(zip(cases, answers), lambda ca: magnitude_problem(*ca), "normal_impulse_magnitude",
                describe=lambda ca: f"normal_impulse_magnitude{show_inputs(*ca[0][:2], *ca[0][2:])}")


# Applying one impulse ----------------------------------------------------------------------------
def apply_cases() -> list[tuple]:
    rng = np.random.default_rng(604)
    cases = []
    # By hand (docstring): 1 N s along +x through both centres of two 1 kg discs: v_A = (-1, 0), v_B = (1, 0).
    a = plain.body(plain.circle((0, 0), 0.5), position=(0.0, 0.0))
    b = plain.body(plain.circle((0, 0), 0.5), position=(1.0, 0.0))
    cases.append((a, b, [0.5, 0.0], [1.0, 0.0]))
    for k in range(16):
        a, b, contact = contact_pair(rng, SINGLE_KINDS[k % len(SINGLE_KINDS)], "approach" if k % 2 else "separate")
        # Any direction: along the normal, against it, or oblique (friction impulses are oblique).
        impulse = float(rng.uniform(0.2, 4.0)) * unit_vector(rng)
        cases.append((a, b, contact["points"][0], impulse.tolist()))
    return cases


@pytest.mark.points(2)
@pytest.mark.title("Applying one impulse to two bodies")
def test_apply_impulse(student):
    """+P to B and -P to A, each turned by r x P / I; static bodies and fixed rotations stay."""
    cases = apply_cases()
    results = [student.call_with_state(MODULE, "apply_impulse", *case) for case in cases]

    def problem(case_result):
        (a, b, p, impulse), (_, after) = case_result
        want_a, want_b = oracle.apply_impulse(a, b, p, impulse)
        found = (body_problem("A", after[0], want_a, ("velocity", "angular_velocity"))
                 or body_problem("B", after[1], want_b, ("velocity", "angular_velocity")))
        expected = (f"A: v = {show(want_a['velocity'])}, w = {want_a['angular_velocity']:.10g}; "
                    f"B: v = {show(want_b['velocity'])}, w = {want_b['angular_velocity']:.10g}")
        return found and (f"{found}; v_B += P/m_B, w_B += (r_B x P)/I_B, v_A -= P/m_A, w_A -= (r_A x P)/I_A with "
                          f"r = p - x (expected {expected})")

    check_cases(zip(cases, results), problem, "apply_impulse",
                describe=lambda cr: f"apply_impulse{show_inputs(*cr[0][:2], cr[0][2], cr[0][3])}")


# Resolving a collision -----------------------------------------------------------------------------
def resolve_cases() -> list[tuple]:
    """Argument tuples for resolve_collision: (A, B, contact) or (A, B, contact, e, mu)."""
    rng = np.random.default_rng(606)
    cases = []
    # By hand (docstring): a 1 kg box lands flat at 2 m/s on static ground, e = 0.5: each corner
    # takes 1.5 N s, the box leaves at 1 m/s without spinning (friction 0 as nothing slides).
    ground, box = ground_and(plain.body(plain.obb((0, 0), (0.5, 0.5), 0.0), position=(0.0, 1.0),
                                        velocity=(0.0, -2.0)))
    corners = plain.contact((0.0, 1.0), 0.0, [(-0.5, 0.5), (0.5, 0.5)])
    cases.append((ground, box, corners, 0.5, 0.0))
    # The same landing tilted by a spin: one corner approaches, the other leaves; default materials.
    cases.append((ground, {**box, "velocity": [0.4, -1.0], "angular_velocity": 3.0, "restitution": 0.6,
                           "friction": 0.5}, corners))
    # Sliding along the ground with v_n = 0 exactly: nothing happens, even with friction.
    cases.append((ground, {**box, "velocity": [2.0, 0.0], "friction": 0.8}, corners))
    # One point, approaching, every kind of pair, default materials (e = e_A e_B, mu = mu_A mu_B).
    for k in range(16):
        cases.append(contact_pair(rng, SINGLE_KINDS[k % len(SINGLE_KINDS)]))
    # Explicit restitution 0 and 1, friction off, sticking (large mu) and sliding (small mu).
    for k, (e, mu) in enumerate([(0.0, 0.0), (1.0, 0.0), (0.0, 5.0), (1.0, 0.05), (0.3, 0.0), (1.0, 3.0)]):
        cases.append((*contact_pair(rng, SINGLE_KINDS[k % 5]), e, mu))
    # Two-point manifolds, approaching.
    for k in range(8):
        cases.append(contact_pair(rng, PAIR_KINDS[k % len(PAIR_KINDS)], points=2))
    # Separating contacts (one and two points): nothing changes, all impulses 0.
    for k in range(6):
        cases.append(contact_pair(rng, PAIR_KINDS[k % len(PAIR_KINDS)], "separate", points=1 + k % 2))
    return cases


def resolve_problem(case: tuple, result) -> str | None:
    a, b, contact, *materials = case
    value, after = result
    want_a, want_b, want_jn, want_jt = oracle.resolve_collision(a, b, contact, *materials)
    if not isinstance(value, list) or len(value) != 2:
        return f"must return (normal_impulses, tangent_impulses), got {show(value)}"
    found = (body_problem("A", after[0], want_a, ("velocity", "angular_velocity"))
             or body_problem("B", after[1], want_b, ("velocity", "angular_velocity"))
             or vector("normal impulses j_i (returned)", value[0], want_jn, atol=ATOL, rtol=RTOL)
             or vector("tangent impulses j_t along t = (n_y, -n_x) (returned)", value[1], want_jt, atol=ATOL,
                       rtol=RTOL))
    if not found:
        return None
    e = a["restitution"] * b["restitution"] if not materials else materials[0]
    mu = a["friction"] * b["friction"] if not materials else materials[1]
    if not any(want_jn):
        hint = ("no point approaches, so nothing may change: a contact pushes, never pulls, and friction acts only "
                "where a normal impulse does")
    else:
        hint = (f"expected normal impulses {show(want_jn)}, tangent impulses {show(want_jt)}, "
                f"A: v = {show(want_a['velocity'])}, w = {want_a['angular_velocity']:.10g}; "
                f"B: v = {show(want_b['velocity'])}, w = {want_b['angular_velocity']:.10g}")
    return f"{found} (e = {e:.6g}, mu = {mu:.6g}, {normal_velocities(a, b, contact)} before); {hint}"


def describe_resolve(case: tuple) -> str:
    a, b, contact, *materials = case
    extra = f", restitution={materials[0]:g}, friction={materials[1]:g}" if materials else ""
    return f"resolve_collision{show_inputs(a, b, contact)[:-1]}{extra})"


@pytest.mark.points(3)
@pytest.mark.title("Collision response with restitution and friction")
def test_resolve_collision(student):
    """Normal impulses of all points at once, then one Coulomb friction pass."""
    cases = resolve_cases()
    results = [student.call_with_state(MODULE, "resolve_collision", *case) for case in cases]
    check_cases(zip(cases, results), lambda cr: resolve_problem(*cr), "resolve_collision",
                describe=lambda cr: describe_resolve(cr[0]))


# Positional correction --------------------------------------------------------------------------
def correction_cases() -> list[tuple]:
    """(A, B, normal, depth, percent, slop) or (A, B, normal, depth) for the defaults 0.8 and 0.01."""
    rng = np.random.default_rng(607)
    # By hand (docstring): 1 kg and 3 kg discs overlapping 0.11 m along x, defaults: the light one
    # moves 3/4 of 0.8 * (0.11 - 0.01) = 0.08 m: -0.06 m, the heavy one +0.02 m.
    a = plain.body(plain.circle((0, 0), 0.5), mass=1.0, position=(0.0, 0.0))
    b = plain.body(plain.circle((0, 0), 0.5), mass=3.0, position=(0.89, 0.0))
    cases = [(a, b, [1.0, 0.0], 0.11)]
    kinds = [("dynamic", "dynamic"), ("static", "dynamic"), ("dynamic", "static"), ("fixed", "dynamic")]
    for k in range(12):
        a, b, contact = contact_pair(rng, kinds[k % 4])
        percent, slop = ((1.0, 0.0), (0.8, 0.01), (0.5, 0.02), (0.2, 0.005))[k % 4]
        cases.append((a, b, contact["normal"], float(rng.uniform(0.03, 0.4)), percent, slop))
    a, b, contact = contact_pair(rng, ("dynamic", "dynamic"))
    n = contact["normal"]
    cases += [(a, b, n, 0.3),  # the defaults again, any direction
              (a, b, n, 0.005, 0.8, 0.01),  # within the slop: nothing moves
              (a, b, n, 0.01, 0.8, 0.01),  # exactly the slop: nothing moves
              (a, b, n, -0.2, 0.8, 0.01),  # apart: nothing moves
              (a, b, n, 0.2, 0.0, 0.01),  # percent 0: nothing moves
              ({**a, "is_static": True}, {**b, "is_static": True}, n, 0.2, 0.8, 0.01)]  # both static
    return cases


def correction_problem(case: tuple, result) -> str | None:
    a, b, n, depth, *rest = case
    percent, slop = rest if rest else (0.8, 0.01)
    value, after = result
    want_a, want_b, moved_a, moved_b = oracle.correct_positions(a, b, n, depth, percent, slop)
    if not isinstance(value, list) or len(value) != 2:
        return f"must return (displacement_a, displacement_b), got {show(value)}"
    found = (body_problem("A", after[0], want_a, ("position",))
             or body_problem("B", after[1], want_b, ("position",))
             or vector("displacement_a (returned)", value[0], moved_a, atol=EXACT, rtol=RTOL)
             or vector("displacement_b (returned)", value[1], moved_b, atol=EXACT, rtol=RTOL))
    if not found:
        return None
    return (f"{found}; expected moves A {show(moved_a)}, B {show(moved_b)} m: C = percent * max(depth - slop, 0) / "
            f"(1/m_A + 1/m_B), x_A -= C/m_A n, x_B += C/m_B n (percent = {percent:g}, slop = {slop:g} m); "
            "velocities stay, static bodies do not move")


def describe_correction(case: tuple) -> str:
    a, b, n, depth, *rest = case
    extra = f", percent={rest[0]:g}, slop={rest[1]:g}" if rest else " (default percent and slop)"
    return f"correct_positions{show_inputs(a, b, n)[:-1]}, depth={depth:g}{extra})"


@pytest.mark.points(2)
@pytest.mark.title("Positional correction by inverse mass")
def test_correct_positions(student):
    """Each body moves by its share of inverse mass of percent * (depth - slop)."""
    cases = correction_cases()
    results = [student.call_with_state(CORRECTION, "correct_positions", *case) for case in cases]
    check_cases(zip(cases, results), lambda cr: correction_problem(*cr), "correct_positions",
                describe=lambda cr: describe_correction(cr[0]))


# Limits and thresholds ----------------------------------------------------------------------------
def limit_cases() -> list[tuple[str, tuple, str]]:
    """(function, arguments, what the case is about): the boundaries of the three
    functions.  Every expected answer is worked by hand below (and is also what the sympy
    oracle gives, which the test compares with)."""
    up, down = [0.0, 1.0], [0.0, -1.0]
    cases = []

    def add(function, args, why):
        cases.append((function, args, why))

    ball = plain.body(plain.circle((0, 0), 0.5), mass=1.0, position=(0.0, 0.5), velocity=(0.0, -3.0))
    ground, ball = ground_and(ball)
    # A 1 kg ball hits the ground at 3 m/s through its centre, e = 0.5: k = 1/1 = 1 1/kg exactly,
    # j = 1.5 * 3 / 1 = 4.5 N s.
    add("normal_impulse_magnitude", (ground, ball, [0.0, 0.0], up, 0.5), "k = 1 1/kg exactly")
    # The static body on side B: the ball A above static ground B, n = (0, -1) from A to B,
    # v_n = (0 - (-3)) * -1 = -3 m/s, k = 1: j = 2 * 3 / 1 = 6 N s (e = 1).
    add("normal_impulse_magnitude", (ball, ground, [0.0, 0.0], down, 1.0), "static body B, k = 1 1/kg")
    # Two static bodies closing in: a static platform A, moved by a script up at 2 m/s, under a
    # static crate B: v_n = -2 m/s but k = 0: no impulse can move them, j = 0.
    platform = {**ground, "velocity": [0.0, 2.0]}
    crate = plain.body(plain.obb((0, 0), (0.5, 0.5), 0.0), mass=2.0, position=(0.0, 0.5), is_static=True,
                       restitution=0.5, friction=0.5)
    add("normal_impulse_magnitude", (platform, crate, [0.0, 0.0], up, 0.5), "two static bodies closing in")
    add("resolve_collision", (platform, crate, plain.contact(up, 0.0, [(0.0, 0.0)]), 0.5, 0.5),
        "two static bodies closing in: nothing moves")

    # A 1 kg box with fixed rotation lands sliding on the ground at one point below its centre:
    # k = k_t = 1 1/kg exactly (no angular terms).  e = 0.5: j = 1.5 * 3 = 4.5 N s, v_y' = 1.5 m/s;
    # t = (n_y, -n_x) = (1, 0), the impulse that stops v_t = v_x is j_t = -v_x, clamped to
    # |j_t| <= mu j.
    slider = plain.body(plain.obb((0, 0), (0.5, 0.5), 0.0), mass=1.0, position=(0.0, 0.5), velocity=(2.0, -3.0),
                        fixed_rotation=True)
    under = plain.contact(up, 0.0, [(0.0, 0.0)])
    # mu = 1: j_t = -2 (inside the limit 4.5): v' = (0, 1.5).
    add("resolve_collision", (ground, slider, under, 0.5, 1.0), "mu = 1, k_t = 1 1/kg, sticks")
    # v_x = 4.5 m/s: j_t = -4.5 = -mu j exactly, at the Coulomb limit: v' = (0, 1.5).
    add("resolve_collision", (ground, {**slider, "velocity": [4.5, -3.0]}, under, 0.5, 1.0),
        "exactly at the Coulomb limit |j_t| = mu j")
    add("resolve_collision", (ground, {**slider, "velocity": [-4.5, -3.0]}, under, 0.5, 1.0),
        "exactly at the Coulomb limit |j_t| = mu j, sliding the other way")
    # v_x = 6 m/s, mu = 0.5: the limit 2.25 N s clamps j_t = -2.25: v' = (3.75, 1.5).
    add("resolve_collision", (ground, {**slider, "velocity": [6.0, -3.0]}, under, 0.5, 0.5),
        "beyond the Coulomb limit: clamped to -mu j")
    # Static body B: the slider A above static ground B, n = (0, -1), t = (-1, 0); e = 1: j = 6 N s,
    # v_t = (0 - 2) * -1 = 2 m/s, j_t = -2 (limit 0.5 * 6 = 3): A gets -(j n + j_t t) = (-2, 6):
    # v_A' = (0, 3).
    add("resolve_collision", (slider, ground, plain.contact(down, 0.0, [(0.0, 0.0)]), 1.0, 0.5),
        "static body B")

    # Infinite friction (mu = inf: no sliding at all).  A 1 kg disc r = 0.5 m (I = 0.125 kg m^2)
    # lands at (2, -3) m/s: j = 4.5 N s (r x n = 0), then j_t = -v_t / k_t with
    # k_t = 1 + 0.5^2 / 0.125 = 3 1/kg: j_t = -2/3 N s, v' = (4/3, 1.5); r = (0, -0.5),
    # r x P = -(-0.5)(-2/3) = -1/3, w' = -1/3 / 0.125 = -8/3 rad/s: the contact point rolls
    # (v + w x r = 4/3 - 4/3 = 0 along t).
    disc = {**ball, "velocity": [2.0, -3.0]}
    add("resolve_collision", (ground, disc, under, 0.5, math.inf), "mu = inf: the point sticks")
    # Separating (the disc moves up and sideways): j = 0, so no friction either, even with
    # mu = inf (mu j = inf * 0 is not a number: skip points without normal impulse).
    add("resolve_collision", (ground, {**disc, "velocity": [2.0, 1.0], "angular_velocity": 1.0}, under, 0.5,
                              math.inf), "mu = inf, separating: nothing happens")
    # Sliding flat along the ground, v_n = 0 exactly at both corners: nothing happens.
    box = plain.body(plain.obb((0, 0), (0.5, 0.5), 0.0), mass=1.0, position=(0.0, 0.5), velocity=(2.0, 0.0))
    corners = plain.contact(up, 0.0, [(-0.5, 0.0), (0.5, 0.0)])
    add("resolve_collision", (ground, box, corners, 0.5, math.inf), "mu = inf, v_n = 0 exactly: nothing happens")
    # Landing tilted by a spin w = 6 rad/s: the left corner approaches (v_n = -1 - 6 * 0.5 = -4 m/s),
    # the right one leaves (v_n = -1 + 3 = +2 m/s).  I = 1/6 kg m^2, K = [[2.5, -0.5], [-0.5, 2.5]]:
    # the left corner alone takes 1.5 * 4 / 2.5 = 2.4 N s, which leaves the right one at
    # 2 - 0.5 * 2.4 = +0.8 m/s: it gets neither a normal nor a friction impulse (sympy for the rest).
    add("resolve_collision", (ground, {**box, "velocity": [0.4, -1.0], "angular_velocity": 6.0}, corners, 0.5,
                              math.inf), "mu = inf, one corner leaving")

    # Positional correction around the slop.  1 kg and 3 kg discs along x: the light one takes
    # 3/4 of the correction.  depth - slop = 1.25 - 0.25 = 1 m exactly, percent 0.5: the bodies
    # move 0.5 m apart, A by -0.375 m, B by +0.125 m.
    light = plain.body(plain.circle((0, 0), 0.5), mass=1.0, position=(0.0, 0.0))
    heavy = plain.body(plain.circle((0, 0), 0.5), mass=3.0, position=(0.5, 0.0))
    along_x = [1.0, 0.0]
    add("correct_positions", (light, heavy, along_x, 1.25, 0.5, 0.25), "depth - slop = 1 m exactly")
    # Static A: B alone moves the whole percent * (depth - slop) = 1 * (2 - 1) = 1 m.
    add("correct_positions", ({**light, "is_static": True}, heavy, along_x, 2.0, 1.0, 1.0),
        "static A, depth - slop = 1 m exactly")
    # Static B: A alone moves -percent * (depth - slop) = -0.8 * (1.5 - 0.5) = -0.8 m.
    add("correct_positions", (light, {**heavy, "is_static": True}, along_x, 1.5, 0.8, 0.5),
        "static B, depth - slop = 1 m exactly")
    # depth exactly the slop (0.5 m), and depth = slop = 0: nothing moves.
    add("correct_positions", (light, heavy, along_x, 0.5, 0.8, 0.5), "depth exactly equal to the slop")
    add("correct_positions", (light, heavy, along_x, 0.0, 1.0, 0.0), "depth = slop = 0")
    # Just beyond the default slop: 0.8 * (0.011 - 0.01) = 0.0008 m in all, A -0.0006 m, B +0.0002 m.
    add("correct_positions", (light, heavy, along_x, 0.011), "depth just beyond the default slop")
    return cases


def limit_problem(case: tuple, result) -> str | None:
    function, args, why = case
    if not result.ok:
        return f"raised: {result.message.strip()[-300:]}"
    if function == "normal_impulse_magnitude":
        found = magnitude_problem(args, result.value)
    elif function == "resolve_collision":
        found = resolve_problem(args, (result.value, result.args_after))
        if found and math.isinf(args[4]):
            found += ("; with mu = inf the friction impulse is the whole sticking impulse -v_t / k_t, and a point "
                      "with j_i = 0 gets none (skip it: inf * 0 is not a number)")
    else:
        found = correction_problem(args, (result.value, result.args_after))
    return found and f"{found} [{why}]"


def describe_limit(case: tuple) -> str:
    function, args, _ = case
    if function == "normal_impulse_magnitude":
        return f"normal_impulse_magnitude{show_inputs(*args)}"
    return describe_resolve(args) if function == "resolve_collision" else describe_correction(args)


@pytest.mark.points(1)
@pytest.mark.title("Limits: static pairs, k = 1, the Coulomb limit, infinite friction, the slop")
def test_limits(student):
    """Boundaries worked by hand: two static bodies, k = 1, |j_t| = mu j, mu = inf, depth - slop = 0 or 1"""
    cases = limit_cases()
    results = []
    for function, args, _ in cases:
        module = CORRECTION if function == "correct_positions" else MODULE
        result = student.raw(module, function, *args)
        if result.status in ("not_implemented", "timeout", "crashed"):
            student.value_of(result, f"{module}.{function}")  # stops the test with that status
        results.append(result)
    check_cases(zip(cases, results), lambda cr: limit_problem(cr[0], cr[1]), "limit cases",
                describe=lambda cr: describe_limit(cr[0]))


# Any case (Hypothesis) ----------------------------------------------------------------------------
def rounded(low: float, high: float, digits: int = 2):
    """Floats in [low, high] rounded to ``digits`` decimals (cases that read and shrink well)."""
    return st.floats(low, high, allow_nan=False).map(lambda v: round(v, digits))


@st.composite
def bodies(draw, kinds=("dynamic", "dynamic", "static", "fixed")):
    kind = draw(st.sampled_from(kinds))
    if draw(st.booleans()):
        shape = plain.circle((0, 0), draw(rounded(0.1, 1.5)))
    else:
        shape = plain.obb((0, 0), (draw(rounded(0.1, 1.5)), draw(rounded(0.1, 1.5))), 0.0)
    moving = kind != "static"
    return plain.body(shape, mass=draw(rounded(0.1, 10.0)), position=(draw(rounded(-4, 4)), draw(rounded(-4, 4))),
                      angle=draw(rounded(-3, 3)),
                      velocity=(draw(rounded(-6, 6)), draw(rounded(-6, 6))) if moving else (0.0, 0.0),
                      angular_velocity=draw(rounded(-4, 4)) if kind == "dynamic" else 0.0,
                      restitution=draw(rounded(0, 1)), friction=draw(rounded(0, 1.5)),
                      is_static=kind == "static", fixed_rotation=kind == "fixed")


points = st.tuples(rounded(-4, 4), rounded(-4, 4)).map(list)
normals = rounded(-math.pi, math.pi, 3).map(lambda angle: [math.cos(angle), math.sin(angle)])
restitutions = st.one_of(st.sampled_from([0.0, 1.0]), rounded(0, 1))
#: Two approaching contacts for one separating one (Hypothesis draws which).
approaching = st.sampled_from([True, True, False])


def set_motion(a: dict, b: dict, point, normal, approach: bool) -> tuple[dict, dict]:
    """Reverse both bodies' motion when v_n at ``point`` has the wrong sign."""
    v_n = oracle.relative_normal_velocity(a, b, point, normal)
    if (approach and v_n > 0) or (not approach and v_n < 0):
        return reversed_motion(a), reversed_motion(b)
    return a, b


@pytest.mark.points(1)
@given(a=bodies(), b=bodies(), point=points, normal=normals, e=restitutions, approach=approaching)
def test_closed_forms_any_case(student, a, b, point, normal, e, approach):
    """v_n, k and j for any pair of bodies, point and normal (Hypothesis, sympy)"""
    a, b = set_motion(a, b, point, normal, approach)
    inputs = show_inputs(a, b, point, normal)
    v_n = student.call(MODULE, "relative_normal_velocity", a, b, point, normal)
    found = number("v_n", v_n, oracle.relative_normal_velocity(a, b, point, normal), rtol=RTOL, atol=ATOL)
    if found:
        fail(f"relative_normal_velocity{inputs}: {found}; v_n = (v_B + w_B x r_B - v_A - w_A x r_A) . n")
    k = student.call(MODULE, "effective_mass_inverse", a, b, point, normal)
    found = number("k", k, oracle.effective_mass_inverse(a, b, point, normal), rtol=RTOL, atol=1e-12)
    if found:
        fail(f"effective_mass_inverse{inputs}: {found}; k = 1/m_A + 1/m_B + (r_A x n)^2/I_A + (r_B x n)^2/I_B")
    j = student.call(MODULE, "normal_impulse_magnitude", a, b, point, normal, e)
    found = number("j", j, oracle.normal_impulse(a, b, point, normal, e), rtol=RTOL, atol=1e-12)
    if found:
        fail(f"normal_impulse_magnitude{show_inputs(a, b, point, normal, e)}: {found}; j = -(1 + e) v_n / k when "
             "v_n < 0, else 0")


@st.composite
def resolve_inputs(draw):
    """A, B, a contact of one or two points (a face: the second point along the tangent),
    the motion chosen to approach or separate at the first point, and default or
    explicit materials."""
    a, b = draw(bodies()), draw(bodies())
    normal = draw(normals)
    first = draw(points)
    chosen = [first]
    if draw(st.booleans()):
        along = draw(rounded(0.1, 1.5))
        chosen.append([round(first[0] + along * normal[1], 6), round(first[1] - along * normal[0], 6)])
    contact = plain.contact(normal, draw(rounded(0, 0.2)), chosen)
    if len(chosen) == 2:
        assume(well_conditioned(a, b, contact))
    a, b = set_motion(a, b, first, normal, draw(approaching))
    materials = draw(st.one_of(st.just(()), st.tuples(restitutions, st.sampled_from([0.0, 0.3, 2.0]))))
    return (a, b, contact, *materials)


@pytest.mark.points(2)
@given(case=resolve_inputs())
def test_resolve_any_case(student, case):
    """resolve_collision for any bodies, normal and one or two points (Hypothesis, sympy)"""
    result = student.call_with_state(MODULE, "resolve_collision", *case)
    found = resolve_problem(case, result)
    if found:
        fail(f"{describe_resolve(case)}: {found}")


@pytest.mark.points(1)
@given(a=bodies(), b=bodies(), normal=normals, depth=rounded(-0.1, 0.5, 3), percent=rounded(0, 1),
       slop=st.sampled_from([0.0, 0.01, 0.05]))
def test_correct_positions_any_case(student, a, b, normal, depth, percent, slop):
    """correct_positions for any bodies, normal, depth, percent and slop (Hypothesis, sympy)"""
    case = (a, b, normal, depth, percent, slop)
    found = correction_problem(case, student.call_with_state(CORRECTION, "correct_positions", *case))
    if found:
        fail(f"{describe_correction(case)}: {found}")
