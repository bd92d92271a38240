"""Rigid-body impulses derived with sympy from the impulse-momentum equations.

An oracle a student may hold: it never imports the reference engine.  Bodies and
contacts are the plain dicts of :mod:`grader.oracles.plain`.  Conventions of the
course: the contact normal ``n`` is a unit vector from body A to body B; SI units;
``r_A = p - x_A`` and ``r_B = p - x_B`` are lever arms from each centre of mass; the
2D cross product is ``a x b = a_x b_y - a_y b_x``; the impulse ``P`` goes to B and
``-P`` to A; a static body has ``1/m = 1/I = 0`` and a body with fixed rotation
``1/I = 0``; a pair's restitution and friction are the products ``e = e_A e_B``,
``mu = mu_A mu_B``.

The derivation (:func:`derived`, run once on first use)
-------------------------------------------------------
1. Unknown post-impulse velocities ``v_A', w_A', v_B', w_B'`` and an impulse ``P`` at
   ``p``.  Linear momentum: ``m_B (v_B' - v_B) = P``, ``m_A (v_A' - v_A) = -P``.
   Angular momentum about each centre of mass: ``I_B (w_B' - w_B) = r_B x P``,
   ``I_A (w_A' - w_A) = -(r_A x P)``.  sympy solves these for the post-velocities,
   which are then rewritten with inverse masses (``1/m``, ``1/I``) so that a static
   body or a fixed rotation is the value 0 rather than a limit.
2. Velocity of a body's material point at ``p``: ``v + w x r = (v_x - w r_y, v_y + w r_x)``;
   relative normal velocity ``v_n = (v_B(p) - v_A(p)) . n``.
3. With ``P = j n``, ``v_n'`` is linear in ``j``: its slope ``dv_n'/dj`` is the inverse
   effective mass ``k``; sympy checks that it equals
   ``1/m_A + 1/m_B + (r_A x n)^2/I_A + (r_B x n)^2/I_B``.
4. Restitution law ``v_n' = -e v_n`` solved for ``j``: ``j = -(1 + e) v_n / k``.  A
   contact pushes and never pulls: ``j = 0`` when ``v_n >= 0`` or ``k = 0``.
5. Friction: ``P = j_t t`` with ``t = (n_y, -n_x)`` and the law ``v_t' = 0`` give the
   impulse that stops the sliding, clamped to ``|j_t| <= mu j`` (Coulomb).
6. Several points: impulses ``j_1 ... j_k`` at once; ``K[i, l] = dv_n,i' / dj_l``
   (sympy); the normal impulses solve the linear complementarity problem
   ``j >= 0``, ``v_n' >= target``, ``j_i (v_n,i' - target_i) = 0`` with
   ``target = -e v_n`` at approaching points and 0 elsewhere, found here by trying
   every set of active points (brute force, at most a few points).
7. Positional correction: a "position impulse" ``C n`` moves B by ``C n / m_B`` and A
   by ``-C n / m_A`` (so the centre of mass stays); the relative move along ``n`` must
   be ``percent * max(depth - slop, 0)``, which sympy solves for ``C``.
"""
from __future__ import annotations

import copy
import itertools
import math
from functools import lru_cache
from types import SimpleNamespace

import numpy as np
import sympy as sp

from . import derivation_cache, plain

__all__ = ["derived", "relative_normal_velocity", "relative_tangent_velocity", "effective_mass_inverse",
           "normal_impulse", "apply_impulse", "resolve_collision", "correct_positions", "OracleError",
           "response_matrix", "show_body", "show_contact", "kinetic_energy", "momenta"]


class OracleError(ValueError):
    """A case the oracle cannot decide (a test should not build one)."""


def _cross(ax, ay, bx, by):
    return ax * by - ay * bx


@lru_cache(maxsize=None)
def derived() -> SimpleNamespace:
    """The closed forms, solved by sympy from the equations above and lambdified.

    Returns a namespace of plain-float functions (argument order in each docstring of
    this module's wrappers) and the sympy expressions themselves (``expressions``).
    sympy's work (about 3 s) is done once per version of this file, of Python and of
    sympy: its expressions are kept in ``__pycache__`` (:mod:`.derivation_cache`).
    """
    forms = derivation_cache.cached(__file__, "derived", _derive, derivation_cache.sympy_versions())
    functions = {name: sp.lambdify(arguments, expression, "math") for name, (arguments, expression) in forms.items()}
    return SimpleNamespace(**functions, expressions=SimpleNamespace(
        **{name: expression for name, (_, expression) in forms.items() if name != "v_t"}))


def _derive() -> dict[str, tuple[tuple, object]]:
    """Each closed form by name: (its arguments, the sympy expression) (see :func:`derived`)."""
    ma, mb, ia, ib = sp.symbols("m_A m_B I_A I_B", positive=True)
    ima, imb, iia, iib = sp.symbols("invm_A invm_B invI_A invI_B", nonnegative=True)
    vax, vay, wa, vbx, vby, wb = sp.symbols("v_Ax v_Ay w_A v_Bx v_By w_B", real=True)
    rax, ray, rbx, rby, nx, ny, px, py = sp.symbols("r_Ax r_Ay r_Bx r_By n_x n_y P_x P_y", real=True)
    e, j, jt = sp.symbols("e j j_t", real=True)
    # 1. Impulse-momentum: unknown post-velocities.
    vax2, vay2, wa2, vbx2, vby2, wb2 = sp.symbols("v_Ax' v_Ay' w_A' v_Bx' v_By' w_B'", real=True)
    momentum = [sp.Eq(mb * (vbx2 - vbx), px), sp.Eq(mb * (vby2 - vby), py),
                sp.Eq(ib * (wb2 - wb), _cross(rbx, rby, px, py)),
                sp.Eq(ma * (vax2 - vax), -px), sp.Eq(ma * (vay2 - vay), -py),
                sp.Eq(ia * (wa2 - wa), -_cross(rax, ray, px, py))]
    solved = sp.solve(momentum, [vax2, vay2, wa2, vbx2, vby2, wb2], dict=True)[0]
    inverse = {ma: 1 / ima, mb: 1 / imb, ia: 1 / iia, ib: 1 / iib}
    after = [sp.expand(solved[s].subs(inverse)) for s in (vax2, vay2, wa2, vbx2, vby2, wb2)]

    # 2. Relative velocity of the material points along a direction (dx, dy).
    def relative_along(state, dx, dy):
        ax_, ay_, a_w, bx_, by_, b_w = state
        point_a = (ax_ - a_w * ray, ay_ + a_w * rax)
        point_b = (bx_ - b_w * rby, by_ + b_w * rbx)
        return (point_b[0] - point_a[0]) * dx + (point_b[1] - point_a[1]) * dy

    before_state = (vax, vay, wa, vbx, vby, wb)
    v_n = relative_along(before_state, nx, ny)

    # 3. Inverse effective mass: slope of v_n' in j for P = j n.
    after_normal = [x.subs({px: j * nx, py: j * ny}) for x in after]
    v_n_after = sp.expand(relative_along(after_normal, nx, ny))
    k = sp.expand(sp.diff(v_n_after, j))
    # Rewritten with |n| = 1 (n_x^2 + n_y^2 = 1), it must be the textbook formula.
    textbook = ima + imb + iia * _cross(rax, ray, nx, ny) ** 2 + iib * _cross(rbx, rby, nx, ny) ** 2
    if sp.simplify((k - textbook).subs(ny, sp.sqrt(1 - nx ** 2))) != 0:
        raise AssertionError(f"sympy's inverse effective mass {k} is not {textbook}")
    if sp.simplify(v_n_after - (v_n + j * k)) != 0:
        raise AssertionError("v_n' is not linear in j with slope k")

    # 4. Restitution law solved for j.
    (j_solution,) = sp.solve(sp.Eq(v_n_after, -e * v_n), j)

    # 5. Friction: the tangent impulse that stops the sliding (t = (n_y, -n_x)).
    tx, ty = ny, -nx
    after_tangent = [x.subs({px: jt * tx, py: jt * ty}) for x in after]
    (jt_solution,) = sp.solve(sp.Eq(relative_along(after_tangent, tx, ty), 0), jt)
    v_t = relative_along(before_state, tx, ty)

    # 6. Two impulses at two points: response of v_n at point 1 to a unit impulse at 2.
    r2 = sp.symbols("r2_Ax r2_Ay r2_Bx r2_By", real=True)
    j1, j2 = sp.symbols("j_1 j_2", real=True)
    # Velocities after j1 n at r = (rax, ray, rbx, rby) and j2 n at r2: impulses add.
    after_two = [x.subs({px: j1 * nx, py: j1 * ny}) for x in after]
    extra = [x.subs({px: j2 * nx, py: j2 * ny, rax: r2[0], ray: r2[1], rbx: r2[2], rby: r2[3]})
             - s for x, s in zip(after, before_state)]
    after_two = [a + d for a, d in zip(after_two, extra)]
    coupling = sp.expand(sp.diff(relative_along(after_two, nx, ny), j2))

    # 7. Positional correction.
    # The overlap beyond the slop, max(depth - slop, 0), is the symbol "excess".
    c, excess, percent = sp.symbols("C excess percent", real=True)
    move_a = (-ima * c * nx, -ima * c * ny)
    move_b = (imb * c * nx, imb * c * ny)
    (c_solution,) = sp.solve(sp.Eq((move_b[0] - move_a[0]) * nx + (move_b[1] - move_a[1]) * ny, percent * excess), c)
    c_solution = sp.simplify(c_solution.subs(ny, sp.sqrt(1 - nx ** 2)))

    masses = (ima, imb, iia, iib)
    arms = (rax, ray, rbx, rby)
    normal = (nx, ny)
    return {
        "v_n": ((*before_state, *arms, *normal), v_n),
        "v_t": ((*before_state, *arms, *normal), v_t),
        "k": ((*masses, *arms, *normal), k),
        "j": ((*masses, *before_state, *arms, *normal, e), j_solution),
        "j_t": ((*masses, *before_state, *arms, *normal), jt_solution),
        "after": ((*masses, *before_state, *arms, px, py), after),
        "coupling": ((*masses, *arms, *r2, *normal), coupling),
        "correction": ((ima, imb, nx, ny, excess, percent), c_solution),
    }


# Plain-dict wrappers --------------------------------------------------------------------
def _state(body: dict) -> tuple[float, ...]:
    (vx, vy), w = body["velocity"], body["angular_velocity"]
    return float(vx), float(vy), float(w)


def _masses(a: dict, b: dict) -> tuple[float, ...]:
    return plain.inverse_mass(a), plain.inverse_mass(b), plain.inverse_inertia(a), plain.inverse_inertia(b)


def _arms(a: dict, b: dict, point) -> tuple[float, ...]:
    px, py = (float(v) for v in np.asarray(point, dtype=float).reshape(2))
    (ax, ay), (bx, by) = a["position"], b["position"]
    return px - ax, py - ay, px - bx, py - by


def _unit(normal) -> tuple[float, float]:
    nx, ny = (float(v) for v in np.asarray(normal, dtype=float).reshape(2))
    if not abs(math.hypot(nx, ny) - 1.0) <= 1e-9:
        raise OracleError(f"the normal {nx, ny} is not a unit vector")
    return nx, ny


def relative_normal_velocity(a: dict, b: dict, point, normal) -> float:
    """``v_n = (v_B(p) - v_A(p)) . n`` (m/s), negative while approaching."""
    return derived().v_n(*_state(a), *_state(b), *_arms(a, b, point), *_unit(normal))


def relative_tangent_velocity(a: dict, b: dict, point, normal) -> float:
    """``v_t = (v_B(p) - v_A(p)) . t`` with ``t = (n_y, -n_x)`` (m/s)."""
    return derived().v_t(*_state(a), *_state(b), *_arms(a, b, point), *_unit(normal))


def effective_mass_inverse(a: dict, b: dict, point, normal) -> float:
    """``k = 1/m_A + 1/m_B + (r_A x n)^2/I_A + (r_B x n)^2/I_B`` (1/kg)."""
    return derived().k(*_masses(a, b), *_arms(a, b, point), *_unit(normal))


def normal_impulse(a: dict, b: dict, point, normal, restitution: float) -> float:
    """``j = -(1 + e) v_n / k`` (N s), or 0 for a separating contact or ``k = 0``."""
    if relative_normal_velocity(a, b, point, normal) >= 0.0 or effective_mass_inverse(a, b, point, normal) == 0.0:
        return 0.0
    return derived().j(*_masses(a, b), *_state(a), *_state(b), *_arms(a, b, point), *_unit(normal),
                       float(restitution))


def apply_impulse(a: dict, b: dict, point, impulse) -> tuple[dict, dict]:
    """New copies of ``a`` and ``b`` after ``+P`` on B and ``-P`` on A at ``point``."""
    px, py = (float(v) for v in np.asarray(impulse, dtype=float).reshape(2))
    vax, vay, wa, vbx, vby, wb = derived().after(*_masses(a, b), *_state(a), *_state(b), *_arms(a, b, point),
                                                   px, py)
    a, b = copy.deepcopy(a), copy.deepcopy(b)
    a["velocity"], a["angular_velocity"] = [vax, vay], wa
    b["velocity"], b["angular_velocity"] = [vbx, vby], wb
    return a, b


def _lcp(matrix: np.ndarray, wanted: np.ndarray) -> np.ndarray:
    """The ``j >= 0`` with ``matrix j >= wanted`` and complementarity, by trying every
    active set (brute force).  OracleError when no set or two different answers fit."""
    count = len(wanted)
    scale = 1e-10 * (1.0 + float(np.max(np.abs(wanted), initial=0.0)))
    found = []
    for size in range(count + 1):
        for active in itertools.combinations(range(count), size):
            active = list(active)
            trial = np.zeros(count)
            if active:
                block = matrix[np.ix_(active, active)]
                if abs(np.linalg.det(block)) <= 1e-12 * max(1.0, float(np.max(np.abs(block)))) ** len(active):
                    continue
                trial[active] = np.linalg.solve(block, wanted[active])
            slack = matrix @ trial - wanted
            if np.all(trial >= -scale) and np.all(slack >= -scale):
                found.append(np.maximum(trial, 0.0))
    if not found:
        raise OracleError("no set of active contact points solves the complementarity problem")
    if any(np.max(np.abs(f - found[0])) > 1e-7 * (1.0 + float(np.max(np.abs(found[0])))) for f in found[1:]):
        raise OracleError("the contact's normal impulses are not unique (a singular response matrix)")
    return found[0]


def response_matrix(a: dict, b: dict, points, normal) -> np.ndarray:
    """``K[i, l]``: change of ``v_n`` at point i per unit impulse along ``n`` at point l."""
    n = _unit(normal)
    arms = [_arms(a, b, p) for p in points]
    return np.array([[derived().coupling(*_masses(a, b), *ri, *rl, *n) for rl in arms] for ri in arms])


def resolve_collision(a: dict, b: dict, contact: dict, restitution: float | None = None,
                      friction: float | None = None) -> tuple[dict, dict, list[float], list[float]]:
    """The course's single-shot response of one manifold: new copies of ``a`` and ``b``,
    the normal impulses ``j_i`` and the tangent impulses ``j_t`` (along ``t = (n_y, -n_x)``).

    Normal impulses of all points at once (complementarity, see the module docstring),
    then one friction pass over the points in order, each clamped by ``mu j_i`` and
    skipped when ``j_i = 0``, ``mu = 0`` or the tangent's ``k = 0``.  Two static bodies
    get no impulse at all (``K = 0``).
    """
    e = a["restitution"] * b["restitution"] if restitution is None else float(restitution)
    mu = a["friction"] * b["friction"] if friction is None else float(friction)
    n = _unit(contact["normal"])
    t = (n[1], -n[0])
    points = [tuple(p) for p in contact["points"]]
    v_n = np.array([relative_normal_velocity(a, b, p, n) for p in points])
    target = np.where(v_n < 0.0, -e * v_n, 0.0)
    if plain.inverse_mass(a) + plain.inverse_mass(b) == 0.0:
        # Two static bodies: K = 0, no impulse can change anything (as for one point, j = 0 when k = 0).
        normal_impulses = np.zeros(len(points))
    else:
        normal_impulses = _lcp(response_matrix(a, b, points, n), target - v_n)
    for p, j in zip(points, normal_impulses):
        if j > 0.0:
            a, b = apply_impulse(a, b, p, (j * n[0], j * n[1]))
    tangent_impulses = []
    for p, j in zip(points, normal_impulses):
        jt = 0.0
        if j > 0.0 and mu > 0.0 and effective_mass_inverse(a, b, p, t) > 0.0:
            unclamped = derived().j_t(*_masses(a, b), *_state(a), *_state(b), *_arms(a, b, p), *n)
            jt = min(max(unclamped, -mu * j), mu * j)
            a, b = apply_impulse(a, b, p, (jt * t[0], jt * t[1]))
        tangent_impulses.append(jt)
    return a, b, [float(j) for j in normal_impulses], tangent_impulses


def correct_positions(a: dict, b: dict, normal, depth: float, percent: float = 0.8,
                      slop: float = 0.01) -> tuple[dict, dict, list[float], list[float]]:
    """New copies of ``a`` and ``b`` moved apart along ``normal`` by inverse mass, and the
    two displacements (m)."""
    nx, ny = _unit(normal)
    ima, imb = plain.inverse_mass(a), plain.inverse_mass(b)
    if ima + imb == 0.0:
        c = 0.0
    else:
        excess = max(float(depth) - float(slop), 0.0)
        c = float(derived().correction(ima, imb, nx, ny, excess, float(percent)))
    moved_a, moved_b = [-ima * c * nx, -ima * c * ny], [imb * c * nx, imb * c * ny]
    a, b = copy.deepcopy(a), copy.deepcopy(b)
    for body, move in ((a, moved_a), (b, moved_b)):
        body["position"] = [body["position"][0] + move[0], body["position"][1] + move[1]]
    return a, b, [x + 0.0 for x in moved_a], [x + 0.0 for x in moved_b]


# Conservation -----------------------------------------------------------------------------
def kinetic_energy(body: dict) -> float:
    """Translational plus rotational kinetic energy (J); 0 for a static body."""
    if body["is_static"]:
        return 0.0
    (vx, vy), w = body["velocity"], body["angular_velocity"]
    spin = 0.0 if body["fixed_rotation"] else 0.5 * plain.moment_of_inertia(body["shape"], body["mass"]) * w * w
    return 0.5 * body["mass"] * (vx * vx + vy * vy) + spin


def momenta(bodies: list[dict]) -> tuple[np.ndarray, float]:
    """Total linear momentum (kg m/s) and angular momentum about the origin (kg m^2/s)
    of dynamic bodies that can turn or not (a fixed rotation adds no spin term)."""
    linear, angular = np.zeros(2), 0.0
    for body in bodies:
        (vx, vy), w = body["velocity"], body["angular_velocity"]
        (x, y), m = body["position"], body["mass"]
        linear += m * np.array([vx, vy])
        spin = 0.0 if body["fixed_rotation"] else plain.moment_of_inertia(body["shape"], m) * w
        angular += spin + m * (x * vy - y * vx)
    return linear, angular


# Descriptions for failure messages ------------------------------------------------------------
def _g(x: float) -> str:
    return f"{float(x):.6g}"


def _xy(v) -> str:
    return "(" + ", ".join(_g(x) for x in v) + ")"


def show_body(body: dict) -> str:
    """One line: shape, mass, inertia, position, velocities, material."""
    shape = body["shape"]
    kind = shape["$shape"]
    if kind == "Circle":
        form = f"disc r={_g(shape['radius'])} m"
    elif kind == "OBB":
        hx, hy = shape["half_extents"]
        form = f"box {_g(2 * hx)}x{_g(2 * hy)} m"
    elif kind == "AABB":
        form = "AABB"
    else:
        form = f"polygon of {len(shape['vertices'])} vertices"
    if body["is_static"]:
        mass = "static (1/m = 1/I = 0)"
    else:
        inertia = "fixed rotation (1/I = 0)" if body["fixed_rotation"] else \
            f"I={_g(plain.moment_of_inertia(shape, body['mass']))} kg m^2"
        mass = f"m={_g(body['mass'])} kg, {inertia}"
    return (f"{form}, {mass}, at {_xy(body['position'])}, v={_xy(body['velocity'])} m/s, "
            f"w={_g(body['angular_velocity'])} rad/s, e={_g(body['restitution'])}, mu={_g(body['friction'])}")


def show_contact(contact: dict) -> str:
    points = ", ".join(_xy(p) for p in contact["points"])
    return f"Contact(normal A->B {_xy(contact['normal'])}, depth {_g(contact['depth'])} m, points [{points}])"
