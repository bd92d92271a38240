"""A chapter cell imports only what the student edition holds, or is tagged
``reference-output-only`` (:mod:`grader.release.chapter_imports`).

- ``changes_sys_path`` tells a change of ``sys.path`` from a reading of it;
- ``grader release`` of a repository whose one chapter holds a cell that imports the
  instructor's ``bench/`` script through ``sys.path``, or a module of ``solutions`` that
  ``exercises`` does not mirror, stops with a message naming the chapter, the cell and
  the module, and writes nothing;
- tagged, the same cell becomes a ``%%reference_output`` cell naming what it needs,
  its stored output kept with its digest, and a later cell that reads a name only
  that cell binds is refused.

The repository of these releases is a temporary folder linking to this one's
``exercises``, ``grader``, ``solutions`` and ``tools`` with a synthetic chapter (about 1 s).
"""
from __future__ import annotations

from pathlib import Path

import nbformat
import pytest

from grader.release.book import MystToMarkdown, is_shown_only, student_notebook
from grader.release.chapter_imports import (REFERENCE_OUTPUT_TAG, SYS_PATH, ChapterImportError, StudentModules,
                                           changes_sys_path)
from grader.release.edition import ReleaseError, build_release
from grader.student.notebook import METADATA_KEY, outputs_digest

REPO = Path(__file__).resolve().parent.parent
STEM = "99_synthetic"
BENCH_CELL = ("import sys\n"
              "sys.path.insert(0, '../../bench')\n"
              "from bench_secret import measure\n"
              "print(measure())")
TIMING = "numba tree: 0.48 ms per frame\n"


def chapter(code: str, tags: list[str] = ()) -> nbformat.NotebookNode:
    """An executed chapter: a title, a cell that imports the engine, ``code`` with a stored output."""
    cells = [nbformat.v4.new_markdown_cell("# A synthetic chapter"),
             nbformat.v4.new_code_cell("from solutions.broadphase.uniform_grid import UniformGrid"),
             nbformat.v4.new_code_cell(code, metadata={"tags": list(tags)},
                                       outputs=[nbformat.v4.new_output("stream", name="stdout", text=TIMING)])]
    for index, cell in enumerate(cells):
        cell["id"] = f"cell-{index:03d}"
    return nbformat.v4.new_notebook(cells=cells)


@pytest.fixture
def repository(tmp_path) -> Path:
    """A course repository with this one's code and no chapter yet."""
    root = tmp_path / "repo"
    (root / "book" / "chapters").mkdir(parents=True)
    for name in ("exercises", "grader", "solutions", "tools", "pyproject.toml"):
        (root / name).symlink_to(REPO / name)
    return root


@pytest.mark.parametrize("code", ["import sys\nsys.path.append('x')", "import sys\nsys.path[:0] = ['x']",
                                  "import sys\nsys.path = ['x'] + sys.path", "import sys\nsys.path += ['x']",
                                  "import site\nsite.addsitedir('x')", "def f():\n    import sys\n    sys.path.insert(0, 'x')"])
def test_a_change_of_sys_path_is_seen(code):
    assert changes_sys_path(code)


@pytest.mark.parametrize("code", ["import sys\nprint(sys.path)", "import sys\nfirst = sys.path[0]",
                                  "import os\nos.path.join('a', 'b')", "path = []\npath.insert(0, 'x')"])
def test_a_reading_of_sys_path_is_no_change(code):
    assert not changes_sys_path(code)


@pytest.mark.parametrize("code, module", [
    (BENCH_CELL, "bench_secret"),
    ("from solutions.broadphase.dynamic_tree_numba import NumbaTree", "exercises.broadphase.dynamic_tree_numba"),
    ("from grader.release.edition import build_release", "grader.release.edition"),
])
def test_release_refuses_a_cell_that_imports_what_the_student_edition_lacks(repository, tmp_path, code, module):
    nbformat.write(chapter(code), repository / "book" / "chapters" / f"{STEM}.ipynb")
    out = tmp_path / "out"
    with pytest.raises(ReleaseError) as raised:
        build_release(out, repo_root=repository)
    message = str(raised.value)
    assert f"{STEM}.ipynb, cell 2 (cell-002)" in message, message
    assert f"it imports {module}, which is neither" in message, message
    assert REFERENCE_OUTPUT_TAG in message
    assert ("changes sys.path" in message) == ("sys.path" in code), message
    assert not out.exists()


def test_a_tagged_cell_shows_its_stored_output_and_never_runs():
    modules = StudentModules({name: REPO / name for name in ("exercises", "grader", "tools")})
    student = student_notebook(chapter(BENCH_CELL, ["nbval-ignore-output", REFERENCE_OUTPUT_TAG]), STEM,
                               MystToMarkdown({}, f"{STEM}.ipynb"), modules)
    engine, tagged = [c for c in student.cells if c.cell_type == "code"][1:]
    assert engine.source.startswith(f"%%reference_fallback {STEM}:cell-001\n")
    first, _, body = tagged.source.partition("\n")
    assert first == f"%%reference_output {STEM}:cell-002 bench_secret,{SYS_PATH}" and is_shown_only(tagged.source)
    assert body == BENCH_CELL   # the code stays for the student to read
    assert tagged.outputs[0]["text"] == TIMING
    assert tagged.metadata[METADATA_KEY]["digest"] == outputs_digest(tagged.outputs)


def test_a_later_cell_may_not_read_what_only_a_tagged_cell_binds():
    modules = StudentModules({name: REPO / name for name in ("exercises", "grader", "tools")})
    nb = chapter(BENCH_CELL + "\nrow = measure()", [REFERENCE_OUTPUT_TAG])
    nb.cells.append(nbformat.v4.new_code_cell("print(row)"))
    nb.cells[-1]["id"] = "cell-003"
    with pytest.raises(ChapterImportError, match=r"cell 3 \(cell-003\): the cell reads row, which only "
                                                 r"99_synthetic.ipynb, cell 2 \(cell-002\) binds"):
        student_notebook(nb, STEM, MystToMarkdown({}, f"{STEM}.ipynb"), modules)
    nb.cells[-1].source = "row = 1\nprint(row)"   # bound again in a cell that runs: fine
    student_notebook(nb, STEM, MystToMarkdown({}, f"{STEM}.ipynb"), modules)
