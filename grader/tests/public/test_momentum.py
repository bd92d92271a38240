"""1D momentum: the three formulas against sympy closed forms derived here."""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
import pytest
import sympy as sp

from grader.harness.compare import number, show
from grader.oracles.derivation_cache import cached, sympy_versions
from grader.harness.credit import check_cases

MODULE = "response.momentum_1d"
KMH = 1000 / 3600


def lambdified(name: str, derive) -> tuple:
    """The (general, common) forms of ``derive()`` (arguments and expression of each),
    kept on disk once per version of this file (grader.oracles.derivation_cache: sympy's
    solving costs seconds in every grading process), lambdified to plain-float functions."""
    forms = cached(__file__, name, derive, sympy_versions())
    return tuple(sp.lambdify(*forms[key], "math") for key in ("general", "common"))


@lru_cache(maxsize=None)
def closed_forms():
    """Lambdified (v1', v2') for restitution e, and the common velocity, from sympy.

    Momentum m1 v1 + m2 v2 = m1 u1 + m2 u2 and restitution u2 - u1 = -e (v2 - v1).
    """
    return lambdified("closed_forms", derive_closed_forms)


def derive_closed_forms() -> dict:
    m1, m2, v1, v2, u1, u2, e = sp.symbols("m1 m2 v1 v2 u1 u2 e", real=True)
    solution = sp.solve([sp.Eq(m1 * v1 + m2 * v2, m1 * u1 + m2 * u2), sp.Eq(u2 - u1, -e * (v2 - v1))], [u1, u2],
                        dict=True)[0]
    return {"general": ((m1, v1, m2, v2, e), (solution[u1], solution[u2])),
            "common": ((m1, v1, m2, v2), sp.simplify(solution[u1].subs(e, 0)))}


def random_cases(seed: int, count: int = 20, restitution: bool = False) -> list[tuple]:
    rng = np.random.default_rng(seed)
    cases = []
    for _ in range(count):
        case = (rng.uniform(0.1, 10), rng.normal(0, 5), rng.uniform(0.1, 10), rng.normal(0, 5))
        if restitution:
            case += (rng.uniform(0, 1),)
        cases.append(tuple(float(x) for x in case))
    return cases


def velocities_problem(got, want) -> str | None:
    if not isinstance(got, list) or len(got) != 2:
        return f"must return (v1', v2'), got {show(got)}"
    return (number("v1'", got[0], want[0], rtol=1e-9, atol=1e-9)
            or number("v2'", got[1], want[1], rtol=1e-9, atol=1e-9))


@pytest.mark.points(2)
def test_elastic(student):
    """1D elastic collision (worked example 2 and random cases)"""
    general, _ = closed_forms()
    cases = [(0.1, 10.0, 0.2, -5.0)] + random_cases(501)  # worked example 2: exactly -10 and +5
    answers = student.call_many(MODULE, "elastic_collision_1d", cases)
    check_cases(zip(cases, answers), lambda ca: velocities_problem(ca[1], general(*ca[0], 1.0)),
                "elastic collisions", describe=lambda ca: f"elastic_collision_1d{show(ca[0])}")


@pytest.mark.points(2)
def test_restitution(student):
    """1D collision with restitution e"""
    general, _ = closed_forms()
    cases = random_cases(502, restitution=True) + [(2.0, 3.0, 1.0, -1.0, 0.0), (2.0, 3.0, 1.0, -1.0, 1.0)]
    answers = student.call_many(MODULE, "collision_1d", cases)
    check_cases(zip(cases, answers), lambda ca: velocities_problem(ca[1], general(*ca[0])),
                "collisions with restitution", describe=lambda ca: f"collision_1d{show(ca[0])}")


@pytest.mark.points(2)
def test_perfectly_inelastic(student):
    """1D perfectly inelastic collision (worked example 1)"""
    _, common = closed_forms()
    cases = [(5000.0, 80 * KMH, 1000.0, 60 * KMH)] + random_cases(503)  # worked example 1: 21.30 m/s
    answers = student.call_many(MODULE, "perfectly_inelastic_1d", cases)
    check_cases(zip(cases, answers),
                lambda ca: number("common velocity", ca[1], common(*ca[0]), rtol=1e-9, atol=1e-9),
                "perfectly inelastic collisions", describe=lambda ca: f"perfectly_inelastic_1d{show(ca[0])}")


@lru_cache(maxsize=None)
def wall_forms():
    """(v1', v2') and the common velocity with inverse masses w = 1/m, from the same
    sympy solution: w = 0 is an immovable wall (m = inf), where the forms in m give nan."""
    return lambdified("wall_forms", derive_wall_forms)


def derive_wall_forms() -> dict:
    w1, w2, v1, v2, e = sp.symbols("w1 w2 v1 v2 e", real=True)
    m1, m2, u1, u2 = sp.symbols("m1 m2 u1 u2", real=True)
    solution = sp.solve([sp.Eq(m1 * v1 + m2 * v2, m1 * u1 + m2 * u2), sp.Eq(u2 - u1, -e * (v2 - v1))], [u1, u2],
                        dict=True)[0]
    inverse = {m1: 1 / w1, m2: 1 / w2}
    after = tuple(sp.simplify(solution[u].subs(inverse)) for u in (u1, u2))
    return {"general": ((w1, v1, w2, v2, e), after), "common": ((w1, v1, w2, v2), sp.simplify(after[0].subs(e, 0)))}


def inverse(mass: float) -> float:
    return 0.0 if math.isinf(mass) else 1.0 / mass


WALL_CASES = [(0.2, 3.0, math.inf, 0.0, 0.5),     # the docstring's ball against a wall: (-1.5, 0)
              (math.inf, -2.0, 1.5, 4.0, 1.0),     # the wall is body 1, moving at -2 m/s
              (2.0, -1.0, math.inf, 1.0, 0.0),     # a wall moving at 1 m/s catches the body: both at 1
              (0.5, 5.0, math.inf, -3.0, 0.8)]


@pytest.mark.points(1)
def test_wall(student):
    """1D collisions with an immovable wall (infinite mass)"""
    general, common = wall_forms()
    answers = student.call_many(MODULE, "collision_1d", WALL_CASES)
    check_cases(zip(WALL_CASES, answers),
                lambda ca: velocities_problem(ca[1], general(inverse(ca[0][0]), ca[0][1], inverse(ca[0][2]), ca[0][3],
                                                             ca[0][4])),
                "collisions with a wall", describe=lambda ca: f"collision_1d{show(ca[0])}")
    cases = [case[:4] for case in WALL_CASES]
    answers = student.call_many(MODULE, "perfectly_inelastic_1d", cases)
    check_cases(zip(cases, answers),
                lambda ca: number("common velocity", ca[1], common(inverse(ca[0][0]), ca[0][1], inverse(ca[0][2]),
                                                                   ca[0][3]), rtol=1e-9, atol=1e-9),
                "sticking to a wall", describe=lambda ca: f"perfectly_inelastic_1d{show(ca[0])}")


BAD_INPUTS = [("collision_1d", (0.0, 1.0, 1.0, 0.0, 0.5), "a mass of 0"),
              ("collision_1d", (-1.0, 1.0, 1.0, 0.0, 0.5), "a negative mass"),
              ("collision_1d", (math.nan, 1.0, 1.0, 0.0, 0.5), "a NaN mass"),
              ("collision_1d", (math.inf, 1.0, math.inf, 0.0, 0.5), "two infinite masses"),
              ("collision_1d", (1.0, math.nan, 1.0, 0.0, 0.5), "a NaN velocity"),
              ("collision_1d", (1.0, math.inf, 1.0, 0.0, 0.5), "an infinite velocity"),
              ("collision_1d", (1.0, 1.0, 1.0, 0.0, 1.5), "e > 1"),
              ("collision_1d", (1.0, 1.0, 1.0, 0.0, -0.1), "e < 0"),
              ("elastic_collision_1d", (1.0, 1.0, 0.0, 0.0), "a mass of 0"),
              ("perfectly_inelastic_1d", (math.inf, 1.0, math.inf, 0.0), "two infinite masses"),
              ("perfectly_inelastic_1d", (1.0, 1.0, 2.0, math.nan), "a NaN velocity")]
#: Input on the edge of what is allowed, that must be accepted: a function that refuses
#: everything must not pass the test of refusals.
GOOD_INPUTS = [("collision_1d", (1.0, 1.0, 1.0, 0.0, 0.0), "e = 0"),
               ("collision_1d", (1.0, 1.0, 1.0, 0.0, 1.0), "e = 1"),
               ("collision_1d", (math.inf, 1.0, 2.0, 0.0, 0.5), "one infinite mass"),
               ("collision_1d", (1e-6, 0.0, 1e6, 0.0, 0.5), "tiny and huge masses at rest"),
               ("elastic_collision_1d", (2.0, -1.0, 3.0, 4.0), "two ordinary bodies"),
               ("perfectly_inelastic_1d", (1.0, 1.0, math.inf, 0.0), "one infinite mass")]


@pytest.mark.points(1)
def test_rejects_bad_input(student):
    """Bad masses, velocities and restitution raise ValueError (as the docstrings say);
    input on the edge of what is allowed is accepted"""
    for function, args, what in GOOD_INPUTS:
        result = student.raw(MODULE, function, *args)
        if result.status in ("not_implemented", "timeout", "crashed"):
            student.value_of(result, f"{MODULE}.{function}")  # stops the test with that status
        assert result.ok, (f"{function}{show(args)} ({what}) is allowed input and must return velocities, "
                           f"raised: {result.message.strip()[-300:]}")
    for function, args, what in BAD_INPUTS:
        result = student.raw(MODULE, function, *args)
        if result.status in ("not_implemented", "timeout", "crashed"):
            student.value_of(result, f"{MODULE}.{function}")  # stops the test with that status
        assert result.status == "error" and "ValueError" in result.message, (
            f"{function}{show(args)} ({what}) must raise ValueError, "
            + (f"got {show(result.value)}" if result.ok else f"raised: {result.message.strip()[-300:]}"))
