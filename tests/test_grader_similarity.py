"""``grader similarity``: copies are flagged, independent work and untouched stubs are not."""
from __future__ import annotations

import ast
import csv
import shutil
import subprocess
import sys
import zipfile
from itertools import combinations
from pathlib import Path

import pytest

from grader.batch import similarity as sim
from grader.samples.example_class import Replacement, replace_functions

REPO = Path(__file__).resolve().parent.parent
IGNORE = shutil.ignore_patterns("__pycache__", "*.pyc")

LOOP = Replacement("narrowphase.projection", "project_vertices", '''
    def project_vertices(vertices, axis):
        lo = float("inf")
        hi = float("-inf")
        for v in vertices:
            d = v[0] * axis[0] + v[1] * axis[1]
            if d < lo:
                lo = d
            if d > hi:
                hi = d
        return float(lo), float(hi)
    ''')
NUMPY = Replacement("narrowphase.projection", "project_vertices", '''
    def project_vertices(vertices, axis):
        dots = np.asarray(vertices, dtype=float) @ np.asarray(axis, dtype=float)
        return float(dots.min()), float(dots.max())
    ''')
#: Honest 1D collisions written from the formulas, not from the reference.
MOMENTUM = (
    Replacement("response.momentum_1d", "collision_1d", '''
        def collision_1d(m1, v1, m2, v2, restitution):
            if m1 == math.inf:
                return v1, v1 - restitution * (v2 - v1)
            if m2 == math.inf:
                return v2 - restitution * (v1 - v2), v2
            total = m1 + m2
            centre = (m1 * v1 + m2 * v2) / total
            return centre - restitution * m2 * (v1 - v2) / total, centre + restitution * m1 * (v1 - v2) / total
        '''),
    Replacement("response.momentum_1d", "perfectly_inelastic_1d", '''
        def perfectly_inelastic_1d(m1, v1, m2, v2):
            if math.isinf(m1):
                return float(v1)
            if math.isinf(m2):
                return float(v2)
            return (m1 * v1 + m2 * v2) / (m1 + m2)
        '''),
)


class Disguise(ast.NodeTransformer):
    """Rename every parameter and local variable of every function (a plagiarist's disguise)."""

    def visit_FunctionDef(self, node):
        names = {a.arg for a in [*node.args.posonlyargs, *node.args.args, *node.args.kwonlyargs]}
        names |= {n.id for n in ast.walk(node) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)}
        mapping = {name: f"my_{name[::-1]}_{i}" for i, name in enumerate(sorted(names)) if name != "self"}
        for child in ast.walk(node):
            if isinstance(child, ast.Name) and child.id in mapping:
                child.id = mapping[child.id]
            elif isinstance(child, ast.arg) and child.arg in mapping:
                child.arg = mapping[child.arg]
        return node


def package_copy(folder: Path, base: Path, replacements=()) -> Path:
    package = folder / "exercises"
    shutil.copytree(base, package, ignore=IGNORE)
    by_module: dict[str, list[Replacement]] = {}
    for replacement in replacements:
        by_module.setdefault(replacement.module, []).append(replacement)
    for module, group in by_module.items():
        path = package.joinpath(*module.split(".")).with_suffix(".py")
        path.write_text(replace_functions(path.read_text(), group, folder.name))
    return folder


def disguised_copy(folder: Path) -> Path:
    """The reference with every local renamed, reformatted by ast.unparse (comments gone),
    and blank lines and a comment added in every function."""
    package_copy(folder, REPO / "solutions")
    for path in (folder / "exercises").rglob("*.py"):
        tree = Disguise().visit(ast.parse(path.read_text()))
        text = ast.unparse(tree).replace("\n    return ", "\n\n    # my own work\n    return ")
        path.write_text(text + "\n")
    return folder


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    root = tmp_path_factory.mktemp("similarity")
    subs = root / "subs"
    paths = {
        "copy": package_copy(subs / "copy", REPO / "solutions"),
        "disguised": disguised_copy(subs / "disguised"),
        "loop": package_copy(subs / "loop", REPO / "exercises", [LOOP]),
        "numpy": package_copy(subs / "numpy", REPO / "exercises", [NUMPY, *MOMENTUM]),
        "stubs-a": package_copy(subs / "stubs-a", REPO / "exercises"),
        "stubs-b": package_copy(subs / "stubs-b", REPO / "exercises"),
    }
    zipped = subs / "zipped.zip"
    with zipfile.ZipFile(zipped, "w") as archive:
        for file in sorted((paths["disguised"] / "exercises").rglob("*.py")):
            archive.write(file, file.relative_to(paths["disguised"]).as_posix())
    paths["zipped"] = zipped
    broken = package_copy(subs / "broken", REPO / "solutions")
    (broken / "exercises" / "response" / "momentum_1d.py").write_text("def collision_1d(:\n")
    paths["broken"] = broken
    out = root / "out"
    flags = sim.find_similar(list(paths.values()), out)
    with open(out / sim.CSV_NAME, newline="") as handle:
        rows = {frozenset((r["a"], r["b"])): r for r in csv.DictReader(handle)}
    return {"paths": paths, "out": out, "flags": {frozenset((p.a.id, p.b.id)) for p in flags}, "rows": rows,
            "html": (out / sim.HTML_NAME).read_text()}


def pair(a: str, b: str) -> frozenset:
    return frozenset((a, b))


def test_a_copy_of_the_reference_is_flagged(report):
    assert pair("copy", "reference") in report["flags"]
    assert float(report["rows"][pair("copy", "reference")]["similarity"]) == pytest.approx(1.0)


def test_a_copy_with_renamed_variables_and_new_layout_is_flagged(report):
    for name in ("disguised", "zipped"):
        assert pair(name, "reference") in report["flags"], name
        assert float(report["rows"][pair(name, "reference")]["similarity"]) > 0.95
    assert pair("copy", "disguised") in report["flags"]


def test_independent_implementations_are_not_flagged(report):
    for name in ("loop", "numpy"):
        assert not any(name in flagged for flagged in report["flags"]), name
    assert int(report["rows"][pair("loop", "numpy")]["shared_fingerprints"]) == 0


def test_untouched_stubs_count_for_nothing(report):
    assert not any({"stubs-a", "stubs-b"} & flagged for flagged in report["flags"])
    row = report["rows"][pair("stubs-a", "stubs-b")]
    assert row["similarity"] == "0.0000" and row["a_fingerprints"] == "0" and row["flagged"] == "no"
    assert "No code of their own (untouched stubs)" in report["html"] and "stubs-a" in report["html"]


def test_every_pair_is_in_the_csv(report):
    names = [*report["paths"], "reference"]
    expected = {frozenset(p) for p in combinations(report["paths"], 2)} | {pair(n, "reference")
                                                                            for n in report["paths"]}
    assert set(report["rows"]) == expected
    assert len(names) == len(report["paths"]) + 1


def test_the_html_report_shows_flagged_pairs_side_by_side(report):
    page = report["html"]
    assert page.startswith("<!DOCTYPE html>") and "Similar submissions" in page
    assert "<mark>" in page and "narrowphase.projection.project_vertices" in page
    assert "copy and reference" in page or "reference and copy" in page
    assert "broken: response.momentum_1d: not compared (SyntaxError)" in page


def test_the_command_line(tmp_path, report):
    paths = report["paths"]
    completed = subprocess.run([sys.executable, "-m", "grader.cli", "similarity", str(paths["copy"]),
                                str(paths["loop"]), "--out", str(tmp_path / "out"), "--threshold", "0.9"],
                               cwd=REPO, capture_output=True, text=True, timeout=120)
    assert completed.returncode == 0, completed.stderr
    assert "1 pairs flagged" in completed.stdout and "copy  reference" in completed.stdout
    assert (tmp_path / "out" / sim.HTML_NAME).is_file() and (tmp_path / "out" / sim.CSV_NAME).is_file()
    bad = subprocess.run([sys.executable, "-m", "grader.cli", "similarity", str(tmp_path / "nothere"), "--out",
                          str(tmp_path / "x")], cwd=REPO, capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "nothere" in bad.stderr and "Traceback" not in bad.stderr


def test_winnowing_guarantee():
    tokens = [(f"t{i % 7}{i % 5}", i) for i in range(60)]
    prints = sim.winnow(tokens, k=5, window=4)
    shared_run = tokens[20:20 + 5 + 4 - 1]  # any run of k + w - 1 tokens shares a fingerprint
    assert set(sim.winnow(shared_run, k=5, window=4)) & set(prints)
    assert sim.winnow([], k=5, window=4) == {}


def test_a_symbolic_link_is_never_followed(tmp_path):
    secret = tmp_path / "secret.py"
    secret.write_text("def collision_1d(m1, v1, m2, v2, restitution):\n    return 'the instructor's secret'\n")
    linked = package_copy(tmp_path / "linked", REPO / "exercises")
    module = linked / "exercises" / "response" / "momentum_1d.py"
    module.unlink()
    module.symlink_to(secret)
    sim.find_similar([linked], tmp_path / "out")
    page = (tmp_path / "out" / sim.HTML_NAME).read_text()
    assert "response.momentum_1d: not compared (a symbolic link)" in page
    assert "the instructor" not in page


def test_a_copy_hidden_in_an_init_file_is_found(tmp_path):
    """Every exercise file is the untouched stub; the reference's polygon module sits in
    ``narrowphase/__init__.py``: the pair with the reference is flagged, and the report
    names the ``__init__`` functions."""
    hidden = package_copy(tmp_path / "hidden", REPO / "exercises")
    init = hidden / "exercises" / "narrowphase" / "__init__.py"
    copied = (REPO / "solutions" / "narrowphase" / "polygon_polygon.py").read_text()
    init.write_text(init.read_text() + "\n\n" + copied)
    flags = sim.find_similar([hidden], tmp_path / "out")
    assert [frozenset((p.a.id, p.b.id)) for p in flags] == [pair("hidden", "reference")]
    assert flags[0].a_in_b > 0.95
    assert "narrowphase.__init__.collide_polygon_polygon" in (tmp_path / "out" / sim.HTML_NAME).read_text()
