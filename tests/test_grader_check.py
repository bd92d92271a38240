"""``grader check`` and its pictures: what a student sees for passing, stub and wrong code.

The runs go through the real sandboxed worker on three packages: the reference
(``solutions/``), the generated stubs (``exercises/``) and a copy of the reference with
one bug (``collide_circle_circle`` returns the normal from B to A).
"""
from __future__ import annotations

import base64
import importlib
import itertools
import io
import json
import re
import shutil
import subprocess
import sys
import textwrap
import types
from pathlib import Path

import matplotlib.colors
import matplotlib.image
import numpy as np
import pytest

from grader.harness import figures as grader_figures
from grader.harness.outcome import Outcome, TestResult
from grader.harness.package import PackageNotFound, find_package
from grader.harness.results_model import SubmissionResults
from grader.harness.spec import TestSpec
from grader.reports.results import check_results
from grader.student.check import CheckError, check, main, select_tests
from grader.harness.figures import EXPECTED_COLOR, EXTRA_COLOR, GOT_COLOR, MISSED_COLOR, draw_figure, figure_png_base64, save_figure
from matplotlib.patches import Rectangle
from grader.harness.run import load_spec

check_module = importlib.import_module("grader.student.check")  # `grader.check` names the function
REPO = Path(__file__).resolve().parents[1]
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
PUBLIC_EXERCISES = ("momentum", "grid", "quadtree", "sat", "contacts", "impulse")


@pytest.fixture(scope="module")
def wrong_package(tmp_path_factory) -> Path:
    """A submission folder: the reference with the circle-circle normal flipped."""
    root = tmp_path_factory.mktemp("wrong")
    shutil.copytree(REPO / "solutions", root / "exercises", ignore=shutil.ignore_patterns("__pycache__"))
    module = root / "exercises" / "narrowphase" / "circle_circle.py"
    source = module.read_text()
    buggy = source.replace("return Contact(normal, reach - distance", "return Contact(-normal, reach - distance")
    assert buggy != source, "the reference changed: update the bug planted by this test"
    module.write_text(buggy)
    return root


def plant(path: Path, function: str, lines: str, old: str = "", new: str = "") -> None:
    """Put ``lines`` at the start of ``function``'s solution block in ``path`` (and
    replace ``old`` by ``new``)."""
    source = path.read_text()
    start = source.index("    ### BEGIN SOLUTION", source.index(f"def {function}("))
    changed = source[:start] + textwrap.indent(textwrap.dedent(lines), "    ") + source[start:]
    if old:
        assert old in changed, "the reference changed: update the bug planted by this test"
        changed = changed.replace(old, new)
    path.write_text(changed)


#: What the printing collide_circle_circle prints per call after its first line.
DEBUG_LINES = 50


@pytest.fixture(scope="module")
def printing_package(tmp_path_factory) -> Path:
    """The reference with debug prints: collide_circle_circle prints its case and 50
    lines and flips the normal; collide_circle_polygon prints its radius and raises on a
    radius above 0.6; clip_segment_to_half_plane prints and is right; aabbs_overlap
    raises on a box wider than 1.5 m."""
    root = tmp_path_factory.mktemp("printing")
    shutil.copytree(REPO / "solutions", root / "exercises", ignore=shutil.ignore_patterns("__pycache__"))
    narrowphase = root / "exercises" / "narrowphase"
    plant(narrowphase / "circle_circle.py", "collide_circle_circle", f"""\
        print(f"CASE {{a.center[0]:g}} {{a.center[1]:g}} {{a.radius:g}} {{b.center[0]:g}} {{b.center[1]:g}} {{b.radius:g}}")
        for step in range({DEBUG_LINES}):
            print("debug step", step)
        """, "return Contact(normal, reach - distance", "return Contact(-normal, reach - distance")
    plant(narrowphase / "circle_polygon.py", "collide_circle_polygon", """\
        print("radius", circle.radius)
        if circle.radius > 0.6:
            raise ValueError("a big circle")
        """)
    plant(narrowphase / "polygon_polygon.py", "clip_segment_to_half_plane", 'print("CLIP-DEBUG")\n')
    plant(narrowphase / "aabb_aabb.py", "aabbs_overlap", """\
        if a.max_corner[0] - a.min_corner[0] > 1.5:
            raise ValueError("too wide")
        """)
    return root


@pytest.fixture(scope="module")
def printing_report(printing_package):
    return check("contacts", package=printing_package, show=False)


def test_printed_output_is_capped_and_is_what_the_case_shown_printed(printing_report):
    from grader.harness.outcome import OUTPUT_LINES

    row = next(r for r in printing_report.rows if r.test.name == "contacts.circle_circle")
    assert row.outcome.status == "failed" and "a small case found by Hypothesis" in row.outcome.message
    # The output is the shrunk case's own: its first line names the circles the message shows.
    first, *rest = row.outcome.output.splitlines()
    numbers = first.split()[1:]
    circles = re.findall(r"Circle\(center=\(([-\d.e]+), ([-\d.e]+)\), radius=([-\d.e]+)\)", row.outcome.message)
    assert [float(v) for v in numbers] == [float(v) for circle in circles for v in circle], (first, row.outcome.message)
    # One case printed 1 + DEBUG_LINES lines: OUTPUT_LINES are shown, the rest counted.
    printed = first + "\n" + "".join(f"debug step {i}\n" for i in range(DEBUG_LINES))
    shown = "".join(printed.splitlines(keepends=True)[:OUTPUT_LINES])
    assert rest[:OUTPUT_LINES - 1] == shown.splitlines()[1:]
    assert rest[-1] == f"[... {len(printed) - len(shown)} more characters not shown]", rest[-3:]
    text = check_module.format_row(row)
    assert "your code printed:" in text and text.count("debug step") == OUTPUT_LINES - 1


def test_a_hypothesis_test_shows_what_its_failing_example_printed(printing_report):
    row = next(r for r in printing_report.rows if r.test.name == "contacts.centre_inside")
    assert row.outcome.status == "error" and "a big circle" in row.outcome.message
    # Every example printed a line; only the failing (shrunk) example's is kept.
    assert row.outcome.output.splitlines() == ["radius 0.61"], row.outcome.output
    assert "radius=0.61" in row.outcome.message  # the case that raised


def test_output_of_passing_tests_is_shown_on_request_only(printing_package, printing_report, capsys):
    row = next(r for r in printing_report.rows if r.test.name == "contacts.clip_segment")
    assert row.passed and row.outcome.output.startswith("CLIP-DEBUG")
    assert "CLIP-DEBUG" not in check_module.format_row(row) and "CLIP-DEBUG" not in printing_report.html()
    assert "CLIP-DEBUG" in check_module.format_row(row, show_output=True)
    arguments = ["contacts.clip_segment", "--package", str(printing_package)]
    assert main(arguments) == 0 and "CLIP-DEBUG" not in capsys.readouterr().out
    assert main(arguments + ["--show-output"]) == 0 and "your code printed:\n" in capsys.readouterr().out.replace(
        " " * 19, "")


def test_the_check_table_is_a_view_of_the_one_result_model(printing_report):
    """grader check's results are the grader's SubmissionResults: written as results.json and
    read back, they draw the same table (failing, raising and passing tests alike)."""
    data = json.loads(json.dumps(printing_report.results.to_json()))
    assert check_results(data) == [] and {t["extra_data"]["status"] for t in data["tests"]} >= {"failed", "error",
                                                                                                "passed"}
    again = check_module.CheckReport("contacts", printing_report.package, SubmissionResults.from_json(data))
    assert again.text(width=100) == printing_report.text(width=100)
    assert again.summary() == printing_report.summary() and again.score == printing_report.score


def test_a_random_case_that_raises_is_named_with_its_input(printing_package):
    report = check("sat.aabbs_overlap", package=printing_package, show=False)
    [row] = report.rows
    assert row.outcome.status == "error" and "too wide" in row.outcome.message
    named = re.search(r"on the case aabbs_overlap\(AABB\(min_corner=\(([-\d.e]+), [-\d.e]+\), "
                      r"max_corner=\(([-\d.e]+), [-\d.e]+\)\)", row.outcome.message)
    assert named, row.outcome.message
    assert float(named[2]) - float(named[1]) > 1.5, "the case named is not one that raises"


def png_pixels(data: bytes) -> np.ndarray:
    assert data.startswith(PNG_SIGNATURE)
    return matplotlib.image.imread(io.BytesIO(data), format="png")[..., :3]


def pixels_near(image: np.ndarray, color: str, tolerance: float = 0.08) -> int:
    """How many pixels are within ``tolerance`` (per channel, 0-1) of ``color``."""
    rgb = np.array([int(color[k:k + 2], 16) / 255 for k in (1, 3, 5)])
    return int(np.sum(np.all(np.abs(image - rgb) < tolerance, axis=-1)))


# Runs on the three packages -----------------------------------------------------------
def chapter_order() -> list[str]:
    """The exercises in the order the book's chapters check them (their ``check("...")`` cells)."""
    found: list[str] = []
    for chapter in sorted((REPO / "book" / "chapters").glob("[0-9][0-9]_*.md")):
        for exercise in re.findall(r'check\("(\w+)"\)', chapter.read_text(encoding="utf-8")):
            if exercise not in found:
                found.append(exercise)
    return found


def test_reference_passes_every_public_test_listed_in_chapter_order():
    shown = []  # in the order the shell command prints them, as each test finishes
    report = check_module.run_check(None, "solutions", progress=lambda result: shown.append(result.test.name))
    public = [t for t in load_spec() if t.public]
    assert sorted(r.test.name for r in report.rows) == sorted(t.name for t in public)
    order = chapter_order()
    assert len(order) >= 6 and order[:2] == ["grid", "quadtree"], order
    exercises = [name.split(".")[0] for name in shown]
    assert [name for name, _ in itertools.groupby(exercises)] == [e for e in order if e in exercises], exercises
    assert [r.test.name for r in report.rows] == shown
    assert report.passed, [(r.test.name, r.outcome.message) for r in report.rows if not r.passed]
    assert report.score == report.max_score == sum(t.points for t in public)
    assert "all 25 tests passed" in report.summary() or f"all {len(public)} tests passed" in report.summary()


def test_stubs_say_not_implemented_yet_and_show_no_traceback():
    report = check(package=REPO / "exercises", show=False)
    assert report.rows and {r.outcome.status for r in report.rows} == {"not_implemented"}
    assert report.score == 0 and not report.passed
    text, page = report.text(), report.html()
    for row in report.rows:
        block = check_module.format_row(row)
        assert "not implemented yet" in block and "TO DO" in block
        # The message names the stub that raised (which may be a method the tested
        # function calls, as Quadtree.insert for pairs_quadtree) and the file to write it in.
        stub = row.outcome.message.rsplit(": ", 1)[1].split(" in ")[0]
        assert f"write {stub}()" in block and "exercises/" in block
    for shown in (text, page):
        assert "Traceback" not in shown and 'File "' not in shown
    assert page.count("not implemented yet") >= len(report.rows)


def test_wrong_normal_is_explained_with_a_picture_in_a_shell(wrong_package, tmp_path, capsys):
    folder = tmp_path / "figures"
    status = main(["contacts", "--package", str(wrong_package), "--figures", str(folder)])
    out = capsys.readouterr().out
    assert status == 1
    rows = {m.group(2): m.group(1) for m in re.finditer(r"^(PASS|FAIL)\s.*\[(contacts\.\w+)\]$", out, re.M)}
    public = [t.name for t in load_spec() if t.public and t.exercise == "contacts"]
    assert rows == {name: "FAIL" if name == "contacts.circle_circle" else "PASS" for name in public}
    words = " ".join(out.split())  # messages are wrapped to the terminal's width
    # The failing batch is shown by a small case of its category, shrunk by Hypothesis.
    assert "the normal points from B to A: expected [0, 1] (from A to B), got [-0, -1]" in words
    printed = re.findall(r"picture of the failing case: (\S+)", out)
    assert printed == [str(folder / "contacts.circle_circle.png")]
    data = Path(printed[0]).read_bytes()
    assert len(data) > 0 and png_pixels(data).std() > 0.05
    # A systematic bug (every overlapping pair wrong) earns no partial credit.
    total = sum(t.points for t in load_spec() if t.public and t.exercise == "contacts")
    assert "Traceback" not in out and f"Score {total - 2:g}/{total:g} points" in out


def test_check_outside_a_notebook_prints_the_table_and_returns_an_html_report(wrong_package, tmp_path, capsys):
    report = check("contacts.circle_circle", package=wrong_package, figures=tmp_path)
    out = capsys.readouterr().out
    assert [r.outcome.status for r in report.rows] == ["failed"] and report.score < 2
    assert "FAIL" in out and str(tmp_path / "contacts.circle_circle.png") in out
    assert (tmp_path / "contacts.circle_circle.png").stat().st_size > 0
    page = report._repr_html_()
    assert "data:image/png;base64," in page and ">FAIL<" in page and re.search(r"[\d.]+ / 2", page)
    # The message is escaped, not interpreted: shape reprs keep their brackets.
    assert "Circle(center=(0, 0), radius=1)" in page
    encoded = re.search(r"data:image/png;base64,([A-Za-z0-9+/=]+)", page).group(1)
    assert png_pixels(base64.b64decode(encoded)).std() > 0.05


def test_check_in_a_notebook_displays_html_once(monkeypatch):
    shown = []
    ipython = types.ModuleType("IPython")
    display_module = types.ModuleType("IPython.display")
    ipython.get_ipython = lambda: types.SimpleNamespace(kernel=object())
    display_module.HTML = lambda text: ("HTML", text)
    display_module.display = shown.append
    ipython.display = display_module
    monkeypatch.setitem(sys.modules, "IPython", ipython)
    monkeypatch.setitem(sys.modules, "IPython.display", display_module)
    report = check("momentum", package="solutions")
    assert len(shown) == 1 and shown[0][0] == "HTML" and ">PASS<" in shown[0][1]
    assert report._repr_html_() is None  # already shown: the cell's Out is the one-line repr
    momentum = [t for t in load_spec() if t.public and t.exercise == "momentum"]
    total, count = sum(t.points for t in momentum), len(momentum)
    assert repr(report) == f"<CheckReport momentum: {total:g}/{total:g} points, {count}/{count} tests passed>"


def test_shell_command_exit_codes(wrong_package):
    def run(*args, cwd=REPO):
        return subprocess.run([sys.executable, "-m", "grader", "check", *args], cwd=cwd, capture_output=True,
                              text=True, timeout=120)

    passing = run("momentum", "--package", "solutions")
    assert passing.returncode == 0, passing.stderr
    count = len([t for t in load_spec() if t.public and t.exercise == "momentum"])
    assert f"all {count} tests passed" in passing.stdout
    stubs = run("momentum")  # default: exercises/ of the current folder
    assert stubs.returncode == 1 and stubs.stdout.count("TO DO") == count
    unknown = run("gird")
    assert unknown.returncode == 2 and unknown.stdout == ""
    assert "unknown exercise 'gird'" in unknown.stderr
    assert all(name in unknown.stderr for name in PUBLIC_EXERCISES)
    assert "Traceback" not in passing.stderr + stubs.stderr + unknown.stderr


def test_unknown_exercise_is_a_clear_error():
    with pytest.raises(CheckError, match=rf"unknown exercise 'sta': choose one of {', '.join(chapter_order())} "):
        check("sta", package="solutions", show=False)
    public_grid = [t for t in load_spec() if t.public and t.exercise == "grid"]
    assert len(public_grid) >= 3 and [t.name for t in select_tests("grid")] == [t.name for t in public_grid]
    assert [t.name for t in select_tests("sat.project_circle")] == ["sat.project_circle"]


def test_where_the_package_is_found(monkeypatch, tmp_path, wrong_package):
    monkeypatch.delenv(check_module.PACKAGE_VARIABLE, raising=False)
    monkeypatch.chdir(wrong_package)
    assert find_package() == wrong_package / "exercises"
    monkeypatch.chdir(wrong_package / "exercises" / "narrowphase")  # a parent folder holds exercises/
    assert find_package() == wrong_package / "exercises"
    assert find_package("solutions") == REPO / "solutions"  # relative to the repository root
    monkeypatch.setenv(check_module.PACKAGE_VARIABLE, str(REPO / "solutions"))
    assert find_package() == REPO / "solutions"
    assert find_package(wrong_package) == wrong_package / "exercises"  # the argument wins
    with pytest.raises(PackageNotFound, match="no folder"):
        find_package(tmp_path / "missing")
    (tmp_path / "empty").mkdir()
    with pytest.raises(PackageNotFound, match="no Python package"):
        find_package(tmp_path / "empty")


def test_not_implemented_message_names_the_file():
    stub = Outcome("not_implemented", message="broadphase.uniform_grid.pairs_grid_every_cell: not implemented yet")
    row = TestResult(TestSpec("t", "grid", "T", 1.0, "visible"), stub, 0.0)
    assert check_module.student_message(row) == (
        "not implemented yet: write pairs_grid_every_cell() in exercises/broadphase/uniform_grid.py "
        "(it still raises NotImplementedError)")


# Pictures --------------------------------------------------------------------------------------
CIRCLE_A = {"$shape": "Circle", "center": [0.0, 0.0], "radius": 1.0}
CONTACT_UP = {"$contact": True, "normal": [0.0, 1.0], "depth": 0.5, "points": [[0.0, 0.75]]}
CONTACT_DOWN = {"$contact": True, "normal": [0.0, -1.0], "depth": 0.5, "points": [[0.2, 0.75]]}
SHAPES_B = [
    {"$shape": "Circle", "center": [0.0, 1.5], "radius": 1.0},
    {"$shape": "AABB", "min_corner": [-1.0, 0.5], "max_corner": [1.0, 2.0]},
    {"$shape": "OBB", "center": [0.3, 1.4], "half_extents": [1.0, 0.5], "angle": 0.4},
    {"$shape": "ConvexPolygon", "vertices": [[-1.0, 0.5], [1.0, 0.5], [0.0, 2.0]]},
]


def image_of(figure: dict) -> np.ndarray:
    return png_pixels(base64.b64decode(figure_png_base64(figure)))


@pytest.mark.parametrize("shape_b", SHAPES_B, ids=lambda s: s["$shape"])
def test_shapes_figure_draws_both_shapes_and_both_normals(shape_b):
    figure = {"kind": "shapes", "title": "collide: a case", "shapes": [CIRCLE_A, shape_b],
              "expected": CONTACT_UP, "got": CONTACT_DOWN}
    fig = draw_figure(figure)
    ax = fig.axes[0]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("x (m)", "y (m)") and ax.get_aspect() == 1.0
    assert {t.get_text() for t in ax.texts} >= {"A", "B"}
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any(label.startswith("expected normal") for label in labels)
    assert any(label.startswith("returned normal") for label in labels)
    image = image_of(figure)
    assert image.std() > 0.05  # not blank
    assert pixels_near(image, EXPECTED_COLOR) > 100 and pixels_near(image, GOT_COLOR) > 100


def test_shapes_figure_without_a_returned_contact_says_so():
    figure = {"kind": "shapes", "title": "missed contact", "shapes": [CIRCLE_A, SHAPES_B[0]], "expected": CONTACT_UP}
    labels = [t.get_text() for t in draw_figure(figure).axes[0].get_legend().get_texts()]
    assert "returned: no contact (None or not a Contact)" in labels
    # A returned contact that is not finite is drawn without crashing.
    broken = dict(figure, got={"$contact": True, "normal": [float("nan"), 0.0], "depth": None, "points": [[1e308, 2]]})
    assert image_of(broken).std() > 0.05


def test_pairs_figure_highlights_missed_and_extra_pairs_on_the_grid(tmp_path):
    figure = {"kind": "pairs", "title": "pairs_grid_every_cell: touching", "cell_size": 1.0,
              "aabbs": [[0, 0, 1, 1], [1, 0, 2, 1], [2, 1, 3, 2], [4, 4, 5, 5], [2.2, 3.0, 2.8, 4.0]],
              "missed": [[0, 1]], "extra": [[2, 4]]}
    ax = draw_figure(figure).axes[0]
    assert ax.get_aspect() == 1.0 and "1 overlapping pair missed" in ax.get_title()
    labels = " ".join(t.get_text() for t in ax.get_legend().get_texts())
    assert "missed pair: (0, 1)" in labels and "extra pair (boxes apart): (2, 4)" in labels and "grid cells" in labels
    path = save_figure(figure, tmp_path / "pictures" / "pairs.png")
    data = path.read_bytes()
    assert path.stat().st_size > 0
    image = png_pixels(data)
    assert image.std() > 0.05
    assert pixels_near(image, MISSED_COLOR) > 100 and pixels_near(image, EXTRA_COLOR) > 100


def test_coincident_boxes_are_drawn_apart_and_labelled_together():
    figure = {"kind": "pairs", "title": "pairs_grid_every_cell: coincident boxes", "cell_size": 1.0,
              "aabbs": [[0, 0, 1, 1], [3, 3, 4, 4], [0, 0, 1, 1], [0, 0, 1, 1], [3, 3, 4, 4]],
              "missed": [[0, 2]], "extra": []}
    ax = draw_figure(figure).axes[0]
    grey = [p for p in ax.patches if isinstance(p, Rectangle) and p.get_edgecolor()[:3] == matplotlib.colors.to_rgb(
        grader_figures.BOX_COLOR)]
    corners = {(round(p.get_x(), 9), round(p.get_y(), 9), round(p.get_width(), 9)) for p in grey}
    assert len(grey) == 5 and len(corners) == 5            # five outlines, none on top of another
    texts = {t.get_text() for t in ax.texts}
    assert {"0=2=3", "1=4"} <= texts and not {"2", "3", "4"} & texts
    labels = " ".join(t.get_text() for t in ax.get_legend().get_texts())
    assert "coincident boxes (drawn nested): 0=2=3, 1=4" in labels and "missed pair: (0, 2)" in labels
    rings = [line for line in ax.lines if line.get_marker() == "o" and line.get_markersize() == 16]
    assert len(rings) == 1                                   # the pair (0, 2) has no line to draw
    assert pixels_near(image_of(figure), MISSED_COLOR) > 100


def test_coincident_shapes_draw_b_dashed():
    figure = {"kind": "shapes", "title": "collide: the same box twice", "shapes": [SHAPES_B[0], SHAPES_B[0]],
              "expected": CONTACT_UP}
    ax = draw_figure(figure).axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "A and B coincide (B dashed)" in labels
    assert sorted(p.get_linestyle() for p in ax.patches if not p.get_fill()) == ["-", "--"]
    apart = {"kind": "shapes", "title": "collide: a case", "shapes": [CIRCLE_A, SHAPES_B[0]], "expected": CONTACT_UP}
    assert "A and B coincide (B dashed)" not in [t.get_text() for t in draw_figure(apart).axes[0].get_legend().get_texts()]


def test_quadtree_figure_draws_the_root_bounds():
    figure = {"kind": "pairs", "title": "pairs_quadtree: straddling", "cell_size": 0.0, "bounds": [0, 0, 16, 16],
              "aabbs": [[7.5, 2, 8.5, 3], [7.0, 2.2, 7.6, 2.8], [1, 1, 2, 2]], "missed": [[0, 1]], "extra": []}
    ax = draw_figure(figure).axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "quadtree root" in labels and not any("grid cells" in label for label in labels)
    assert ax.get_xlim()[0] < 0 < 16 < ax.get_xlim()[1]
    assert image_of(figure).std() > 0.05


def test_unknown_figure_kind_is_refused():
    with pytest.raises(ValueError, match="no picture for figures of kind 'omitted'"):
        draw_figure({"kind": "omitted"})


def test_drawing_leaves_no_pyplot_figures_open():
    pyplot = pytest.importorskip("matplotlib.pyplot")
    before = len(pyplot.get_fignums())
    grader_figures.figure_png_base64({"kind": "shapes", "title": "t", "shapes": [CIRCLE_A, SHAPES_B[1]]})
    assert len(pyplot.get_fignums()) == before
