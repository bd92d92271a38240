"""The chapters' committed notebooks stay small (their images stored as palette PNG by
tools/notebook_images.py) and look the same.  Cheap: no kernel, no build."""
from __future__ import annotations

import base64
import io
import re

import matplotlib
import numpy as np
import pytest
from PIL import Image

from tools import book
from tools.notebook_images import compact_html, palette_png

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)
from matplotlib.animation import FuncAnimation  # noqa: E402

#: Bytes the chapters' .ipynb may take together (issue 25: under 6 MB; the student
#: folder, which holds them, must stay under 12 MB).
NOTEBOOKS_BUDGET = 6_000_000


def test_committed_notebooks_fit_the_budget():
    sizes = {md.with_suffix(".ipynb").name: md.with_suffix(".ipynb").stat().st_size
             for md in book.chapter_sources()}
    total = sum(sizes.values())
    largest = ", ".join(f"{name} {size / 1e6:.2f} MB" for name, size in
                        sorted(sizes.items(), key=lambda item: -item[1])[:3])
    assert total < NOTEBOOKS_BUDGET, (
        f"the chapters' notebooks take {total / 1e6:.2f} MB, over {NOTEBOOKS_BUDGET / 1e6:.0f} MB "
        f"(largest: {largest}); sync them with `python -m tools.book sync NN` (it stores "
        f"palette PNG), or store fewer/smaller animation frames")


def _figure(seed: int = 0) -> plt.Figure:
    rng = np.random.default_rng(seed)
    fig, ax = plt.subplots(figsize=(4, 3), dpi=80)
    for _ in range(12):
        ax.add_patch(plt.Circle(rng.uniform(0, 10, 2), rng.uniform(0.3, 1.5), alpha=0.5,
                                color=plt.cm.tab10(rng.integers(10))))
    ax.plot(np.linspace(0, 10, 50), 5 + 3 * np.sin(np.linspace(0, 10, 50)), lw=2)
    ax.set(xlim=(0, 10), ylim=(0, 10), title="circles")
    return fig


def _pixels(png: bytes) -> np.ndarray:
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=float)


def test_palette_png_is_smaller_and_looks_the_same():
    fig = _figure()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png")
    plt.close(fig)
    original = buffer.getvalue()
    compact = palette_png(original)
    assert len(compact) < 0.7 * len(original)
    assert Image.open(io.BytesIO(compact)).mode == "P"
    before, after = _pixels(original), _pixels(compact)
    assert before.shape == after.shape
    assert np.abs(before - after).mean() < 1.0      # of 255 per channel
    assert palette_png(compact) == compact          # a second pass changes nothing


def test_animation_frames_are_compacted_and_the_player_kept():
    fig = _figure(1)
    line = fig.axes[0].plot([], [], "k-")[0]
    animation = FuncAnimation(fig, lambda i: line.set_data([0, i], [0, 10 - i]), frames=3)
    html_text = animation.to_jshtml()
    plt.close(fig)
    frame = re.compile(r"data:image/png;base64,((?:[A-Za-z0-9+/=]|\\\n)+)")
    compact = compact_html(html_text)
    assert len(compact) < 0.7 * len(html_text)
    originals = [base64.b64decode(m.replace("\\\n", "")) for m in frame.findall(html_text)]
    compacts = [base64.b64decode(m) for m in frame.findall(compact)]
    assert len(originals) == len(compacts) == 3
    for before, after in zip(originals, compacts):
        assert np.abs(_pixels(before) - _pixels(after)).mean() < 1.0
    # The player's script is untouched outside the frames' data.
    assert frame.sub("", compact) == frame.sub("", html_text)


def test_every_chapter_opens_with_its_idea_and_tucks_its_set_up_away():
    """A chapter starts with its title and text; its first code cell is the set-up
    (imports and helpers: no output) and is tagged hide-input, so the book shows it as
    a toggle and the student notebook collapses it."""
    import nbformat

    for md in book.chapter_sources():
        nb = nbformat.read(md.with_suffix(".ipynb"), as_version=4)
        assert nb.cells[0].cell_type == "markdown" and re.search(r"^# ", nb.cells[0].source, re.M), (
            f"{md.name} does not open with its title")
        first_code = next(cell for cell in nb.cells if cell.cell_type == "code")
        assert "hide-input" in first_code.metadata.get("tags", []), (
            f"{md.name}: its first code cell (the set-up) is not tagged hide-input")
        assert not first_code.outputs, (
            f"{md.name}: its first code cell shows output; keep the set-up (imports, helpers) "
            f"in a cell of its own")
