"""The chapter notebooks of the student edition, as the student opens them in JupyterLab.

One release is built for the module (about 6 s).  Then:

- no markdown cell of a student notebook, and no reading page, shows a MyST role
  (``{name}`` then a backtick), a directive (a fence ```` ```{ ```` or ``:::{``) or a
  key that a chapter glues; the scan is shown to find each of them;
- each glued value a chapter's text quotes is there, as the chapter's executed run gave
  it and formatted as its role asks, in a paragraph that says it is the reference's;
- no cell imports myst-nb, and the student's packages include neither myst-nb nor
  Sphinx (``grader.student.notebook.glue`` stands in: it shows a value only when asked to);
- the reference outputs are stored once, in the notebook: the fallback of a cell finds
  them in the notebook as saved after a run (marked ``book``: about 30 s), and says so
  when a run of the student's own code was saved over them;
- the cells the book hides (each chapter's set-up cell, figures' drawing code) open
  collapsed in JupyterLab;
- Fig. 3.1 draws the student's grid once the grid exercise is written (marked ``book``);
- chapter 04 (the dynamic tree) runs to its end on a package filled with the reference (marked ``book``:
  about 20 s): its timing cell, tagged ``reference-output-only`` (it times the
  instructor's ``bench/`` script), does not run and shows the stored output under a
  line naming what it needs;
- the kernel that ``run.sh setup`` registers starts without ipykernel's warning about
  unencrypted TCP (a real ``ipykernel install``, started as Jupyter starts it).
"""
from __future__ import annotations

import ast
import json
import os
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from grader.release.book import HIDDEN_SOURCE_TAGS, SETUP_CELL_ID
from grader.release.edition import build_release

pytestmark = pytest.mark.xdist_group("release")

REPO = Path(__file__).resolve().parent.parent
CHAPTERS = REPO / "book" / "chapters"
ROLE = re.compile(r"\{[A-Za-z][\w:-]*\}`")
DIRECTIVE = re.compile(r"^\s*(?:`{3,}|:{3,})\{", re.M)
GLUE_CALL = re.compile(r"\bglue\(\s*[\"'](\w+)[\"']")
GLUE_ROLE = re.compile(r"\{glue(?::\w*)?\}`(?:[^`:]*::)?(\w+)(?::([^`]*))?`")
REFERENCE_NOTE = "come from the reference engine's run of this chapter"


@pytest.fixture(scope="module")
def release(tmp_path_factory):
    return build_release(tmp_path_factory.mktemp("release") / "out")


def _source(cell) -> str:
    return "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]


def _notebook(path: Path) -> dict:
    return json.loads(path.read_text(encoding="utf-8"))


def glue_keys() -> set[str]:
    """Every key a chapter glues (its code cells' ``glue("key", ...)`` calls)."""
    keys = set()
    for path in CHAPTERS.glob("*.ipynb"):
        for cell in _notebook(path)["cells"]:
            if cell["cell_type"] == "code":
                keys.update(GLUE_CALL.findall(_source(cell)))
    return keys


def unrendered(text: str, keys: set[str]) -> list[str]:
    """The MyST roles, directives and glue keys ``text`` shows as they are."""
    found = [m.group(0) for m in ROLE.finditer(text)] + [m.group(0).strip() for m in DIRECTIVE.finditer(text)]
    return found + sorted(key for key in keys if re.search(rf"\b{re.escape(key)}\b", text))


def test_no_student_page_shows_a_myst_role_a_directive_or_a_glue_key(release):
    keys = glue_keys()
    assert keys, "no chapter glues a value: the scan below would look for no key"
    # The scan finds each kind of leftover, in the words of the bug that made it.
    planted = ("After one sweep the bottom contact carries {glue:text}`seq_first_sweep_bottom:.2f` box\n"
               "```{admonition} Note\n:::{exercise}\n")
    assert unrendered(planted, {"seq_first_sweep_bottom"}) == [
        "{glue:text}`", "```{", ":::{", "seq_first_sweep_bottom"]
    problems = []
    book = release.student / "book"
    notebooks = sorted(book.glob("*.ipynb"))
    assert len(notebooks) == len(list(CHAPTERS.glob("*.ipynb")))
    for path in notebooks:
        for cell in _notebook(path)["cells"]:
            if cell["cell_type"] == "markdown":
                problems += [f"{path.name} {cell['id']}: {found}" for found in unrendered(_source(cell), keys)]
    for path in sorted(book.glob("*.md")):
        problems += [f"{path.name}: {found}" for found in unrendered(path.read_text(encoding="utf-8"), keys)]
    assert not problems, "\n".join(problems)


def _formatted(text: str, spec: str) -> str:
    """A glued text/plain as ``{glue:text}`key:spec``` shows it (myst-nb's rule: the
    literal's value, made int or float by the spec's type letter)."""
    try:
        value = ast.literal_eval(text)
    except (SyntaxError, ValueError):
        value = text
    if spec and spec[-1] in "bcdoxX":
        value = int(value)
    elif spec and spec[-1] in "eEfFgGn%":
        value = float(value)
    return format(value, spec) if spec else str(value)


def _quotes(paragraph: str, value: str) -> bool:
    """Whether ``paragraph`` quotes ``value`` as a number of its own (a glued 2 is not
    the 2 of "box2d-lite")."""
    return re.search(rf"(?<![\w.]){re.escape(value)}(?![\w])", paragraph) is not None


def test_glued_values_are_the_reference_runs_and_say_so(release):
    quoted = 0
    for path in sorted(CHAPTERS.glob("*.ipynb")):
        chapter = _notebook(path)
        values = {}
        for cell in chapter["cells"]:
            for output in cell.get("outputs", []):
                record = output.get("metadata", {}).get("scrapbook")
                if record:
                    values[record["name"]] = "".join(output["data"][record["mime_prefix"] + "text/plain"])
        student = {c["id"]: _source(c) for c in _notebook(release.student / "book" / path.name)["cells"]}
        for cell in chapter["cells"]:
            if cell["cell_type"] != "markdown":
                continue
            for key, spec in GLUE_ROLE.findall(_source(cell)):
                shown = _formatted(values[key], spec)
                assert shown in student[cell["id"]], (path.name, cell["id"], key, shown)
                quoted += 1
            # Each paragraph of the chapter that quotes glued values becomes a paragraph of
            # the student's that quotes them and ends with the note.
            paragraphs = student[cell["id"]].split("\n\n")
            for source_paragraph in re.split(r"\n[ \t]*\n", _source(cell)):
                shown = [_formatted(values[k], s) for k, s in GLUE_ROLE.findall(source_paragraph)]
                if shown:
                    assert any(REFERENCE_NOTE in p and all(_quotes(p, value) for value in shown)
                               for p in paragraphs), (path.name, cell["id"], shown)
    assert quoted >= len(glue_keys()) // 2, quoted


def test_student_notebooks_need_neither_myst_nb_nor_sphinx(release, monkeypatch):
    for path in sorted((release.student / "book").glob("*.ipynb")):
        for cell in _notebook(path)["cells"]:
            if cell["cell_type"] == "code":
                assert "myst_nb" not in _source(cell), (path.name, cell["id"])
                outputs = json.dumps(cell.get("outputs", []))
                assert "application/papermill.record" not in outputs, (path.name, cell["id"])
    dependencies = tomllib.loads((release.student / "pyproject.toml").read_text())["project"]["dependencies"]
    names = {re.split(r"[=<>!~ \[]", d, maxsplit=1)[0].lower().replace("_", "-") for d in dependencies}
    assert not names & {"myst-nb", "myst-parser", "sphinx", "jupyter-book"}, dependencies
    # The stand-in for myst-nb's glue: shows the value only when asked to.
    from grader.student import notebook

    shown = []
    monkeypatch.setattr("IPython.display.display", lambda value: shown.append(value))
    notebook.glue("quiet", 1.5, display=False)
    notebook.glue("loud", 2.5)
    assert shown == [2.5]


def test_animation_frames_are_whole_images(release):
    """The animations' frames, their base64 joined onto one line in the student edition:
    as many as the chapter's, each a PNG that decodes whole."""
    import base64
    import io

    from PIL import Image

    frame = re.compile(r'frames\[\d+\] = "data:image/png;base64,([^"]*)"')
    checked = 0
    for path in sorted(CHAPTERS.glob("*.ipynb")):
        def animations(nb: dict) -> list[str]:
            return ["".join(o["data"]["text/html"]) for c in nb["cells"] for o in c.get("outputs", [])
                    if "frames[0]" in "".join(o.get("data", {}).get("text/html", ""))]

        theirs = animations(_notebook(path))
        mine = animations(_notebook(release.student / "book" / path.name))
        starts = re.compile(r'frames\[\d+\] = "data:image/png;base64,')
        assert [len(frame.findall(a)) for a in mine] == [len(starts.findall(a)) for a in theirs]
        for animation in mine:
            for data in frame.findall(animation):
                assert "\\" not in data and "\n" not in data
                Image.open(io.BytesIO(base64.b64decode(data, validate=True))).load()
                checked += 1
    assert checked, "no animation frame found"


def test_cells_the_book_hides_open_collapsed_in_the_student_notebooks(release):
    """Each chapter's set-up cell (imports, helpers) and its figures' drawing code are
    tagged hide-input: a toggle in the book, a collapsed source in JupyterLab."""
    collapsed = 0
    for path in sorted((release.student / "book").glob("*.ipynb")):
        nb = _notebook(path)
        first_code = next(cell for cell in nb["cells"] if cell["cell_type"] == "code"
                          and cell["id"] != SETUP_CELL_ID)
        assert "hide-input" in first_code["metadata"].get("tags", []), f"{path.name}: set-up cell shown"
        for cell in nb["cells"]:
            if cell["cell_type"] != "code":
                continue
            hidden = any(tag in HIDDEN_SOURCE_TAGS for tag in cell["metadata"].get("tags", []))
            source_hidden = cell["metadata"].get("jupyter", {}).get("source_hidden", False)
            assert source_hidden == hidden, f"{path.name}, cell {cell['id']}"
            collapsed += source_hidden
    assert collapsed, "no collapsed cell in any student notebook"


# The fallback reads the notebook as saved -------------------------------------------------------------------
def _text(output) -> str:
    if output.get("output_type") == "stream":
        return "".join(output.get("text", ""))
    value = output.get("data", {}).get("text/plain", "")
    return "".join(value) if isinstance(value, list) else value


@pytest.mark.book
def test_the_fallback_finds_the_reference_in_the_notebook_as_saved(release, tmp_path, monkeypatch):
    import nbformat
    from nbclient import NotebookClient

    from grader.student.notebook import outputs_digest

    student = tmp_path / "course"
    shutil.copytree(release.student, student)
    path = student / "book" / "08_momentum.ipynb"
    shipped = {c.id: c.outputs for c in nbformat.read(path, as_version=4).cells if c.cell_type == "code"}
    monkeypatch.setenv("PYTHONPATH", str(student))
    monkeypatch.delenv("GRADER_CHECK_PACKAGE", raising=False)
    monkeypatch.delenv("COURSE_NOTEBOOKS", raising=False)

    def run_and_save() -> dict:
        """Run the chapter on the stubs and save it; {cell id: what its fallback said}."""
        nb = nbformat.read(path, as_version=4)
        NotebookClient(nb, kernel_name="collision-course", timeout=600,
                       resources={"metadata": {"path": str(path.parent)}}).execute()
        nbformat.write(nb, path)
        notices = {}
        for cell in nb.cells:
            texts = [_text(o) for o in cell.get("outputs", [])]
            if texts and texts[0].startswith("[reference output]"):
                notices[cell.id] = texts[0]
                if "the output below is the reference engine's" in texts[0]:
                    assert outputs_digest(cell.outputs[1:]) == outputs_digest(shipped[cell.id]), cell.id
        return notices

    first = run_and_save()
    assert first and all("the output below is the reference engine's" in n for n in first.values()), first
    # Run again from the saved notebook: the fallbacks find the reference outputs again.
    assert run_and_save() == first
    # A run of the student's own code saved over one cell's outputs: its fallback says so.
    nb = nbformat.read(path, as_version=4)
    mine = next(c for c in nb.cells if c.id in first and any(o.get("output_type") != "stream" or _text(o).strip()
                                                            for o in shipped[c.id]))
    mine.outputs = [nbformat.v4.new_output("stream", name="stdout", text="my own run\n")]
    nbformat.write(nb, path)
    again = run_and_save()
    assert "no longer in 08_momentum.ipynb" in again[mine.id], again[mine.id]
    assert {k: v for k, v in again.items() if k != mine.id} == {k: v for k, v in first.items() if k != mine.id}


@pytest.mark.book
def test_the_grid_figure_shows_the_students_grid_once_it_is_written(release, tmp_path, monkeypatch):
    """Fig. 3.1 needs the grid exercise only (not a later chapter's narrow phase): with
    the grid written and every other stub left, it draws the student's grid."""
    import nbformat
    from nbclient import NotebookClient

    student = tmp_path / "course"
    shutil.copytree(release.student, student)
    shutil.copy(REPO / "solutions/broadphase/uniform_grid.py", student / "exercises/broadphase/uniform_grid.py")
    monkeypatch.setenv("PYTHONPATH", str(student))
    monkeypatch.delenv("GRADER_CHECK_PACKAGE", raising=False)
    path = student / "book" / "03_grid_and_quadtree.ipynb"
    nb = nbformat.read(path, as_version=4)
    figure = next(i for i, c in enumerate(nb.cells)
                  if c.get("metadata", {}).get("mystnb", {}).get("figure", {}).get("name") == "fig-grid-scene")
    nb.cells = nb.cells[:figure + 1]
    NotebookClient(nb, kernel_name="collision-course", timeout=600,
                   resources={"metadata": {"path": str(path.parent)}}).execute()
    outputs = nb.cells[figure].outputs
    assert not any(_text(o).startswith("[reference output]") for o in outputs), [_text(o) for o in outputs]
    assert any("image/png" in o.get("data", {}) for o in outputs)


@pytest.mark.book
def test_dynamic_tree_chapter_runs_on_the_reference_and_only_shows_its_timing(release, tmp_path, monkeypatch):
    import nbformat
    from nbclient import NotebookClient

    student = tmp_path / "course"
    shutil.copytree(release.student, student)
    shutil.rmtree(student / "exercises")
    shutil.copytree(REPO / "solutions", student / "exercises", ignore=shutil.ignore_patterns("__pycache__"))
    monkeypatch.setenv("PYTHONPATH", str(student))
    monkeypatch.delenv("GRADER_CHECK_PACKAGE", raising=False)
    monkeypatch.delenv("COURSE_NOTEBOOKS", raising=False)
    path = student / "book" / "04_dynamic_aabb_tree.ipynb"
    nb = nbformat.read(path, as_version=4)
    shown = [c for c in nb.cells if c.cell_type == "code" and c.source.startswith("%%reference_output ")]
    assert [c.id for c in shown] == ["cell-013"], [c.id for c in shown]
    stored = shown[0].outputs
    assert "bench_dynamic_tree" in shown[0].source and stored
    nb.cells.append(nbformat.v4.new_code_cell(
        "import sys\nprint('RAN=' + str(['bench_dynamic_tree' in sys.modules, 'row' in globals(), "
        "any(p.endswith('bench') for p in sys.path)]))"))
    NotebookClient(nb, kernel_name="collision-course", timeout=600, allow_errors=False,
                   resources={"metadata": {"path": str(path.parent)}}).execute()   # raises on any cell's error
    cells = {c.id: c for c in nb.cells if c.cell_type == "code"}
    texts = [_text(o) for o in cells["cell-013"].outputs]
    assert texts[0].startswith("[reference output] this cell is not run here: it uses bench_dynamic_tree"), texts
    assert "the output below is the reference engine's" in texts[0], texts[0]
    assert texts[1:] == [_text(o) for o in stored]
    assert "RAN=[False, False, False]" in _text(nb.cells[-1].outputs[0])
    falling_back = [i for i, c in cells.items() if i != "cell-013"
                    and any(_text(o).startswith("[reference output]") for o in c.outputs)]
    assert not falling_back, falling_back   # the reference package: every other cell runs


# The kernel ------------------------------------------------------------------------------------------------------
def _kernel_stderr(spec_file: Path, tmp_path: Path) -> str:
    """Start the kernel of ``spec_file`` as Jupyter does, wait until it answers, stop it;
    what it wrote on stderr."""
    from jupyter_client import BlockingKernelClient
    from jupyter_client.connect import write_connection_file

    spec = json.loads(spec_file.read_text())
    connection, _ = write_connection_file(str(tmp_path / f"kernel-{len(list(tmp_path.iterdir()))}.json"))
    argv = [part.replace("{connection_file}", connection) for part in spec["argv"]]
    kernel = subprocess.Popen(argv, env={**os.environ, **spec.get("env", {})}, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True)
    try:
        client = BlockingKernelClient(connection_file=connection)
        client.load_connection_file()
        client.start_channels()
        client.wait_for_ready(timeout=60)
        client.shutdown()
        client.stop_channels()
        kernel.wait(timeout=30)
    finally:
        if kernel.poll() is None:
            kernel.kill()
    return kernel.stderr.read()


def test_the_students_kernel_starts_without_the_tcp_warning(release, tmp_path):
    run_sh = (release.student / "run.sh").read_text()
    assert re.search(r"ipykernel install [^\n]*--name \"\$KERNEL\"", run_sh)
    assert '-m grader.student.notebook quiet-kernel "$VENV/share/jupyter/kernels/$KERNEL/kernel.json"' in run_sh
    prefix = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "ipykernel", "install", "--prefix", str(prefix), "--name", "course"],
                   check=True, capture_output=True)
    spec_file = prefix / "share/jupyter/kernels/course/kernel.json"
    assert "without encryption" in _kernel_stderr(spec_file, tmp_path)   # ipykernel's own spec warns
    result = subprocess.run([sys.executable, "-m", "grader.student.notebook", "quiet-kernel", str(spec_file)],
                            cwd=release.student, env={**os.environ, "PYTHONPATH": str(release.student)},
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert _kernel_stderr(spec_file, tmp_path) == ""
    # A second run changes nothing; a missing file is an error that says which.
    before = spec_file.read_text()
    subprocess.run([sys.executable, "-m", "grader.student.notebook", "quiet-kernel", str(spec_file)], check=True,
                   cwd=release.student, env={**os.environ, "PYTHONPATH": str(release.student)})
    assert spec_file.read_text() == before
    result = subprocess.run([sys.executable, "-m", "grader.student.notebook", "quiet-kernel", str(tmp_path / "none.json")],
                            cwd=release.student, env={**os.environ, "PYTHONPATH": str(release.student)},
                            capture_output=True, text=True)
    assert result.returncode == 1 and "none.json" in result.stderr
