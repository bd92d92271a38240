"""1D momentum: the three formulas against sympy closed forms derived here."""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import pytest
import sympy as sp

from grader.compare import number, show
from grader.credit import check_cases

MODULE = "response.momentum_1d"
KMH = 1000 / 3600


@lru_cache(maxsize=None)
def closed_forms():
    """Lambdified (v1', v2') for restitution e, and the common velocity, from sympy.

    Momentum m1 v1 + m2 v2 = m1 u1 + m2 u2 and restitution u2 - u1 = -e (v2 - v1).
    """
    m1, m2, v1, v2, u1, u2, e = sp.symbols("m1 m2 v1 v2 u1 u2 e", real=True)
    solution = sp.solve([sp.Eq(m1 * v1 + m2 * v2, m1 * u1 + m2 * u2), sp.Eq(u2 - u1, -e * (v2 - v1))], [u1, u2],
                        dict=True)[0]
    general = sp.lambdify((m1, v1, m2, v2, e), (solution[u1], solution[u2]), "math")
    common = sp.lambdify((m1, v1, m2, v2), sp.simplify(solution[u1].subs(e, 0)), "math")
    return general, common


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
