"""The course book (book/, built by tools/book.py): chapters in sync, nbval, a strict
clean build, and the built pages as a browser shows them.

Slow-ish (about a minute): marked ``book`` (``pytest -m "not book"`` leaves them out)
and grouped so that ``pytest -n 2 --dist loadgroup`` builds the book once, on one worker.
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import time
from pathlib import Path

import pytest

from tools import book

pytestmark = [pytest.mark.book, pytest.mark.xdist_group("book")]


def test_every_ipynb_matches_its_md_and_is_executed():
    problems = book.check()
    assert not problems, "\n".join(problems)


def test_chapters_pass_strict_nbval():
    """A fresh run of each chapter .ipynb gives the stored outputs (nbval, not --nbval-lax);
    cells tagged nbval-ignore-output run but are not compared, and no cell writes to stderr
    (tools.nbval_stderr).  The suite's only run of the chapters: the build shows what it checked."""
    start = time.perf_counter()
    result = book.nbval(capture_output=True, text=True)
    print(f"nbval on {len(book.chapter_sources())} chapters: {time.perf_counter() - start:.1f} s")
    assert result.returncode == 0, result.stdout[-6000:] + result.stderr[-2000:]
    assert re.search(r"\d+ passed", result.stdout), result.stdout[-2000:]


@pytest.fixture(scope="module")
def built_html(tmp_path_factory) -> Path:
    """A clean build of the book with -W -n --keep-going; the HTML folder.  It shows the
    outputs stored in the chapters' .ipynb, which the nbval test compares with a fresh run
    (a second run of every chapter took about 100 s); a failing cell still fails a build
    (test_a_failing_cell_fails_the_build), as does stderr in a stored output."""
    out = tmp_path_factory.mktemp("book")
    start = time.perf_counter()
    index = book.build(out=out, stored_outputs=True)
    print(f"clean build: {time.perf_counter() - start:.1f} s")
    return index.parent


def test_clean_build_is_strict_and_offline(built_html):
    for md in book.chapter_sources():
        assert (built_html / "chapters" / f"{md.stem}.html").exists(), md.name
    assert (built_html / "conventions.html").exists()
    # MathJax comes from the copy vendored from npm, never from a CDN.
    assert (built_html / "mathjax" / "tex-mml-chtml.js").exists()
    for page in built_html.rglob("*.html"):
        text = page.read_text(encoding="utf-8")
        assert not re.search(r"https?://[^\"']*mathjax", text, re.IGNORECASE), f"{page.name} loads MathJax from the network"
    for md in book.chapter_sources()[:1]:
        text = (built_html / "chapters" / f"{md.stem}.html").read_text(encoding="utf-8")
        assert "/mathjax/tex-mml-chtml.js" in text, f"{md.stem}.html does not load the vendored MathJax"
    # Only one document per chapter: the .ipynb twins are excluded from Sphinx.
    assert not list(built_html.rglob("*.ipynb.html"))


def _chromium() -> str | None:
    """Chromium's path; installs Debian's package when missing and we may (root + apt)."""
    found = book.find_chromium()
    if found or os.geteuid() != 0 or shutil.which("apt-get") is None:
        return found
    for command in (["apt-get", "install", "-y", "-qq", "chromium"],
                    ["sh", "-c", "apt-get update -qq && apt-get install -y -qq chromium"]):
        if subprocess.run(command, capture_output=True, timeout=900).returncode == 0:
            break
    return book.find_chromium()


def test_pages_render_in_headless_chromium(built_html, tmp_path_factory):
    if _chromium() is None:
        pytest.skip("Chromium is not installed and could not be installed "
                    "(needs root and apt-get: apt-get install chromium)")
    start = time.perf_counter()
    chapter = book.chapter_page(built_html)
    for page in (built_html / "index.html", chapter):
        dom = book.dump_dom(page)
        problems = book.page_problems(dom)
        assert not problems, f"{page.name}: {problems}"
    png = book.screenshot(chapter, tmp_path_factory.mktemp("screenshots") / f"{chapter.stem}.png")
    assert png.stat().st_size > 10_000, f"{png} looks empty"
    print(f"screenshot of {chapter.name}: {png} ({time.perf_counter() - start:.1f} s in Chromium)")


def test_a_failing_cell_fails_the_build(tmp_path, capfd):
    """The strict settings hold: a chapter cell that raises stops the build."""
    source = tmp_path / "book"
    shutil.copytree(book.BOOK, source, ignore=shutil.ignore_patterns("_build", "_vendor", "*.ipynb"))
    (source / "_vendor").symlink_to(book.VENDOR)
    first = book.chapter_sources()[0]
    chapter = source / "chapters" / first.name
    chapter.write_text(chapter.read_text(encoding="utf-8")
                       + "\n```{code-cell} ipython3\nraise ZeroDivisionError('planted by the test')\n```\n",
                       encoding="utf-8")
    with pytest.raises(book.BookError, match="build failed"):
        book.build(source=source)
    assert "planted by the test" in "".join(capfd.readouterr())
