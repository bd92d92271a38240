"""The numba twins against their numpy versions: the grid broad phase and the
box-box speculative manifolds.

numba is a pinned dependency, imported plainly.  The kernels are compiled with
``cache=True``: the first run in a fresh checkout compiles them (about 10 s of CPU),
later runs load the machine code from ``__pycache__``.
"""
from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numba  # noqa: F401  (a pinned dependency: fail loudly if it is missing)
import numpy as np
import pytest

from solutions.broadphase.brute_force import pairs_brute_force
from solutions.broadphase.grid_numba import pairs_grid_numba
from solutions.broadphase.sorted_grid_numpy import pairs_grid_numpy
from solutions.narrowphase.box_pairs_numba import (ROUNDING_NAMES, _tolerance_scales, matmul_rounding,
                                                  speculative_box_manifolds_numba)
from solutions.narrowphase.polygon_polygon import tolerance_scale
from solutions.narrowphase.speculative import SPECULATIVE_MARGIN
from solutions.narrowphase.speculative_batch import BoxManifolds, box_pose, speculative_box_manifolds
from solutions.scenes import SCENES
from solutions.shapes import AABB, OBB
from test_narrowphase_speculative import mixed_pairs, rotate

#: Float fields of the manifolds must agree to this, per m of coordinate size.
RTOL_COORD = 1e-12


# --- Grid broad phase --------------------------------------------------------------------
def grid_scenes(seed: int):
    """(name, aabbs) of many kinds: uniform, clustered, mixed sizes with some huge boxes
    (the oversized path), negative coordinates, boxes touching on strip boundaries,
    points and segments, duplicates."""
    rng = np.random.default_rng(seed)
    out = []
    for n in (2, 3, 50, 400, 2000):
        side = math.sqrt(4 * n / 3)
        centres = rng.uniform(-side, side, (n, 2))
        half = rng.uniform(0.25, 0.75, (n, 2))
        out.append((f"uniform {n}", np.hstack([centres - half, centres + half])))
        clusters = rng.uniform(-side, side, (max(1, n // 100), 2))
        centres = clusters[rng.integers(0, len(clusters), n)] + rng.normal(0, 2.0, (n, 2))
        out.append((f"clustered {n}", np.hstack([centres - half, centres + half])))
    # Mixed sizes: most small, a few 100 times larger (oversized for the default cell).
    n = 1500
    half = rng.uniform(0.1, 1.0, (n, 2)) * np.where(rng.random((n, 1)) < 0.02, 100.0, 1.0)
    centres = rng.uniform(-40, 40, (n, 2))
    out.append(("mixed sizes", np.hstack([centres - half, centres + half])))
    # Integer boxes: many touch exactly, and many edges lie on strip boundaries.
    corners = rng.integers(-20, 20, (800, 2)).astype(float)
    sizes = rng.integers(0, 3, (800, 2)).astype(float)
    out.append(("integer grid", np.hstack([corners, corners + sizes])))
    # Points and segments, and duplicated boxes.
    corners = rng.uniform(-5, 5, (600, 2))
    sizes = rng.uniform(0, 1, (600, 2)) * (rng.random((600, 2)) < 0.5)
    boxes = np.hstack([corners, corners + sizes])
    out.append(("points and segments", np.vstack([boxes, boxes[:100]])))
    # A tall stack over a wide floor, far from the origin.
    floor = [[1e5 - 50, -8e4 - 1, 1e5 + 50, -8e4]]
    stack = [[1e5 - 0.5, -8e4 + k, 1e5 + 0.5, -8e4 + k + 1] for k in range(60)]
    out.append(("stack on a floor, far", np.array(floor + stack)))
    return out


@pytest.mark.parametrize("seed", [0, 1])
def test_grid_numba_equals_the_numpy_grid(seed):
    checked = 0
    for name, aabbs in grid_scenes(seed):
        for cell_size in (None, 0.3, 7.0):
            for max_strips in (16, 2):
                want = pairs_grid_numpy(aabbs, cell_size, max_strips_per_body=max_strips)
                got = pairs_grid_numba(aabbs, cell_size, max_strips_per_body=max_strips)
                assert got.dtype == np.int64 and got.shape == want.shape, (name, cell_size, max_strips)
                assert np.array_equal(got, want), (name, cell_size, max_strips)
                checked += len(want)
    assert checked > 50_000


def test_grid_numba_on_the_benchmark_scenes():
    path = Path(__file__).resolve().parents[1] / "bench" / "bench_broadphase.py"
    spec = importlib.util.spec_from_file_location("bench_broadphase_scenes", path)
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    for kind in ("uniform", "clustered"):
        aabbs = bench.make_scene(kind, 10_000)
        want = pairs_grid_numpy(aabbs)
        assert len(want) > 10_000
        assert np.array_equal(pairs_grid_numba(aabbs), want), kind


def test_grid_numba_margin_is_the_world_growth():
    rng = np.random.default_rng(7)
    centres = rng.uniform(-10, 10, (700, 2))
    half = rng.uniform(0.2, 0.6, (700, 2))
    aabbs = np.hstack([centres - half, centres + half])
    for margin in (0.0, SPECULATIVE_MARGIN, 0.5):
        grown = aabbs + 0.5 * margin * np.array([-1.0, -1.0, 1.0, 1.0])   # as World.broad_phase
        got = pairs_grid_numba(aabbs, margin=margin)
        assert np.array_equal(got, pairs_grid_numpy(grown))
        assert set(map(tuple, got.tolist())) == pairs_brute_force(grown)
    # Gaps of 1 cm in x: paired with a 2 cm margin, not with 5 mm, nor without one.
    row = [[0.0, 0.0, 1.0, 1.0], [1.01, 0.0, 2.0, 1.0]]
    assert pairs_grid_numba(row, margin=0.02).tolist() == [[0, 1]]
    assert pairs_grid_numba(row, margin=0.005).tolist() == [] == pairs_grid_numba(row).tolist()


def test_grid_numba_sparse_strips_need_no_huge_table():
    # Strips numbered -1e12 .. 1e12 (cell 1 mm): counted directly, the table would not
    # fit in memory; the occupied strips are numbered instead.
    rng = np.random.default_rng(3)
    y = rng.choice([-1e9, -3.0, 0.0, 5e8, 1e9], 500) + rng.uniform(0, 0.01, 500)
    x = rng.uniform(0, 0.05, 500)
    aabbs = np.stack([x, y, x + 0.004, y + 0.004], axis=1)
    for max_strips in (16, 2):
        want = pairs_grid_numpy(aabbs, 1e-3, max_strips_per_body=max_strips)
        assert len(want) > 100
        assert np.array_equal(pairs_grid_numba(aabbs, 1e-3, max_strips_per_body=max_strips), want)


def test_grid_numba_edge_cases_and_bad_input():
    empty = pairs_grid_numba(np.zeros((0, 4)))
    assert empty.shape == (0, 2) and empty.dtype == np.int64
    assert pairs_grid_numba([]).shape == (0, 2)
    assert pairs_grid_numba([[0, 0, 1, 1]]).shape == (0, 2)
    assert pairs_grid_numba([[0, 0, 0, 0], [0, 0, 0, 0]]).tolist() == [[0, 1]]     # two points: cell 1 m
    assert pairs_grid_numba([[0, 0, 9, 9], [1, 1, 8, 8]], 0.5).tolist() == [[0, 1]]  # both oversized
    bad = [([[0, 0, 1]], {}), ([[2, 0, 1, 1]], {}), ([[0, 0, 1, np.nan]], {}), ([["a", 0, 1, 1]], {}),
           ([[0, 0, 1, 1]], {"cell_size": 0.0}), ([[0, 0, 1, 1]], {"cell_size": np.inf}),
           ([[0, 0, 1, 1], [0, 1e30, 1, 1e30]], {"cell_size": 1e-3}),
           ([[0, 0, 1, np.nan]], {"max_strips_per_body": 0, "cell_size": -1.0})]   # checked in the same order
    for aabbs, options in bad:
        with pytest.raises(ValueError) as numpy_error:
            pairs_grid_numpy(aabbs, **options)
        with pytest.raises(ValueError) as numba_error:
            pairs_grid_numba(aabbs, **options)
        assert str(numba_error.value) == str(numpy_error.value), (aabbs, options)
    with pytest.raises(ValueError, match="max_strips_per_body must be >= 1"):
        pairs_grid_numba([[0, 0, 1, 1]], max_strips_per_body=0)
    for margin in (-0.01, np.nan, np.inf):
        with pytest.raises(ValueError, match="margin"):
            pairs_grid_numba([[0, 0, 1, 1]], margin=margin)
    # Growing by the margin overflows: the grown boxes are rejected as the numpy grid would.
    with pytest.raises(ValueError, match="not finite"), np.errstate(over="ignore"):
        pairs_grid_numba([[0, 0, 1, 1.7e308]], margin=1e308)


# --- Box-box speculative manifolds ---------------------------------------------------------
INT_FIELDS = ("found", "count", "reference_is_b", "reference_face", "incident_face", "vertex")
FLOAT_FIELDS = ("normal", "points", "separations")


def assert_same_manifolds(got: BoxManifolds, want: BoxManifolds, arrays, where):
    """Flags, counts and feature ids equal; floats equal to RTOL_COORD per m of coordinate
    size (NaN in the same slots)."""
    assert isinstance(got, BoxManifolds) and len(got) == len(want), where
    for name in INT_FIELDS:
        g, w = getattr(got, name), getattr(want, name)
        assert g.dtype == w.dtype and g.shape == w.shape, (where, name)
        bad = np.flatnonzero((g != w).reshape(len(w), int(np.prod(w.shape[1:]))).any(axis=1))
        assert len(bad) == 0, f"{where}: {name} differs at pairs {bad[:10]}, first {[a[bad[0]] for a in arrays]}"
    ca, ha, ta, cb, hb, tb = arrays
    scale = np.maximum(1.0, np.maximum(np.abs(ca).max(axis=1) + ha.max(axis=1) * 1.5,
                                       np.abs(cb).max(axis=1) + hb.max(axis=1) * 1.5))
    for name in FLOAT_FIELDS:
        g, w = getattr(got, name), getattr(want, name)
        assert g.dtype == w.dtype and g.shape == w.shape, (where, name)
        assert np.array_equal(np.isnan(g), np.isnan(w)), (where, name)
        error = np.nan_to_num(np.abs(g - w)).reshape(len(w), int(np.prod(w.shape[1:]))).max(axis=1, initial=0.0)
        worst = int(np.argmax(error / scale)) if len(w) else 0
        assert np.all(error <= RTOL_COORD * scale), f"{where}: {name} off by {error[worst]} at pair {worst}"


def degenerate_pairs(seed: int, n: int):
    """Equal boxes, aligned edges, one box inside another, huge size ratios."""
    rng = np.random.default_rng(seed)
    out = {}
    centre, half, angle = rng.uniform(-3, 3, (n, 2)), rng.uniform(0.1, 1.5, (n, 2)), rng.uniform(-7, 7, n)
    angle[: n // 4] = rng.integers(-8, 9, n // 4) * (math.pi / 4)
    out["equal boxes"] = (centre, half, angle, centre.copy(), half.copy(), angle.copy())
    square = np.repeat(half[:, :1], 2, axis=1)
    out["equal squares, turned by quarter turns"] = (centre, square, angle, centre.copy(), square.copy(),
                                                     angle + rng.integers(1, 4, n) * (math.pi / 2))
    # Axis-aligned boxes on a 1/8 m lattice (exact in binary): edges on one line, shared
    # corners, boxes side by side and stacked; gaps of 0, 1/64 (within the margin) or 1/8.
    lattice = lambda size, low, high: rng.integers(low, high, size) / 8.0   # noqa: E731
    ca, ha = lattice((n, 2), -16, 16), lattice((n, 2), 1, 12)
    hb = lattice((n, 2), 1, 12)
    axis = rng.integers(0, 2, n)
    side = rng.choice([-1.0, 1.0], n)
    gap = rng.choice([0.0, 0.0, 1 / 64, 1 / 8, -1 / 8], n)
    align = rng.choice([-1.0, 0.0, 1.0], n)                  # min edges, centres or max edges on one line
    cb = np.empty((n, 2))
    rows = np.arange(n)
    cb[rows, axis] = ca[rows, axis] + side * (ha[rows, axis] + hb[rows, axis] + gap)
    other = 1 - axis
    cb[rows, other] = ca[rows, other] + align * (ha[rows, other] - hb[rows, other])
    zero = np.zeros(n)
    out["aligned edges"] = (ca, ha, zero, cb, hb, rng.integers(-4, 5, n) * (math.pi / 2))
    # One box inside another, turned or not (A inside B half the time).
    big_half = rng.uniform(0.5, 3.0, (n, 2))
    small_half = big_half.min(axis=1, keepdims=True) * rng.uniform(0.01, 0.3, (n, 2))
    big_angle = np.where(rng.random(n) < 0.3, 0.0, rng.uniform(-7, 7, n))
    small_angle = np.where(rng.random(n) < 0.3, big_angle, rng.uniform(-7, 7, n))
    offset = rotate(rng.uniform(-0.4, 0.4, (n, 2)) * big_half, big_angle)
    big_centre = rng.uniform(-3, 3, (n, 2))
    pair = [big_centre, big_half, big_angle, big_centre + offset, small_half, small_angle]
    swap = rng.random(n) < 0.5
    out["one inside another"] = tuple(np.where(swap[:, None] if p.ndim == 2 else swap, q, p)
                                      for p, q in zip(pair, pair[3:] + pair[:3]))
    # Huge size ratios: a 1e3-1e4 m slab and a 1 mm-10 cm box just above, on or into it.
    slab_half = np.stack([rng.uniform(1e3, 1e4, n), rng.uniform(1.0, 1e3, n)], axis=1)
    slab_angle = np.where(rng.random(n) < 0.5, 0.0, rng.uniform(-0.3, 0.3, n))
    tiny_half = rng.uniform(1e-3, 0.1, (n, 2))
    tiny_angle = np.where(rng.random(n) < 0.5, slab_angle, rng.uniform(-7, 7, n))
    relative = tiny_angle - slab_angle
    reach = tiny_half[:, 0] * np.abs(np.sin(relative)) + tiny_half[:, 1] * np.abs(np.cos(relative))
    gap = rng.choice([-1e-3, 0.0, 0.5 * SPECULATIVE_MARGIN, 2 * SPECULATIVE_MARGIN], n)
    local = np.stack([rng.uniform(-1.0, 1.0, n) * slab_half[:, 0], slab_half[:, 1] + reach + gap], axis=1)
    slab_centre = rng.uniform(-10, 10, (n, 2))
    pair = [slab_centre, slab_half, slab_angle, slab_centre + rotate(local, slab_angle), tiny_half, tiny_angle]
    out["huge size ratio"] = tuple(pair)
    out["huge size ratio, swapped"] = tuple(pair[3:] + pair[:3])
    return {name: tuple(np.asarray(a, dtype=float) for a in arrays) for name, arrays in out.items()}


def test_the_rounding_of_numpy_matmul_is_identified():
    # The numpy version's corners and incident-face products go through numpy's BLAS,
    # which may fuse a multiply-add; the twin must round the same way, or exact ties
    # (two equal boxes) are broken differently (other faces, feature ids, normals).
    corners, incident, exact = matmul_rounding()
    assert exact, ("numpy's matmul rounds its 2-term dot products in none of the known ways: "
                   f"using {ROUNDING_NAMES[corners]} / {ROUNDING_NAMES[incident]}")


def test_the_tolerance_scale_is_the_numpy_versions():
    # The rounding tolerances decide near-ties (reference face, kept and duplicate
    # points), too rarely for random pairs to notice a different scale: compared here.
    rng = np.random.default_rng(8)
    m = 4000
    vertices_a = (rng.normal(size=(m, 4, 2)) * rng.choice([1e-3, 1.0, 1e3], (m, 1, 1))
                  + rng.choice([0.0, 1e5], (m, 1, 2)))
    vertices_b = rng.normal(size=(m, 4, 2)) * rng.choice([0.0, 1e-2, 1.0], (m, 1, 1))
    want = tolerance_scale(vertices_a, vertices_b)
    assert np.array_equal(_tolerance_scales(vertices_a, vertices_b), want)
    assert np.array_equal(_tolerance_scales(vertices_b, vertices_a), want)


@pytest.mark.parametrize("margin", [SPECULATIVE_MARGIN, 0.0, 0.1])
def test_box_manifolds_numba_equal_numpy_on_many_pairs(margin):
    kinds = mixed_pairs(seed=40 + int(100 * margin), n_per_kind=250 if margin == SPECULATIVE_MARGIN else 80)
    kinds.update(degenerate_pairs(seed=41 + int(100 * margin), n=250 if margin == SPECULATIVE_MARGIN else 80))
    totals = dict(pairs=0, found=0, one=0, two=0, ref_b=0)
    for name, arrays in kinds.items():
        want = speculative_box_manifolds(*arrays, margin=margin)
        got = speculative_box_manifolds_numba(*arrays, margin=margin)
        assert_same_manifolds(got, want, arrays, f"{name}, margin {margin}")
        totals["pairs"] += len(want)
        totals["found"] += int(want.found.sum())
        totals["one"] += int((want.count == 1).sum())
        totals["two"] += int((want.count == 2).sum())
        totals["ref_b"] += int(want.reference_is_b.sum())
    # Every branch is met: found and not, one and two points, B's reference face.
    assert totals["pairs"] > (5000 if margin == SPECULATIVE_MARGIN else 1500), totals
    assert 0.2 < totals["found"] / totals["pairs"] < 0.95, totals
    assert totals["one"] > 50 and totals["two"] > 300 and totals["ref_b"] > 50, totals


def test_box_manifolds_numba_on_the_hard_scenes():
    found = 0
    for scene in SCENES.values():
        if not scene.hard:
            continue
        shapes = [body.world_shape() for body in scene.make_bodies()]
        boxes = [k for k, shape in enumerate(shapes) if isinstance(shape, (AABB, OBB))]
        pairs = [(i, j) for a, i in enumerate(boxes) for j in boxes[a + 1:]]
        if not pairs:
            continue
        poses_a = [box_pose(shapes[i]) for i, _ in pairs]
        poses_b = [box_pose(shapes[j]) for _, j in pairs]
        arrays = tuple(np.array(column, dtype=float) for column in [*zip(*poses_a), *zip(*poses_b)])
        want = speculative_box_manifolds(*arrays, SPECULATIVE_MARGIN)
        assert_same_manifolds(speculative_box_manifolds_numba(*arrays, SPECULATIVE_MARGIN), want, arrays, scene.name)
        found += int(want.found.sum())
    assert found > 300


def test_box_manifolds_numba_edge_cases_and_bad_input():
    zeros2, zeros1 = np.zeros((0, 2)), np.zeros(0)
    empty = speculative_box_manifolds_numba(zeros2, zeros2, zeros1, zeros2, zeros2, zeros1)
    assert_same_manifolds(empty, speculative_box_manifolds(zeros2, zeros2, zeros1, zeros2, zeros2, zeros1),
                          (zeros2, zeros2, zeros1, zeros2, zeros2, zeros1), "empty")
    assert empty.points.shape == (0, 2, 2)
    point = ([[0.0, 0.0]], [[0.0, 0.0]], [0.0], [[0.0, 0.0]], [[0.0, 0.0]], [0.0])
    assert_same_manifolds(speculative_box_manifolds_numba(*point), speculative_box_manifolds(*point),
                          tuple(np.array(a, dtype=float) for a in point), "coincident points")
    # Lists and non-contiguous views are accepted as by the numpy version.
    wide = np.array([[0.0, 0.0, 9.0], [1.0, 0.0, 9.0]])
    view = (wide[:, :2], [[1.0, 1.0]] * 2, [0.0, 0.3], wide[::-1, :2], [[1.0, 1.0]] * 2, [0.1, 0.0])
    assert_same_manifolds(speculative_box_manifolds_numba(*view), speculative_box_manifolds(*view),
                          tuple(np.array(a, dtype=float) for a in view), "views")
    good = ([[0.0, 0.0]], [[1.0, 1.0]], [0.0], [[1.0, 0.0]], [[1.0, 1.0]], [0.0])
    bad = [((*good,), {"margin": -0.01}), ((*good,), {"margin": float("nan")}), ((*good[:5], [0.0, 1.0]), {}),
           (([[np.nan, 0.0]], *good[1:]), {}), ((good[0], [[-1.0, 1.0]], *good[2:]), {})]
    for arguments, options in bad:
        with pytest.raises(ValueError) as numpy_error:
            speculative_box_manifolds(*arguments, **options)
        with pytest.raises(ValueError) as numba_error:
            speculative_box_manifolds_numba(*arguments, **options)
        assert str(numba_error.value) == str(numpy_error.value)
