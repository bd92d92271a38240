"""Checks of the 1D momentum formulas against sympy closed forms derived at grading time."""
from __future__ import annotations

from functools import lru_cache

import numpy as np
import sympy as sp

from ..compare import number, show
from ..outcome import Outcome
from . import check

MODULE = "response.momentum_1d"
KMH = 1000 / 3600


@lru_cache(maxsize=None)
def closed_forms():
    """Lambdified (v1', v2') for restitution e and the common velocity, from sympy.

    Momentum m1 v1 + m2 v2 = m1 u1 + m2 u2 and restitution u2 - u1 = -e (v2 - v1)
    give one solution (energy and momentum for e = 1 also give the trivial root
    u = v, which is discarded).
    """
    m1, m2, v1, v2, u1, u2, e = sp.symbols("m1 m2 v1 v2 u1 u2 e", real=True)
    solution = sp.solve([sp.Eq(m1 * v1 + m2 * v2, m1 * u1 + m2 * u2), sp.Eq(u2 - u1, -e * (v2 - v1))], [u1, u2],
                        dict=True)[0]
    general = sp.lambdify((m1, v1, m2, v2, e), (solution[u1], solution[u2]), "math")
    common = sp.lambdify((m1, v1, m2, v2), sp.simplify(solution[u1].subs(e, 0)), "math")
    return general, common


def compare_pairs_of_velocities(student, function: str, cases: list[tuple], want_of) -> Outcome:
    answers = student.call_many(MODULE, function, cases)
    for case, got in zip(cases, answers):
        want = want_of(*case)
        if not isinstance(got, list) or len(got) != 2:
            return Outcome.failed(f"{function}{show(case)} must return (v1', v2'), got {show(got)}")
        problem = number("v1'", got[0], want[0], rtol=1e-9, atol=1e-9) or number("v2'", got[1], want[1], rtol=1e-9,
                                                                                 atol=1e-9)
        if problem:
            return Outcome.failed(f"{function}{show(case)}: {problem} (expected {show(tuple(want))})")
    return Outcome.passed(f"{len(cases)} collisions agree with the closed form")


@check("momentum.elastic")
def elastic(student):
    general, _ = closed_forms()
    rng = np.random.default_rng(501)
    cases = [(0.1, 10.0, 0.2, -5.0)]  # worked example 2: exactly -10 and +5
    cases += [tuple(float(x) for x in (rng.uniform(0.1, 10), rng.normal(0, 5), rng.uniform(0.1, 10), rng.normal(0, 5)))
              for _ in range(20)]
    return compare_pairs_of_velocities(student, "elastic_collision_1d", cases, lambda *c: general(*c, 1.0))


@check("momentum.restitution")
def restitution(student):
    general, _ = closed_forms()
    rng = np.random.default_rng(502)
    cases = [tuple(float(x) for x in (rng.uniform(0.1, 10), rng.normal(0, 5), rng.uniform(0.1, 10), rng.normal(0, 5),
                                      rng.uniform(0, 1))) for _ in range(20)]
    cases += [(2.0, 3.0, 1.0, -1.0, 0.0), (2.0, 3.0, 1.0, -1.0, 1.0)]
    return compare_pairs_of_velocities(student, "collision_1d", cases, general)


@check("momentum.perfectly_inelastic")
def perfectly_inelastic(student):
    _, common = closed_forms()
    rng = np.random.default_rng(503)
    cases = [(5000.0, 80 * KMH, 1000.0, 60 * KMH)]  # worked example 1: 76.67 km/h = 21.30 m/s
    cases += [tuple(float(x) for x in (rng.uniform(0.1, 10), rng.normal(0, 5), rng.uniform(0.1, 10), rng.normal(0, 5)))
              for _ in range(20)]
    answers = student.call_many(MODULE, "perfectly_inelastic_1d", cases)
    for case, got in zip(cases, answers):
        problem = number("common velocity", got, common(*case), rtol=1e-9, atol=1e-9)
        if problem:
            return Outcome.failed(f"perfectly_inelastic_1d{show(case)}: {problem}")
    return Outcome.passed(f"{len(cases)} collisions agree with the closed form")
