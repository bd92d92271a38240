"""Speculative manifolds: the scalar reference against independent facts, and the
vectorised box-box version against the scalar one."""
from __future__ import annotations

import math

import numpy as np
import pytest

from solutions.contact import Contact
from solutions.narrowphase.polygon_polygon import KEEP_POINT_TOL, collide_polygon_polygon
from solutions.narrowphase.speculative import SPECULATIVE_MARGIN, speculative_polygon_manifold
from solutions.narrowphase.speculative_batch import (BoxManifolds, manifolds_as_contacts,
                                                     speculative_box_manifolds)
from solutions.shapes import AABB, OBB

#: Relative tolerance (per m of coordinate size) of the batch-vs-scalar float checks:
#: the two compute the same expressions, so they agree to a few ulps (in practice to
#: the bit); 1e-12 is the tolerance the scalar code itself uses for roundoff.
RTOL_COORD = 1e-12


# --- Pair generators ------------------------------------------------------------------
def rotate(vectors, angle):
    c, s = np.cos(angle), np.sin(angle)
    x, y = vectors[..., 0], vectors[..., 1]
    return np.stack([c * x - s * y, s * x + c * y], axis=-1)


def random_pairs(rng, n, spread=2.0):
    """Boxes anywhere in a few metres: overlapping, near and far apart."""
    return (rng.uniform(-spread, spread, (n, 2)), rng.uniform(0.05, 1.5, (n, 2)), rng.uniform(-7, 7, n),
            rng.uniform(-spread, spread, (n, 2)), rng.uniform(0.05, 1.5, (n, 2)), rng.uniform(-7, 7, n))


def placed_pairs(rng, n, gaps, quarter_turns=False):
    """B beyond one face of A at a signed gap ``gaps`` (< 0 overlap, 0 touching).

    B's nearest corner or face is ``gap`` outside A's face along its normal (exactly
    up to the rounding of the rotation); it slides along the face past its ends.
    """
    centre_a, half_a, half_b = rng.uniform(-3, 3, (n, 2)), rng.uniform(0.1, 1.5, (n, 2)), rng.uniform(0.1, 1.5, (n, 2))
    if quarter_turns:
        angle_a = rng.integers(-4, 5, n) * (math.pi / 2)
        relative = rng.integers(-4, 5, n) * (math.pi / 2)
    else:
        angle_a = rng.uniform(-7, 7, n)
        relative = np.where(rng.random(n) < 0.4, 0.0, rng.uniform(-4, 4, n))
    face = rng.integers(0, 4, n)                               # face of A that B faces
    local_normal = np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]])[face]
    local_tangent = np.stack([-local_normal[:, 1], local_normal[:, 0]], axis=1)
    half_normal = np.where(face % 2 == 0, half_a[:, 1], half_a[:, 0])
    half_tangent = np.where(face % 2 == 0, half_a[:, 0], half_a[:, 1])
    # B's half-width along A's face normal (local frame of A).
    reach = half_b[:, 0] * np.abs(np.cos(relative) * local_normal[:, 0] + np.sin(relative) * local_normal[:, 1]) \
        + half_b[:, 1] * np.abs(-np.sin(relative) * local_normal[:, 0] + np.cos(relative) * local_normal[:, 1])
    slide = rng.uniform(-1.2, 1.2, n) * (half_tangent + half_b.max(axis=1))
    local_b = (half_normal + reach + gaps)[:, None] * local_normal + slide[:, None] * local_tangent
    centre_b = centre_a + rotate(local_b, angle_a)
    return centre_a, half_a, angle_a, centre_b, half_b, angle_a + relative


def stacked_pairs(rng, n, lift, quarter_turns=False):
    """B resting on A's top face, same angle, then turned about one bottom corner so
    that its other bottom corner lifts by ``lift`` (m); A and B swapped half the time."""
    centre_a, half_a, half_b = rng.uniform(-3, 3, (n, 2)), rng.uniform(0.1, 1.5, (n, 2)), rng.uniform(0.1, 1.5, (n, 2))
    if quarter_turns:
        angle_a = rng.integers(-4, 5, n) * (math.pi / 2)
    else:
        angle_a = np.where(rng.random(n) < 0.3, 0.0, rng.uniform(-7, 7, n))
    hax, hay, hbx, hby = half_a[:, 0], half_a[:, 1], half_b[:, 0], half_b[:, 1]
    # Pivot corner on A's top face; B overhangs A's ends part of the time.
    pivot_x = rng.uniform(-hax - 1.5 * hbx, hax - 0.5 * hbx)
    left = rng.random(n) < 0.5                                  # pivot on B's corner 0 (else 1)
    tilt = np.arcsin(lift / (2.0 * hbx)) * np.where(left, 1.0, -1.0)
    pivot_x = np.where(left, pivot_x, pivot_x + 2.0 * hbx)
    to_centre = rotate(np.stack([np.where(left, hbx, -hbx), hby], axis=1), tilt)
    local_b = np.stack([pivot_x, hay], axis=1) + to_centre
    centre_b = centre_a + rotate(local_b, angle_a)
    angle_b = angle_a + tilt
    swap = rng.random(n) < 0.5
    pairs = [centre_a, half_a, angle_a, centre_b, half_b, angle_b]
    return tuple(np.where(swap[:, None] if p.ndim == 2 else swap, q, p) for p, q in zip(pairs, pairs[3:] + pairs[:3]))


def mixed_pairs(seed, n_per_kind=250):
    """A few thousand pairs of every kind the brief names, as six arrays."""
    rng = np.random.default_rng(seed)
    m = SPECULATIVE_MARGIN
    kinds = {
        "random": random_pairs(rng, n_per_kind),
        "overlapping": placed_pairs(rng, n_per_kind, rng.uniform(-0.3, 0.0, n_per_kind)),
        "touching": placed_pairs(rng, n_per_kind, np.zeros(n_per_kind)),
        "within margin": placed_pairs(rng, n_per_kind, rng.uniform(0.0, m, n_per_kind)),
        "beyond margin": placed_pairs(rng, n_per_kind, rng.uniform(m, 4 * m, n_per_kind)),
        "quarter turns": placed_pairs(rng, n_per_kind, rng.choice([-0.1, 0.0, 0.5 * m, 2 * m], n_per_kind),
                                      quarter_turns=True),
        "stacked": stacked_pairs(rng, n_per_kind, 0.0),
        "stacked 1e-13": stacked_pairs(rng, n_per_kind, 1e-13),
        "stacked 1e-3": stacked_pairs(rng, n_per_kind, 1e-3),
        "stacked quarter turns": stacked_pairs(rng, n_per_kind, rng.choice([0.0, 1e-13, 1e-3], n_per_kind),
                                               quarter_turns=True),
    }
    # Far from the origin: the same kinds of pairs moved by about 1e5 m.
    for name in ("touching", "within margin", "stacked", "stacked 1e-3"):
        ca, ha, ta, cb, hb, tb = (a.copy() for a in kinds[name])
        shift = rng.uniform(-1.2e5, 1.2e5, (n_per_kind, 2))
        kinds[name + " far"] = (ca + shift, ha, ta, cb + shift, hb, tb)
    # Very different sizes (1 mm against 100 m), and zero-size boxes (points, segments).
    n = n_per_kind
    ca, ha, ta = rng.uniform(-3, 3, (n, 2)), rng.uniform(0.1, 1.5, (n, 2)), rng.uniform(-7, 7, n)
    hb = rng.uniform(0.1, 1.5, (n, 2)) * rng.choice([1e-3, 1e-2, 30.0, 100.0], (n, 1))
    kinds["different sizes"] = placed_pairs_like(ca, ha, ta, hb, rng.uniform(-7, 7, n), rng, m)
    ca, ha, ta, cb, hb, tb = (a.copy() for a in random_pairs(rng, n_per_kind, spread=1.0))
    ha[rng.random((n_per_kind, 2)) < 0.3] = 0.0
    hb[rng.random((n_per_kind, 2)) < 0.3] = 0.0
    kinds["zero size"] = (ca, ha, ta, cb, hb, tb)
    return {name: tuple(np.asarray(a, dtype=float) for a in arrays) for name, arrays in kinds.items()}


def placed_pairs_like(centre_a, half_a, angle_a, half_b, angle_b, rng, margin):
    """B of the given size and angle placed beyond A's top face at a gap near the margin."""
    n = len(centre_a)
    relative = angle_b - angle_a
    reach = half_b[:, 0] * np.abs(np.sin(relative)) + half_b[:, 1] * np.abs(np.cos(relative))
    gap = rng.uniform(-0.5 * margin, 1.5 * margin, n)
    slide = rng.uniform(-1.0, 1.0, n) * (half_a[:, 0] + half_b.max(axis=1))
    local_b = np.stack([slide, half_a[:, 1] + reach + gap], axis=1)
    return centre_a, half_a, angle_a, centre_a + rotate(local_b, angle_a), half_b, angle_b


def boxes(arrays, k):
    ca, ha, ta, cb, hb, tb = arrays
    return OBB(ca[k], ha[k], ta[k]), OBB(cb[k], hb[k], tb[k])


def coordinate_scale(a, b):
    return max(float(np.abs(a.vertices()).max()), float(np.abs(b.vertices()).max()), 1.0)


# --- Batch against scalar -------------------------------------------------------------
def assert_same_manifold(got, want, scale, where):
    """``got`` from manifolds_as_contacts, ``want`` from the scalar function."""
    assert (got is None) == (want is None), where
    if want is None:
        return
    contact, want_contact = got, want
    separations, want_separations = contact.separations, want_contact.separations
    assert contact.feature_ids == want_contact.feature_ids, where
    assert all(isinstance(v, int) for fid in contact.feature_ids for v in fid[1:]), where
    atol = RTOL_COORD * scale
    np.testing.assert_allclose(contact.normal, want_contact.normal, rtol=0, atol=1e-15, err_msg=where)
    np.testing.assert_allclose(contact.points, want_contact.points, rtol=0, atol=atol, err_msg=where)
    np.testing.assert_allclose(separations, want_separations, rtol=0, atol=atol, err_msg=where)
    np.testing.assert_allclose(contact.depths, want_contact.depths, rtol=0, atol=atol, err_msg=where)
    assert contact.depth == pytest.approx(want_contact.depth, abs=atol), where


@pytest.mark.parametrize("margin", [SPECULATIVE_MARGIN, 0.0, 0.1])
def test_batch_equals_the_scalar_function(margin):
    kinds = mixed_pairs(seed=20 + int(100 * margin), n_per_kind=250 if margin == SPECULATIVE_MARGIN else 60)
    totals = dict(found=0, pairs=0, two=0, one=0, ref_b=0)
    for name, arrays in kinds.items():
        result = speculative_box_manifolds(*arrays, margin=margin)
        assert isinstance(result, BoxManifolds) and len(result) == len(arrays[0])
        got = manifolds_as_contacts(result)
        for k in range(len(got)):
            a, b = boxes(arrays, k)
            want = speculative_polygon_manifold(a, b, margin)
            where = f"{name} #{k}: {a} {b}"
            assert_same_manifold(got[k], want, coordinate_scale(a, b), where)
            # The arrays themselves: counts, empty slots, feature ids.
            count = result.count[k]
            assert result.found[k] == (count > 0) == (want is not None), where
            assert np.all(np.isnan(result.points[k, count:])) and np.all(result.vertex[k, count:] == -1), where
            if want is None:
                assert np.all(np.isnan(result.normal[k])) and result.reference_face[k] == -1, where
                continue
            ref = "B" if result.reference_is_b[k] else "A"
            assert want.feature_ids == tuple((ref, int(result.reference_face[k]), int(result.incident_face[k]),
                                                 int(v)) for v in result.vertex[k, :count]), where
            totals["two" if count == 2 else "one"] += 1
            totals["ref_b"] += ref == "B"
        totals["found"] += int(result.found.sum())
        totals["pairs"] += len(result)
    # The mix exercises every branch: found and not, 1 and 2 points, B's reference face.
    assert 0.2 < totals["found"] / totals["pairs"] < 0.9, totals
    assert totals["one"] > 20 and totals["two"] > 100 and totals["ref_b"] > 30, totals


def test_stacked_boxes_keep_both_corners():
    # Same angle, resting, lifted 0 / 1e-13 / 1 mm at one corner: two points, near the origin and far.
    for lift in (0.0, 1e-13, 1e-3):
        for shift in (0.0, 1e5):
            a = OBB((shift, 0.0), (2.0, 0.5), 0.3)
            corner = a.vertices()[3] + rotate(np.array([0.5, 0.0]), 0.3)   # on A's top face
            tilt = math.asin(lift / 2.0)
            b = OBB(corner + rotate(np.array([1.0, 0.5]), 0.3 + tilt), (1.0, 0.5), 0.3 + tilt)
            want = speculative_polygon_manifold(a, b)
            assert want is not None and len(want.separations) == 2
            np.testing.assert_allclose(np.sort(want.separations), [0.0, lift], atol=1e-10 * max(1.0, shift))
            result = speculative_box_manifolds([a.center], [a.half_extents], [a.angle],
                                               [b.center], [b.half_extents], [b.angle])
            assert_same_manifold(manifolds_as_contacts(result)[0], want, coordinate_scale(a, b), (lift, shift))


def test_floor_as_aabb_equals_floor_as_obb():
    # The world's ground is an AABB; the batch takes it as the OBB of its centre at angle 0.
    rng = np.random.default_rng(5)
    floor = AABB((-5.0, -1.0), (5.0, 0.0))
    for _ in range(50):
        crate = OBB((rng.uniform(-5, 5), rng.uniform(0.3, 0.6)), (0.5, 0.5), rng.uniform(-0.2, 0.2))
        want = speculative_polygon_manifold(floor, crate)
        result = speculative_box_manifolds([floor.center], [floor.half_extents], [0.0],
                                           [crate.center], [crate.half_extents], [crate.angle])
        assert_same_manifold(manifolds_as_contacts(result)[0], want, 5.0, crate)


def test_batch_edge_cases_and_bad_input():
    empty = speculative_box_manifolds(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0),
                                      np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0))
    assert len(empty) == 0 and empty.points.shape == (0, 2, 2) and manifolds_as_contacts(empty) == []
    # Coincident point boxes at the origin: scale 0, every tolerance 0.
    point = speculative_box_manifolds([[0.0, 0.0]], [[0.0, 0.0]], [0.0], [[0.0, 0.0]], [[0.0, 0.0]], [0.0])
    want = speculative_polygon_manifold(OBB((0.0, 0.0), (0.0, 0.0)), OBB((0.0, 0.0), (0.0, 0.0)))
    assert_same_manifold(manifolds_as_contacts(point)[0], want, 1.0, "points")
    good = ([[0.0, 0.0]], [[1.0, 1.0]], [0.0], [[1.0, 0.0]], [[1.0, 1.0]], [0.0])
    for margin in (-0.01, float("nan")):
        with pytest.raises(ValueError, match="margin"):
            speculative_box_manifolds(*good, margin=margin)
    with pytest.raises(ValueError, match="shape"):
        speculative_box_manifolds(*good[:5], [0.0, 1.0])
    with pytest.raises(ValueError, match="finite"):
        speculative_box_manifolds([[np.nan, 0.0]], *good[1:])
    with pytest.raises(ValueError, match=">= 0"):
        speculative_box_manifolds(good[0], [[-1.0, 1.0]], *good[2:])


# --- The scalar function against independent facts ------------------------------------
def test_crate_one_centimetre_above_the_floor():
    floor = AABB((-5.0, -1.0), (5.0, 0.0))
    crate = OBB((1.5, 0.51), (0.5, 0.5), 0.0)
    contact = speculative_polygon_manifold(floor, crate)
    np.testing.assert_allclose(contact.separations, [0.01, 0.01], atol=1e-15)
    np.testing.assert_allclose(contact.normal, [0.0, 1.0])
    np.testing.assert_allclose(sorted(contact.points.tolist()), [[1.0, 0.005], [2.0, 0.005]], atol=1e-15)
    assert contact.depth == 0.0 and np.all(contact.depths == 0.0)
    assert speculative_polygon_manifold(floor, crate, margin=0.0099) is None
    assert collide_polygon_polygon(floor, crate) is None


def test_negative_margin_is_refused():
    floor, crate = AABB((-5.0, -1.0), (5.0, 0.0)), OBB((0.0, 0.51), (0.5, 0.5), 0.0)
    with pytest.raises(ValueError, match="margin"):
        speculative_polygon_manifold(floor, crate, margin=-1e-9)


def test_moving_b_along_the_normal_adds_to_every_separation():
    rng = np.random.default_rng(7)
    m = SPECULATIVE_MARGIN
    arrays = [np.concatenate(parts) for parts in zip(
        placed_pairs(rng, 300, rng.uniform(-0.2, m, 300)),
        stacked_pairs(rng, 100, 1e-3),
        placed_pairs(rng, 100, rng.uniform(-0.1, m, 100), quarter_turns=True))]
    checked = same = 0
    for k in range(len(arrays[0])):
        a, b = boxes(arrays, k)
        found = speculative_polygon_manifold(a, b)
        if found is None or not max(found.separations) < m - 1e-6:
            continue
        contact, separations = found, found.separations
        t = rng.uniform(0.01, 0.99) * (m - max(separations))
        moved = speculative_polygon_manifold(a, OBB(b.center + t * contact.normal, b.half_extents, b.angle))
        checked += 1
        assert moved is not None, (a, b, t)
        if moved.feature_ids != contact.feature_ids:
            continue   # the 2 % hysteresis of the reference face can hand the role over
        same += 1
        atol = 1e-12 * coordinate_scale(a, b)
        np.testing.assert_allclose(moved.separations, separations + t, rtol=0, atol=atol)
        np.testing.assert_allclose(moved.normal, contact.normal, rtol=0, atol=1e-15)
        # Each point is the midpoint between the surfaces: it moves by half of t.
        np.testing.assert_allclose(moved.points, contact.points + 0.5 * t * contact.normal, rtol=0, atol=atol)
    assert checked > 300 and same > 0.95 * checked, (checked, same)


def test_overlapping_boxes_match_the_contact_manifold():
    rng = np.random.default_rng(8)
    arrays = [np.concatenate(parts) for parts in zip(
        random_pairs(rng, 300, spread=1.0),
        placed_pairs(rng, 300, rng.uniform(-0.3, 0.0, 300)),
        stacked_pairs(rng, 100, 0.0),
        placed_pairs(rng, 100, rng.uniform(-0.3, 0.0, 100), quarter_turns=True))]
    overlapping = compared = 0
    for k in range(len(arrays[0])):
        a, b = boxes(arrays, k)
        contact = collide_polygon_polygon(a, b)
        if contact is None:
            continue
        overlapping += 1
        found = speculative_polygon_manifold(a, b)
        assert found is not None, (a, b)       # an overlap is always within the margin
        speculative, separations = found, found.separations
        if speculative.feature_ids[0][:2] != contact.feature_ids[0][:2]:
            continue   # collide_polygon_polygon may switch to B's face to keep the deepest vertex
        compared += 1
        np.testing.assert_allclose(speculative.normal, contact.normal, rtol=0, atol=1e-15)
        # The contact's points are those of the speculative manifold that lie on or below
        # the reference face; the speculative one adds those up to the margin above it.
        roundoff = KEEP_POINT_TOL * coordinate_scale(a, b)
        by_id = dict(zip(speculative.feature_ids, zip(speculative.points, separations)))
        for fid, point, depth in zip(contact.feature_ids, contact.points, contact.depths):
            assert fid in by_id, (a, b)
            np.testing.assert_allclose(by_id[fid][0], point, rtol=0, atol=roundoff)
            assert max(-by_id[fid][1], 0.0) == pytest.approx(depth, abs=roundoff)
        extra = [s for fid, s in zip(speculative.feature_ids, separations) if fid not in contact.feature_ids]
        assert all(s > 0.0 for s in extra), (a, b)
        assert speculative.depth == pytest.approx(max(contact.depths), abs=roundoff)
    assert overlapping > 500 and compared > 0.9 * overlapping, (overlapping, compared)


def test_a_contact_keeps_the_signed_separations_of_its_points():
    """Depths are clamped at 0; the separations keep how far apart a point still is."""
    hovering = Contact((0.0, 1.0), -0.01, [(0.0, 0.0), (1.0, 0.0)], depths=[-0.01, 0.002])
    assert hovering.depth == 0.0 and hovering.depths.tolist() == [0.0, 0.002]
    assert hovering.separations.tolist() == [0.01, -0.002]
    assert hovering.flipped().separations.tolist() == [0.01, -0.002]
    assert Contact((1.0, 0.0), 0.03, [(0.0, 0.0)]).separations.tolist() == [-0.03]
    explicit = Contact((1.0, 0.0), 0.0, [(0.0, 0.0)], depths=[0.0], separations=[0.004])
    assert explicit.separations.tolist() == [0.004] and explicit.depths.tolist() == [0.0]
