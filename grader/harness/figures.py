"""Pictures of failing cases, drawn from the plain data a check returns.

A check describes its failing case as a plain dict (it crosses process boundaries and
goes into results files), and this module turns it into a matplotlib figure.  Two
kinds exist:

``"shapes"`` (from :func:`grader.oracles.narrowphase_answers` and the graded tests)
    ``{"kind": "shapes", "title": str, "shapes": [A, B], "expected": contact,
    "got": contact}``.  Shapes and contacts are tagged dicts of :mod:`grader.sandbox.codec`;
    ``expected`` is absent when the shapes are apart, ``got`` when the student's
    function returned no contact (or something that is not one).  Drawn: both
    outlines labelled A and B (B dashed when it lies exactly on A), the expected
    contact points and normal (A to B) in green, the returned ones in vermillion,
    dashed.
``"pairs"`` (from :func:`grader.oracles.brute_force.pairs_figure`)
    ``{"kind": "pairs", "title": str, "aabbs": [[min_x, min_y, max_x, max_y], ...],
    "cell_size": float, "missed": [[i, j], ...], "extra": [[i, j], ...],
    "bounds": [min_x, min_y, max_x, max_y] or None}``.  Drawn: every box in grey, the
    boxes of missed pairs filled and joined in vermillion, those of extra pairs
    (returned although the boxes are apart) hatched and joined in blue (a pair of
    coincident boxes, whose line would have no length, is ringed; coincident boxes
    are drawn nested, dashed, with one label "3=7"), the grid lines
    when ``cell_size > 0`` and the quadtree's root with its first splitting lines when
    ``bounds`` is given.

Figures are built with :class:`matplotlib.figure.Figure` directly (never pyplot), so
drawing changes no global state, needs no display and leaves nothing open; PNGs are
rendered with the Agg canvas.  Colours are from the Okabe-Ito palette, which stays
readable with colour blindness.  Lengths are in metres, y points up.
"""
from __future__ import annotations

import base64
import io
import math
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Circle as CirclePatch
from matplotlib.patches import FancyArrowPatch, Patch, Polygon, Rectangle
from matplotlib.patheffects import withStroke

from .figure_caps import bounded

SHAPE_COLORS = ("#0072B2", "#CC79A7")  # A blue, B reddish purple
EXPECTED_COLOR = "#009E73"  # bluish green
GOT_COLOR = "#D55E00"  # vermillion
MISSED_COLOR = "#D55E00"
EXTRA_COLOR = "#0072B2"
BOX_COLOR = "#7f7f7f"
GRID_COLOR = "#d0d0d0"
FIGSIZE = (6.4, 5.6)  # inches
DPI = 100
#: White halo that keeps text readable over lines and fills.
HALO = [withStroke(linewidth=3, foreground="white")]
#: Boxes are numbered on the picture when there are at most this many.
MAX_LABELLED_BOXES = 40
#: Places of coincident boxes named in the legend (the rest are counted).
MAX_LISTED_GROUPS = 4
#: Grid lines are drawn when there are at most this many per axis.
MAX_GRID_LINES = 150


def draw_figure(figure: dict) -> Figure:
    """A matplotlib figure of a failing case described by plain data.

    Parameters
    ----------
    figure : dict
        ``{"kind": "shapes", ...}`` or ``{"kind": "pairs", ...}`` (see the module
        docstring); lengths in m.

    Returns
    -------
    matplotlib.figure.Figure
        Not attached to pyplot: save it with :func:`save_figure` or
        :func:`figure_png_base64`, or let a notebook show it.

    Raises
    ------
    ValueError
        For a kind this module does not know.

    Examples
    --------
    >>> fig = draw_figure({"kind": "pairs", "title": "two boxes", "aabbs": [[0, 0, 1, 1], [1, 0, 2, 1]],
    ...                    "cell_size": 1.0, "missed": [[0, 1]], "extra": []})
    >>> fig.axes[0].get_xlabel()
    'x (m)'
    """
    if not isinstance(figure, dict):
        raise ValueError(f"a figure is a dict with a 'kind', got a {type(figure).__name__}")
    figure = bounded(figure)
    kind = figure.get("kind")
    fig = Figure(figsize=FIGSIZE, dpi=DPI)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    if kind == "shapes":
        _draw_shapes(ax, figure)
    elif kind == "pairs":
        _draw_pairs(ax, figure)
    else:
        raise ValueError(f"no picture for figures of kind {kind!r} (known: 'shapes', 'pairs')")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(False)
    fig.tight_layout()
    return fig


def figure_png_bytes(figure: dict | Figure) -> bytes:
    """The PNG image of a figure (plain data or an already drawn matplotlib figure)."""
    fig = figure if isinstance(figure, Figure) else draw_figure(figure)
    if fig.canvas is None or not isinstance(fig.canvas, FigureCanvasAgg):
        FigureCanvasAgg(fig)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=DPI)
    _close(fig)
    return buffer.getvalue()


def figure_png_base64(figure: dict | Figure) -> str:
    """The PNG image as base64 text, for ``<img src="data:image/png;base64,...">``."""
    return base64.b64encode(figure_png_bytes(figure)).decode("ascii")


def save_figure(figure: dict | Figure, path: str | Path) -> Path:
    """Write the figure as a PNG file at ``path`` (folders created); return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_bytes(figure_png_bytes(figure))
    return path


def _close(fig: Figure) -> None:
    """Release a figure: drop it from pyplot in case someone registered it there."""
    import sys

    pyplot = sys.modules.get("matplotlib.pyplot")
    if pyplot is not None:
        pyplot.close(fig)


# Shapes -----------------------------------------------------------------------------
def shape_outline(shape: dict) -> np.ndarray | tuple[np.ndarray, float]:
    """Vertices (k, 2) of a tagged polygonal shape, or ``(center, radius)`` of a circle."""
    kind = shape.get("$shape")
    if kind == "Circle":
        return np.asarray(shape["center"], dtype=float), float(shape["radius"])
    if kind == "AABB":
        (x0, y0), (x1, y1) = shape["min_corner"], shape["max_corner"]
        return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=float)
    if kind == "OBB":
        c = np.asarray(shape["center"], dtype=float)
        hx, hy = (float(h) for h in shape["half_extents"])
        cos, sin = math.cos(shape.get("angle", 0.0)), math.sin(shape.get("angle", 0.0))
        corners = np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])
        return c + corners @ np.array([[cos, sin], [-sin, cos]])
    if kind == "ConvexPolygon":
        return np.asarray(shape["vertices"], dtype=float).reshape(-1, 2)
    raise ValueError(f"cannot draw a shape of kind {kind!r}")


def _shape_points(outline) -> tuple[np.ndarray, np.ndarray, float]:
    """Points spanning a shape (for the axis limits), its centre and inner radius (m)."""
    if isinstance(outline, tuple):
        c, r = outline
        r = abs(r) if math.isfinite(r) else 0.0
        return np.array([c - r, c + r]), c, r
    if not len(outline):
        return np.zeros((1, 2)), np.zeros(2), 0.0
    c = outline.mean(axis=0)
    edges = np.roll(outline, -1, axis=0) - outline
    lengths = np.hypot(edges[:, 0], edges[:, 1])
    cross = np.abs(edges[:, 0] * (c[1] - outline[:, 1]) - edges[:, 1] * (c[0] - outline[:, 0]))
    inner = float(np.min(cross[lengths > 0] / lengths[lengths > 0])) if np.any(lengths > 0) else 0.0
    return outline, c, inner


def _same_outline(first, second) -> bool:
    """Whether two outlines of :func:`shape_outline` are the very same shape."""
    if isinstance(first, tuple) != isinstance(second, tuple):
        return False
    if isinstance(first, tuple):
        return bool(np.array_equal(first[0], second[0]) and first[1] == second[1])
    return first.shape == second.shape and bool(np.array_equal(first, second))


def _label_positions(centres: list[np.ndarray], radii: list[float]) -> list[np.ndarray]:
    """Where to write A and B: inside each shape, on the side away from the other one,
    so the labels stay clear of the contact drawn between them."""
    if len(centres) != 2:
        return centres
    away = centres[0] - centres[1]
    length = float(np.hypot(*away))
    if not math.isfinite(length) or length == 0.0:
        return [centres[0] + np.array([-0.5 * radii[0], 0.0]), centres[1] + np.array([0.5 * radii[1], 0.0])]
    away = away / length
    return [centres[0] + 0.55 * radii[0] * away, centres[1] - 0.55 * radii[1] * away]


def _contact_parts(contact) -> tuple[np.ndarray | None, np.ndarray, float | None]:
    """(normal or None, points (k, 2), depth or None) of a tagged contact, finite values only."""
    if not isinstance(contact, dict):
        return None, np.zeros((0, 2)), None
    try:
        normal = np.asarray(contact.get("normal"), dtype=float).reshape(2)
        normal = normal if np.all(np.isfinite(normal)) else None
    except (TypeError, ValueError):
        normal = None
    try:
        points = np.asarray(contact.get("points"), dtype=float).reshape(-1, 2)
        points = points[np.all(np.isfinite(points), axis=1)]
    except (TypeError, ValueError):
        points = np.zeros((0, 2))
    depth = contact.get("depth")
    depth = float(depth) if isinstance(depth, (int, float)) and not isinstance(depth, bool) else None
    return normal, points, depth


def _vector_text(v) -> str:
    return "(" + ", ".join(f"{x:.3g}" for x in v) + ")"


def _contact_text(contact, name: str) -> str:
    if contact is None:
        return f"{name}: no contact" if name == "expected" else f"{name}: no contact (None or not a Contact)"
    normal, points, depth = _contact_parts(contact)
    normal_text = _vector_text(normal) if normal is not None else "not a finite vector"
    depth_text = f"{depth:.3g} m" if depth is not None else "?"
    return f"{name}: normal {normal_text}, depth {depth_text}, {len(points)} point(s)"


def _draw_shapes(ax, figure: dict) -> None:
    shapes = list(figure.get("shapes") or [])[:2]
    extent_points, centres, radii = [], [], []
    outlines = [shape_outline(shape) for shape in shapes]
    # B exactly on A would hide it: then B's outline is dashed, so A's shows between.
    same_place = len(outlines) == 2 and _same_outline(*outlines)
    for index, (outline, color) in enumerate(zip(outlines, SHAPE_COLORS)):
        style = "--" if same_place and index == 1 else "-"
        if isinstance(outline, tuple):
            c, r = outline
            ax.add_patch(CirclePatch(c, r, fill=True, facecolor=color, alpha=0.12, edgecolor="none"))
            ax.add_patch(CirclePatch(c, r, fill=False, edgecolor=color, linewidth=2, linestyle=style))
        else:
            ax.add_patch(Polygon(outline, closed=True, facecolor=color, alpha=0.12, edgecolor="none"))
            ax.add_patch(Polygon(outline, closed=True, fill=False, edgecolor=color, linewidth=2, linestyle=style))
        span, centre, inner = _shape_points(outline)
        extent_points.append(span)
        centres.append(centre)
        radii.append(inner)
    for name, color, where in zip("AB", SHAPE_COLORS, _label_positions(centres, radii)):
        if np.all(np.isfinite(where)):
            ax.text(*where, name, color=color, fontsize=16, fontweight="bold", ha="center", va="center", zorder=8,
                    path_effects=HALO)
    all_points = np.vstack(extent_points) if extent_points else np.zeros((1, 2))
    all_points = all_points[np.all(np.isfinite(all_points), axis=1)]
    if not len(all_points):
        all_points = np.zeros((1, 2))
    size = float(np.max(np.ptp(all_points, axis=0))) or 1.0
    arrow_length = 0.3 * size
    fallback_start = np.mean(centres, axis=0) if centres else np.zeros(2)

    handles = [Patch(facecolor=c, alpha=0.4, edgecolor=c, label=f"shape {n}") for n, c in zip("AB", SHAPE_COLORS[:len(shapes)])]
    if same_place:
        handles.append(Line2D([], [], color=SHAPE_COLORS[1], linestyle="--", linewidth=2,
                              label="A and B coincide (B dashed)"))
    drawn_points = [all_points]
    for key, color, style, marker, width in (("expected", EXPECTED_COLOR, "-", "o", 3.0),
                                             ("got", GOT_COLOR, "--", "x", 1.8)):
        contact = figure.get(key)
        word = "expected" if key == "expected" else "returned"
        if contact is None:
            continue
        normal, points, depth = _contact_parts(contact)
        if len(points):
            if marker == "o":
                ax.plot(points[:, 0], points[:, 1], "o", markersize=10, markerfacecolor="none",
                        markeredgecolor=color, markeredgewidth=2, zorder=6)
            else:
                ax.plot(points[:, 0], points[:, 1], "x", markersize=10, color=color, markeredgewidth=2.5, zorder=7)
            drawn_points.append(points)
            handles.append(Line2D([], [], linestyle="none", marker=marker, markersize=9, color=color,
                                  markerfacecolor="none" if marker == "o" else color, markeredgewidth=2,
                                  label=f"{word} contact point(s)"))
        if normal is not None:
            starts = points if len(points) else fallback_start[None, :]
            for start in starts:
                end = start + arrow_length * normal
                ax.add_patch(FancyArrowPatch(start, end, arrowstyle="-|>", mutation_scale=18, color=color,
                                             linewidth=width, linestyle=style, zorder=6 if key == "expected" else 7))
                drawn_points.append(np.array([end]))
            depth_text = f", depth {depth:.3g} m" if depth is not None else ""
            handles.append(Line2D([], [], color=color, linewidth=width, linestyle=style,
                                  label=f"{word} normal A→B {_vector_text(normal)}{depth_text}"))
    if "expected" not in figure:
        handles.append(Line2D([], [], linestyle="none", label="expected: no contact (shapes apart)"))
    if "got" not in figure:
        handles.append(Line2D([], [], linestyle="none", label="returned: no contact (None or not a Contact)"))
    # Returned points far from both shapes (a wrong answer can be anywhere) stay out of
    # the view, or the shapes would shrink to a dot.
    view = np.vstack(drawn_points)
    middle = (all_points.min(axis=0) + all_points.max(axis=0)) / 2
    view = view[np.all(np.abs(view - middle) <= 3 * size, axis=1)]
    _set_limits(ax, np.vstack([all_points, view]))
    ax.set_title(_title(figure, "contact"), fontsize=11)
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(0.0, -0.12), fontsize=8.5, frameon=False, ncol=1)


def coincident_groups(boxes: np.ndarray) -> list[list[int]]:
    """Indices of boxes with exactly the same corners, one sorted list per place with
    more than one box, in order of their first index."""
    places: dict[tuple, list[int]] = {}
    for index, box in enumerate(boxes.tolist()):
        places.setdefault(tuple(box), []).append(index)
    return [group for group in places.values() if len(group) > 1]


def _inset(box: np.ndarray, rank: int) -> float:
    """How far inside its corners the ``rank``-th of coincident boxes is drawn (m): 6 %
    of the shorter side per rank, at most a third of it."""
    x0, y0, x1, y1 = (float(v) for v in box)
    side = min(x1 - x0, y1 - y0)
    if not math.isfinite(side) or side <= 0.0:
        return 0.0
    return min(0.06 * rank, 1 / 3) * side


def _set_limits(ax, points: np.ndarray, margin: float = 0.12) -> None:
    points = points[np.all(np.isfinite(points), axis=1)] if len(points) else np.zeros((1, 2))
    if not len(points):
        points = np.zeros((1, 2))
    lo, hi = points.min(axis=0), points.max(axis=0)
    span = float(max(np.max(hi - lo), 1e-12 * max(1.0, float(np.max(np.abs(points))))))
    if span == 0.0:
        span = 1.0
    pad = margin * span
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal", adjustable="box")


def _title(figure: dict, default: str) -> str:
    title = str(figure.get("title") or default)
    return title if len(title) <= 70 else title[:67] + "..."


# Pairs ------------------------------------------------------------------------------
def _pair_list(pairs, count: int) -> list[tuple[int, int]]:
    out = []
    for pair in pairs or []:
        try:
            i, j = (int(p) for p in pair)
        except (TypeError, ValueError):
            continue
        if 0 <= i < count and 0 <= j < count:
            out.append((i, j))
    return out


def _pairs_text(pairs: list[tuple[int, int]], limit: int = 5) -> str:
    text = ", ".join(f"({i}, {j})" for i, j in pairs[:limit])
    return text + (", ..." if len(pairs) > limit else "")


def _draw_pairs(ax, figure: dict) -> None:
    boxes = np.asarray(figure.get("aabbs") or np.zeros((0, 4)), dtype=float).reshape(-1, 4)
    count = len(boxes)
    missed = _pair_list(figure.get("missed"), count)
    extra = _pair_list(figure.get("extra"), count)
    centres = (boxes[:, :2] + boxes[:, 2:]) / 2

    # Boxes with the very same corners would hide one another: each is drawn inset a
    # little more than the one before, and they share one label "3=7".
    coincident = coincident_groups(boxes)
    rank = {k: position for group in coincident for position, k in enumerate(group)}
    for index, (x0, y0, x1, y1) in enumerate(boxes):
        inset = _inset(boxes[index], rank.get(index, 0))
        ax.add_patch(Rectangle((x0 + inset, y0 + inset), x1 - x0 - 2 * inset, y1 - y0 - 2 * inset, fill=False,
                               edgecolor=BOX_COLOR, linewidth=1.0, linestyle="--" if rank.get(index) else "-",
                               zorder=2))
    handles = [Patch(facecolor="none", edgecolor=BOX_COLOR, label=f"boxes ({count})")]
    if coincident:
        shown = ", ".join("=".join(map(str, group)) for group in coincident[:MAX_LISTED_GROUPS])
        more = f" and {len(coincident) - MAX_LISTED_GROUPS} more" if len(coincident) > MAX_LISTED_GROUPS else ""
        handles.append(Line2D([], [], color=BOX_COLOR, linestyle="--",
                              label=f"coincident boxes (drawn nested): {shown}{more}"))

    for pairs, color, hatch, style, word in ((missed, MISSED_COLOR, None, "-", "missed pair"),
                                             (extra, EXTRA_COLOR, "///", "--", "extra pair (boxes apart)")):
        members = sorted({k for pair in pairs for k in pair})
        for k in members:
            inset = _inset(boxes[k], rank.get(k, 0))
            x0, y0, x1, y1 = boxes[k] + np.array([inset, inset, -inset, -inset])
            if hatch is None:
                ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor=color, alpha=0.3, edgecolor="none", zorder=3))
            else:
                ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor="none", hatch=hatch, edgecolor=color,
                                       linewidth=0.0, alpha=0.7, zorder=3))
            ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, edgecolor=color, linewidth=2.0, zorder=4))
        for i, j in pairs:
            (xa, ya), (xb, yb) = centres[i], centres[j]
            if np.array_equal(boxes[i], boxes[j]):    # a line of length 0: ring the shared centre
                ax.plot([xa], [ya], "o", markersize=16, markerfacecolor="none", markeredgecolor=color,
                        markeredgewidth=2.0, zorder=5)
            else:
                ax.plot([xa, xb], [ya, yb], style, color=color, linewidth=2.0, marker="o", markersize=4, zorder=5)
        if pairs:
            handles.append(Line2D([], [], color=color, linewidth=2.0, linestyle=style, marker="o", markersize=4,
                                  label=f"{word}: {_pairs_text(pairs)}"))

    if count <= MAX_LABELLED_BOXES:
        highlighted = {k for pair in missed + extra for k in pair}
        group_of = {k: group for group in coincident for k in group}
        for k, (cx, cy) in enumerate(centres):
            group = group_of.get(k, [k])
            if k != group[0]:
                continue                                   # one label per place
            strong = any(member in highlighted for member in group)
            ax.text(cx, cy, "=".join(map(str, group)), fontsize=9 if strong else 7, ha="center", va="center",
                    zorder=6, path_effects=HALO, color="black" if strong else "#555555",
                    fontweight="bold" if strong else "normal")

    points = [boxes[:, :2], boxes[:, 2:]] if count else [np.zeros((1, 2))]
    bounds = figure.get("bounds")
    if bounds is not None:
        try:
            bx0, by0, bx1, by1 = (float(b) for b in bounds)
        except (TypeError, ValueError):
            bounds = None
    if bounds is not None:
        ax.add_patch(Rectangle((bx0, by0), bx1 - bx0, by1 - by0, fill=False, edgecolor="black", linewidth=1.8,
                               linestyle="--", zorder=1))
        # First two levels of splitting lines: where bodies straddle and stay at inner nodes.
        for level, alpha in ((1, 0.7), (2, 0.35)):
            parts = 2 ** level
            for k in range(1, parts):
                if k % 2 == 0 and level == 2:
                    continue
                x = bx0 + (bx1 - bx0) * k / parts
                y = by0 + (by1 - by0) * k / parts
                ax.plot([x, x], [by0, by1], ":", color="black", alpha=alpha, linewidth=1.0, zorder=1)
                ax.plot([bx0, bx1], [y, y], ":", color="black", alpha=alpha, linewidth=1.0, zorder=1)
        points.append(np.array([[bx0, by0], [bx1, by1]]))
        handles.append(Line2D([], [], color="black", linestyle="--", label="quadtree root"))
        handles.append(Line2D([], [], color="black", linestyle=":", alpha=0.7, label="splitting lines (2 levels)"))

    cell = figure.get("cell_size") or 0.0
    try:
        cell = float(cell)
    except (TypeError, ValueError):
        cell = 0.0
    if math.isfinite(cell) and cell > 0 and count:
        # Show whole cells around the boxes when that keeps the boxes readable: which
        # cells a box falls in is what a grid failure is about.
        lo = np.floor(boxes[:, :2].min(axis=0) / cell) * cell
        hi = np.ceil(boxes[:, 2:].max(axis=0) / cell) * cell
        hi = np.where(hi > lo, hi, lo + cell)
        span = float(np.max(boxes[:, 2:].max(axis=0) - boxes[:, :2].min(axis=0)))
        if float(np.max(hi - lo)) <= 10 * max(span, cell / 10):
            points.append(np.array([lo, hi]))
    _set_limits(ax, np.vstack(points), margin=0.08)
    if math.isfinite(cell) and cell > 0:
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        xs = np.arange(math.floor(x0 / cell), math.ceil(x1 / cell) + 1) * cell
        ys = np.arange(math.floor(y0 / cell), math.ceil(y1 / cell) + 1) * cell
        if len(xs) <= MAX_GRID_LINES and len(ys) <= MAX_GRID_LINES:
            for x in xs:
                ax.axvline(x, color=GRID_COLOR, linewidth=0.8, zorder=0)
            for y in ys:
                ax.axhline(y, color=GRID_COLOR, linewidth=0.8, zorder=0)
            handles.append(Line2D([], [], color=GRID_COLOR, linewidth=1.5, label=f"grid cells ({cell:.3g} m)"))
        ax.set_xlim(x0, x1)
        ax.set_ylim(y0, y1)

    summary = []
    if missed:
        summary.append(f"{len(missed)} overlapping pair{'s' * (len(missed) != 1)} missed")
    if extra:
        summary.append(f"{len(extra)} pair{'s' * (len(extra) != 1)} of separate boxes returned")
    title = _title(figure, "pairs")
    ax.set_title(title + ("\n" + ", ".join(summary) if summary else ""), fontsize=11)
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(0.0, -0.12), fontsize=8.5, frameon=False, ncol=2)
