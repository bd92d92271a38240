"""Compact the images stored in the chapters' executed notebooks.

A chapter's ``.ipynb`` keeps every figure as a PNG and every ``to_jshtml`` animation as
an HTML player holding one base64 PNG per frame: 12.3 MB in all before this step, 7.2 MB
of it animation frames that nbval never compares (their cells are tagged
``nbval-ignore-output``; nbval skips ``image/png`` too).  Matplotlib writes 24-bit
RGBA; re-encoded with a palette of at most :data:`PALETTE_COLOURS` colours a figure
takes about a third of the bytes and looks the same (anti-aliased lines and alpha
blending need far fewer colours than that).  ``tools.book sync`` applies this to every
notebook it writes; the built book executes the ``.md`` afresh and is not affected.

``python -m tools.notebook_images [NN ...]`` compacts the stored notebooks in place
without executing them (all chapters, or those starting with NN).
"""
from __future__ import annotations

import base64
import io
import sys
from pathlib import Path

from grader.release.book import INLINE_IMAGE

#: Colours of the palette an image is re-encoded with (the most a palette PNG holds).
PALETTE_COLOURS = 256
PNG_DATA_URI = "data:image/png;base64,"


def palette_png(png: bytes) -> bytes:
    """``png`` re-encoded with at most :data:`PALETTE_COLOURS` colours, or ``png``
    itself when that is not smaller.  Opaque images are quantised by median cut, images
    with transparency by octree (the one Pillow method that keeps alpha)."""
    from PIL import Image  # deferred: Pillow is needed only when a notebook is written

    image = Image.open(io.BytesIO(png))
    image.load()
    if image.mode != "P":
        image = image.convert("RGBA")
    if image.mode == "RGBA" and image.getextrema()[3][0] == 255:
        image = image.convert("RGB")
    if image.mode == "RGB":
        paletted = image.quantize(PALETTE_COLOURS, method=Image.Quantize.MEDIANCUT)
    elif image.mode == "RGBA":
        paletted = image.quantize(PALETTE_COLOURS, method=Image.Quantize.FASTOCTREE)
    else:
        paletted = image
    out = io.BytesIO()
    paletted.save(out, format="PNG", optimize=True)
    smaller = out.getvalue()
    return smaller if len(smaller) < len(png) else png


def _compact_base64(text: str) -> str:
    return base64.b64encode(palette_png(base64.b64decode(text))).decode("ascii")


def compact_html(html_text: str) -> str:
    """``html_text`` with each inlined PNG (an animation frame) re-encoded by
    :func:`palette_png`, its base64 on one line."""
    def replace(match) -> str:
        if match.group(1) != PNG_DATA_URI:
            return match.group(0)
        return PNG_DATA_URI + _compact_base64(match.group(2).replace("\\\n", ""))
    return INLINE_IMAGE.sub(replace, html_text)


def compact_outputs(nb) -> None:
    """Re-encode in place every PNG the code cells of notebook ``nb`` show: ``image/png``
    outputs and the frames inlined in ``text/html`` outputs."""
    for cell in nb.cells:
        for output in cell.get("outputs", []) if cell.cell_type == "code" else []:
            data = output.get("data", {})
            if "image/png" in data:
                data["image/png"] = _compact_base64(data["image/png"])
            if "text/html" in data:
                value = data["text/html"]
                data["text/html"] = compact_html("".join(value) if isinstance(value, list) else value)


def compact_file(path: Path) -> tuple[int, int]:
    """Compact the stored notebook ``path`` in place; its sizes in bytes before and after."""
    import nbformat  # deferred: like tools.book, only the commands that write notebooks need it

    before = path.stat().st_size
    nb = nbformat.read(path, as_version=4)
    compact_outputs(nb)
    with open(path, "w", encoding="utf-8") as handle:
        nbformat.write(nb, handle)
    return before, path.stat().st_size


def main(argv: list[str] | None = None) -> int:
    from tools.book import ROOT, chapter_sources  # deferred: tools.book imports this module

    names = sys.argv[1:] if argv is None else argv
    total_before = total_after = 0
    for md in chapter_sources(names or None):
        path = md.with_suffix(".ipynb")
        before, after = compact_file(path)
        total_before += before
        total_after += after
        print(f"{path.relative_to(ROOT)}: {before / 1e6:.2f} MB -> {after / 1e6:.2f} MB")
    print(f"total: {total_before / 1e6:.2f} MB -> {total_after / 1e6:.2f} MB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
