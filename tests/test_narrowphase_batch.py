"""The vectorised OBB-OBB test against the readable per-pair version and pymunk."""
from __future__ import annotations

import math

import numpy as np
import pytest

from solutions.narrowphase.batch_sat import obbs_overlap_batch
from solutions.narrowphase.polygon_polygon import obbs_overlap
from solutions.shapes import OBB
from test_narrowphase_oracles import pymunk_contact, signed_gap

#: m: pairs closer than this to touching may be classified either way by roundoff
#: (the batch form and the corner form round differently).
TOUCH_BAND = 1e-9


def random_boxes(rng, n, zero_fraction=0.0):
    centers_a, centers_b = rng.uniform(-3, 3, (n, 2)), rng.uniform(-3, 3, (n, 2))
    half_a, half_b = rng.uniform(0.05, 2.0, (n, 2)), rng.uniform(0.05, 2.0, (n, 2))
    if zero_fraction:
        half_a[rng.random((n, 2)) < zero_fraction] = 0.0
        half_b[rng.random((n, 2)) < zero_fraction] = 0.0
    angles_a, angles_b = rng.uniform(-4 * math.pi, 4 * math.pi, n), rng.uniform(-4 * math.pi, 4 * math.pi, n)
    return centers_a, half_a, angles_a, centers_b, half_b, angles_b


@pytest.mark.parametrize("zero_fraction", [0.0, 0.3])
def test_batch_equals_the_readable_version(zero_fraction):
    rng = np.random.default_rng(11 + int(10 * zero_fraction))
    arrays = random_boxes(rng, 6000, zero_fraction)
    got = obbs_overlap_batch(*arrays)
    assert got.dtype == bool and got.shape == (6000,)
    ca, ha, ta, cb, hb, tb = arrays
    checked = 0
    for i in range(len(got)):
        a, b = OBB(ca[i], ha[i], ta[i]), OBB(cb[i], hb[i], tb[i])
        if abs(signed_gap(a, b)) < TOUCH_BAND:
            continue
        checked += 1
        assert got[i] == obbs_overlap(a, b), (a, b)
    assert checked > 5900 and 0.1 < got.mean() < 0.8


def test_batch_agrees_with_pymunk():
    rng = np.random.default_rng(12)
    ca, ha, ta, cb, hb, tb = random_boxes(rng, 2000)
    got = obbs_overlap_batch(ca, ha, ta, cb, hb, tb)
    for i in range(len(got)):
        a, b = OBB(ca[i], ha[i], ta[i]), OBB(cb[i], hb[i], tb[i])
        if abs(signed_gap(a, b)) >= TOUCH_BAND:
            assert got[i] == (pymunk_contact(a, b) is not None)


def test_batch_named_cases():
    # FLT_MIN case (apart), touching faces (overlap), same point boxes, an empty batch.
    got = obbs_overlap_batch([[-5, 0], [0, 0], [1, 1]], [[1, 1], [1, 1], [0, 0]], [0, 0, 0.3],
                             [[-2, 0], [2, 0], [1, 1]], [[1, 1], [1, 1], [0, 0]], [0, 0, -1.0])
    assert got.tolist() == [False, True, True]
    assert obbs_overlap_batch(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0),
                              np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0)).shape == (0,)


@pytest.mark.parametrize("broken", ["nan", "negative", "shape", "length"])
def test_batch_rejects_invalid_input(broken):
    arrays = [np.zeros((3, 2)), np.ones((3, 2)), np.zeros(3), np.ones((3, 2)), np.ones((3, 2)), np.zeros(3)]
    if broken == "nan":
        arrays[3][1, 0] = math.nan
    elif broken == "negative":
        arrays[4][2, 1] = -0.5
    elif broken == "shape":
        arrays[1] = np.ones((3, 3))
    else:
        arrays[5] = np.zeros(4)
    with pytest.raises(ValueError):
        obbs_overlap_batch(*arrays)
