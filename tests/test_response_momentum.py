"""1D collisions: solutions.response.momentum_1d against sympy derivations.

The oracle is sympy solving the conservation laws; the worked examples of the course
notes are recomputed here in exact arithmetic, with the corrected figures of the
errata (15-17) as the expected values.
"""
import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from solutions.response.momentum_1d import (
    collision_1d,
    elastic_collision_1d,
    kinetic_energy,
    momentum,
    perfectly_inelastic_1d,
)

m1, m2 = sp.symbols("m1 m2", positive=True)
v1, v2, u1, u2, e = sp.symbols("v1 v2 u1 u2 e", real=True)
MOMENTUM = sp.Eq(m1 * v1 + m2 * v2, m1 * u1 + m2 * u2)
ENERGY = sp.Eq(m1 * v1**2 / 2 + m2 * v2**2 / 2, m1 * u1**2 / 2 + m2 * u2**2 / 2)
RESTITUTION = sp.Eq(u2 - u1, -e * (v2 - v1))


def derive_general():
    (solution,) = sp.solve([MOMENTUM, RESTITUTION], [u1, u2], dict=True)
    return solution[u1], solution[u2]


def derive_elastic():
    roots = sp.solve([MOMENTUM, ENERGY], [u1, u2], dict=True)
    # One root is the state before the impact (nothing happened); discard it.
    after = [r for r in roots if sp.simplify(r[u1] - v1) != 0]
    assert len(roots) == 2 and len(after) == 1
    return after[0][u1], after[0][u2]


def derive_perfectly_inelastic():
    u = sp.symbols("u", real=True)
    (common,) = sp.solve(sp.Eq(m1 * v1 + m2 * v2, (m1 + m2) * u), u)
    return common


GENERAL = sp.lambdify((m1, v1, m2, v2, e), derive_general())
ELASTIC = sp.lambdify((m1, v1, m2, v2), derive_elastic())
INELASTIC = sp.lambdify((m1, v1, m2, v2), derive_perfectly_inelastic())
RNG_CASES = np.random.default_rng(20241122).uniform([0.01, -50, 0.01, -50, 0], [100, 50, 100, 50, 1], (200, 5))
# Results are sums of a few products of the inputs: relative error ~1e-15 of the
# largest term; 1e-9 m/s leaves room and still catches any wrong formula.
ATOL = 1e-9


@pytest.mark.parametrize("case", range(len(RNG_CASES)))
def test_general_restitution_matches_sympy(case):
    a, va, b, vb, c = RNG_CASES[case]
    np.testing.assert_allclose(collision_1d(a, va, b, vb, c), GENERAL(a, va, b, vb, c), rtol=1e-12, atol=ATOL)


def test_elastic_and_perfectly_inelastic_match_sympy():
    for a, va, b, vb, _ in RNG_CASES:
        np.testing.assert_allclose(elastic_collision_1d(a, va, b, vb), ELASTIC(a, va, b, vb), rtol=1e-12, atol=ATOL)
        assert perfectly_inelastic_1d(a, va, b, vb) == pytest.approx(INELASTIC(a, va, b, vb), rel=1e-12, abs=ATOL)
        # e = 0 is the perfectly inelastic case of the general law.
        np.testing.assert_allclose(collision_1d(a, va, b, vb, 0.0), [INELASTIC(a, va, b, vb)] * 2, rtol=1e-12, atol=ATOL)


def test_wall_is_the_infinite_mass_limit():
    after_1, after_2 = derive_general()
    wall_1 = sp.lambdify((v1, v2, e), sp.limit(after_1, m2, sp.oo))
    wall_2 = sp.lambdify((v1, v2, e), sp.limit(after_2, m2, sp.oo))
    for a, va, _, vb, c in RNG_CASES[:50]:
        got = collision_1d(a, va, math.inf, vb, c)
        np.testing.assert_allclose(got, (wall_1(va, vb, c), wall_2(va, vb, c)), rtol=1e-12, atol=ATOL)
        # The same wall as body 1.
        np.testing.assert_allclose(collision_1d(math.inf, vb, a, va, c)[::-1], got, rtol=1e-12, atol=ATOL)
        assert perfectly_inelastic_1d(a, va, math.inf, vb) == pytest.approx(vb, rel=1e-15)


masses = st.floats(1e-3, 1e3)
speeds = st.floats(-100.0, 100.0)


@settings(max_examples=300, deadline=None)
@given(masses, speeds, masses, speeds, st.floats(0.0, 1.0))
def test_momentum_conserved_and_no_energy_gained(a, va, b, vb, c):
    wa, wb = collision_1d(a, va, b, vb, c)
    scale = abs(a * va) + abs(b * vb) + 1e-12
    assert abs(momentum(a, wa) + momentum(b, wb) - momentum(a, va) - momentum(b, vb)) <= 1e-12 * scale
    before = kinetic_energy(a, va) + kinetic_energy(b, vb)
    after = kinetic_energy(a, wa) + kinetic_energy(b, wb)
    assert after <= before * (1 + 1e-12) + 1e-12
    # Restitution law itself: separation speed is e times approach speed.
    assert wb - wa == pytest.approx(-c * (vb - va), rel=1e-9, abs=1e-9)


@settings(max_examples=200, deadline=None)
@given(masses, speeds, masses, speeds)
def test_elastic_keeps_energy_and_zero_restitution_moves_together(a, va, b, vb):
    before = kinetic_energy(a, va) + kinetic_energy(b, vb)
    wa, wb = elastic_collision_1d(a, va, b, vb)
    assert kinetic_energy(a, wa) + kinetic_energy(b, wb) == pytest.approx(before, rel=1e-9, abs=1e-12)
    sa, sb = collision_1d(a, va, b, vb, 0.0)
    assert sa == pytest.approx(sb, rel=1e-12, abs=1e-12)
    assert sa == pytest.approx(perfectly_inelastic_1d(a, va, b, vb), rel=1e-12, abs=1e-12)


def test_truck_hits_car_and_they_stay_together():
    # Exact arithmetic: 5000 kg at 80 km/h, 1000 kg at 60 km/h ahead of it.
    kmh = sp.Rational(1000, 3600)  # m/s per km/h
    truck, car = 5000, 1000
    v_truck, v_car = 80 * kmh, 60 * kmh
    v_common = (truck * v_truck + car * v_car) / (truck + car)
    e_before = sp.Rational(1, 2) * (truck * v_truck**2 + car * v_car**2)
    e_after = sp.Rational(1, 2) * (truck + car) * v_common**2
    # The corrected figures of the errata (15, 16), checked against exact arithmetic.
    assert round(float(v_common / kmh), 2) == 76.67
    assert round(float(v_common), 2) == 21.30
    assert round(float(e_before)) == 1_373_457
    assert round(float(e_after)) == 1_360_597
    assert round(float(e_after - e_before)) == -12_860
    assert round(float(100 * (e_before - e_after) / e_before), 2) == 0.94
    # The code under test, in SI units.
    got = perfectly_inelastic_1d(truck, float(v_truck), car, float(v_car))
    assert got == pytest.approx(float(v_common), rel=1e-14)
    assert kinetic_energy(truck, float(v_truck)) + kinetic_energy(car, float(v_car)) == pytest.approx(float(e_before), rel=1e-14)
    assert kinetic_energy(truck + car, got) == pytest.approx(float(e_after), rel=1e-14)
    # The notes' 68 km/h is not what momentum conservation gives.
    assert abs(got / float(kmh) - 68) > 8


def test_two_balls_bounce_elastically_to_exactly_minus_10_and_plus_5():
    ball_1, ball_2 = sp.Rational(1, 10), sp.Rational(2, 10)
    before = {m1: ball_1, m2: ball_2, v1: 10, v2: -5}
    roots = sp.solve([MOMENTUM.subs(before), ENERGY.subs(before)], [u1, u2], dict=True)
    assert {(r[u1], r[u2]) for r in roots} == {(10, -5), (-10, 5)}  # exact rationals
    np.testing.assert_allclose(elastic_collision_1d(0.1, 10.0, 0.2, -5.0), (-10.0, 5.0), rtol=0, atol=1e-14)


def test_momentum_is_a_vector_along_the_velocity():
    assert momentum(2.0, np.array([3.0, -4.0])).tolist() == [6.0, -8.0]
    assert kinetic_energy(2.0, np.array([3.0, -4.0])) == 25.0


@pytest.mark.parametrize("bad", [
    dict(m1=-1.0), dict(m1=0.0), dict(m1=math.nan), dict(m2=-2.0),
    dict(m1=math.inf, m2=math.inf), dict(e=1.5), dict(e=-0.1), dict(e=math.nan),
    dict(v1=math.nan), dict(v2=math.inf),
])
def test_invalid_input_raises(bad):
    args = dict(m1=1.0, v1=1.0, m2=2.0, v2=-1.0, e=0.5) | bad
    with pytest.raises(ValueError):
        collision_1d(args["m1"], args["v1"], args["m2"], args["v2"], args["e"])


def test_invalid_input_raises_for_every_function():
    for call in (lambda: elastic_collision_1d(-1.0, 0.0, 1.0, 0.0),
                 lambda: perfectly_inelastic_1d(1.0, 0.0, math.nan, 0.0),
                 lambda: momentum(-1.0, 1.0), lambda: momentum(math.inf, 1.0),
                 lambda: kinetic_energy(math.nan, 1.0)):
        with pytest.raises(ValueError):
            call()
