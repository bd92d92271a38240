"""The bundled example class: sample submissions with the classic bugs of the notes.

``grader example-class --out DIR`` writes one folder per sample, each holding an
``exercises`` package that ``grader grade`` accepts like a student's:

- ``reference/``: the reference engine (a copy of ``solutions/``), full marks;
- ``stubs/``: the generated student package (a copy of ``exercises/``), zero;
- ``bug-<name>/``: the reference with one or two functions rewritten the way a student
  would, with one classic bug of the course notes (errata 5, 7-11, 22).

A buggy sample is data, not a committed package: the reference source plus the buggy
functions below.  The builder finds each function by its qualified name with
:mod:`ast` and swaps its source lines for the buggy text, keeping the original
docstring as a student's file would.  Each sample names the exact set of tests its bug
must fail (``expected_failures``, each justified in a comment); the test suite grades
every sample and checks that it loses the points of those tests and of no others.
"""
from __future__ import annotations

import argparse
import ast
import shutil
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent
SOLUTIONS_DIR = REPO_ROOT / "solutions"
EXERCISES_DIR = REPO_ROOT / "exercises"
PACKAGE = "exercises"
#: Written into every sample folder: what the sample is.  Its presence also marks a
#: folder as built here, so that rebuilding may replace it.
ABOUT_FILE = "SAMPLE.md"
REFERENCE_SAMPLE = "reference"
STUBS_SAMPLE = "stubs"


class ExampleClassError(ValueError):
    """A buggy sample cannot be built; the message names the sample, module and function."""


@dataclass(frozen=True)
class Replacement:
    """One function of the reference swapped for a student's version.

    Attributes
    ----------
    module : str
        Module path inside the package, dotted: ``"narrowphase.projection"``.
    qualname : str
        The function's qualified name: ``"project_vertices"``, ``"Quadtree.split"``.
    source : str
        The student's function, a complete ``def`` (any indentation).  Without a
        docstring, the original docstring is kept.
    imports : tuple of str
        Import lines the student added at the top of the module.
    """

    module: str
    qualname: str
    source: str
    imports: tuple[str, ...] = ()


@dataclass(frozen=True)
class BuggySample:
    """A sample submission: the reference with one classic bug.

    Attributes
    ----------
    name : str
        Folder ``bug-<name>``.
    mistake : str
        What the student did wrong, in one sentence.
    erratum : int
        Number of the erratum of the course notes (COURSE.md) behind the bug.
    replacements : tuple of Replacement
        The rewritten functions.
    expected_failures : frozenset of str
        Exactly the tests this bug fails; every other test passes.
    status : str
        Outcome status of those tests (``"failed"``: wrong answers, no exception).
    """

    name: str
    mistake: str
    erratum: int
    replacements: tuple[Replacement, ...]
    expected_failures: frozenset[str]
    status: str = "failed"

    @property
    def folder_name(self) -> str:
        return f"bug-{self.name}"


# --------------------------------------------------------------------------- samples

FLT_MIN = BuggySample(
    name="flt-min",
    mistake="project_vertices starts the running maximum at FLT_MIN (sys.float_info.min), the smallest "
            "positive float, instead of -infinity, so an interval lying left of the origin ends at 0.",
    erratum=7,
    replacements=(Replacement("narrowphase.projection", "project_vertices", '''
        def project_vertices(vertices, axis) -> tuple[float, float]:
            lowest = sys.float_info.max     # FLT_MAX
            highest = sys.float_info.min    # FLT_MIN, as in the notes
            for vertex in np.asarray(vertices, dtype=float).reshape(-1, 2):
                along = float(vertex[0] * axis[0] + vertex[1] * axis[1])
                if along < lowest:
                    lowest = along
                if along > highest:
                    highest = along
            return lowest, highest
        ''', imports=("import sys",)),),
    expected_failures=frozenset({
        # Half of its polygons lie where every projection is negative.
        "sat.project_vertices",
        # Boxes at x = -5 and -2: both intervals stretch to 0 and overlap (erratum 7).
        "sat.obb_negative_coordinates",
        # 250 random pairs around the origin: some are separated only on an axis where
        # both shapes project to negative values.
        "sat.polygons_overlap.random",
        # obbs_overlap projects both boxes with project_vertices; its cases include
        # boxes left of the origin.
        "sat.obbs_overlap.random",
        # circle_polygon_overlap projects the box with project_vertices: the box's
        # interval grows to 0 and meets circles it does not touch.
        "sat.circle_polygon.random",
    }),
)

NO_RESET = BuggySample(
    name="no-reset",
    mistake="polygons_overlap sets the min/max of both shapes once, before the loop over the axes, so every "
            "axis compares the union of the intervals of all axes so far.",
    erratum=8,
    replacements=(Replacement("narrowphase.polygon_polygon", "polygons_overlap", '''
        def polygons_overlap(a: AABB | OBB | ConvexPolygon, b: AABB | OBB | ConvexPolygon) -> bool:
            vertices_a = polygon_vertices(a)
            vertices_b = polygon_vertices(b)
            min_a, max_a = np.inf, -np.inf
            min_b, max_b = np.inf, -np.inf
            for axis in [*separating_axis_candidates(a), *separating_axis_candidates(b)]:
                for vertex in vertices_a:
                    along = float(vertex @ axis)
                    min_a = min(min_a, along)
                    max_a = max(max_a, along)
                for vertex in vertices_b:
                    along = float(vertex @ axis)
                    min_b = min(min_b, along)
                    max_b = max(max_b, along)
                if max_a < min_b or max_b < min_a:
                    return False
            return True
        '''),),
    expected_failures=frozenset({
        # The notes' 8 259 wrong pairs out of 20 000: random pairs apart on a later axis
        # look overlapping because the earlier axes' intervals leak in.
        "sat.polygons_overlap.random",
        # Its third pair is apart along y only; y is tested after x, whose interval
        # [-4.5, -3.5] is added to both y intervals ([-5, -3] and [-2, 0]).
        "sat.obb_negative_coordinates",
    }),
)

ABS_PROJECTION = BuggySample(
    name="abs-projection",
    mistake="circle_polygon_overlap projects the circle's centre with abs(Dot(c, axis)), folding it onto the "
            "positive side of the origin.",
    erratum=10,
    replacements=(Replacement("narrowphase.circle_polygon", "circle_polygon_overlap", '''
        def circle_polygon_overlap(circle: Circle, polygon: Polygonal) -> bool:
            vertices = polygon_vertices(polygon)
            axes = list(separating_axis_candidates(polygon))
            offsets = vertices - circle.center
            nearest_vertex = vertices[int(np.argmin(np.einsum("kd,kd->k", offsets, offsets)))]
            vertex_axis = normalize(nearest_vertex - circle.center)
            if vertex_axis is not None:
                axes.append(vertex_axis)
            for axis in axes:
                centre = abs(float(np.dot(circle.center, axis)))
                polygon_min, polygon_max = project_vertices(vertices, axis)
                if centre + circle.radius < polygon_min or centre - circle.radius > polygon_max:
                    return False
            return True
        '''),),
    expected_failures=frozenset({
        # Box x in [8, 12] against a circle at (-10, 0): folded to +10, it overlaps (erratum 10).
        "sat.circle_polygon.opposite_sides",
        # Random circles around the origin: any centre with a negative projection is
        # mirrored, which turns some separated pairs into overlapping ones and back.
        "sat.circle_polygon.random",
    }),
)

DIAMETER = BuggySample(
    name="diameter",
    mistake="The circle is projected as centre +- diameter, and two circles are said to meet when their "
            "centres are closer than the sum of the diameters.",
    erratum=9,
    replacements=(
        Replacement("narrowphase.projection", "project_circle", '''
            def project_circle(center, radius: float, axis) -> tuple[float, float]:
                along = float(center[0]) * float(axis[0]) + float(center[1]) * float(axis[1])
                diameter = 2.0 * radius
                return along - diameter, along + diameter
            '''),
        Replacement("narrowphase.circle_circle", "circles_overlap", '''
            def circles_overlap(a: Circle, b: Circle) -> bool:
                dx = float(b.center[0] - a.center[0])
                dy = float(b.center[1] - a.center[1])
                reach = 2.0 * a.radius + 2.0 * b.radius
                return dx * dx + dy * dy <= reach * reach
            '''),
    ),
    expected_failures=frozenset({
        # The interval is twice too wide (erratum 9).
        "sat.project_circle",
        # Circles 2-30 % of a radius outside a box's corner are reported as overlapping.
        "sat.circle_polygon.random",
        # Circles of radius 1 at distance 2.5 are said to overlap.
        "sat.circles_overlap",
        # Not failed: sat.circle_polygon.opposite_sides (its gaps exceed a diameter) and
        # the contact tests (collide_* compute the depth with the radius themselves).
    }),
)

UNNORMALISED_AXIS = BuggySample(
    name="unnormalised-axis",
    mistake="circle_polygon_overlap uses the centre-to-nearest-vertex axis without normalising it, so the "
            "centre's projection is scaled by the axis length but the radius is not.",
    erratum=11,
    replacements=(Replacement("narrowphase.circle_polygon", "circle_polygon_overlap", '''
        def circle_polygon_overlap(circle: Circle, polygon: Polygonal) -> bool:
            vertices = polygon_vertices(polygon)
            axes = list(separating_axis_candidates(polygon))
            offsets = vertices - circle.center
            nearest_vertex = vertices[int(np.argmin(np.einsum("kd,kd->k", offsets, offsets)))]
            axes.append(nearest_vertex - circle.center)
            for axis in axes:
                circle_interval = project_circle(circle.center, circle.radius, axis)
                if not intervals_overlap(circle_interval, project_vertices(vertices, axis)):
                    return False
            return True
        '''),),
    expected_failures=frozenset({
        # Its circles just outside a corner are separated by the vertex axis only; on the
        # unnormalised axis the radius is too short or too long compared with the gap.
        "sat.circle_polygon.random",
        # Not failed: sat.circle_polygon.opposite_sides, where a box normal separates.
    }),
)

SEPARATE_IMPULSES = BuggySample(
    name="separate-impulses",
    mistake="resolve_collision computes one impulse for A with A's mass and inertia only, then 'repeats the "
            "computation for B' with B's terms only, instead of one impulse with r = r_A + r_B.",
    erratum=22,
    replacements=(Replacement("response.impulse", "resolve_collision", '''
        def resolve_collision(body_a: Body, body_b: Body, contact: Contact,
                              restitution: float | None = None,
                              friction: float | None = None) -> tuple[np.ndarray, np.ndarray]:
            e = body_a.restitution * body_b.restitution if restitution is None else restitution
            mu = body_a.friction * body_b.friction if friction is None else friction
            n = np.asarray(contact.normal, dtype=float)
            tangent = np.array([n[1], -n[0]])
            points = contact.points
            normal_impulses = np.zeros(len(points))
            tangent_impulses = np.zeros(len(points))
            for i, point in enumerate(points):
                v_n = relative_normal_velocity(body_a, body_b, point, n)
                if v_n >= 0.0:
                    continue
                # The impulse for A as if B could not move, then the same for B.
                for body, sign in ((body_a, -1.0), (body_b, 1.0)):
                    if body.is_static:
                        continue
                    rn = float(cross(point - body.position, n))
                    j = -(1.0 + e) * v_n / (body.inverse_mass + body.inverse_inertia * rn * rn)
                    body.velocity = body.velocity + sign * body.inverse_mass * j * n
                    body.angular_velocity += sign * body.inverse_inertia * rn * j
                    normal_impulses[i] = j
            for i, point in enumerate(points):
                k_t = effective_mass_inverse(body_a, body_b, point, tangent)
                if normal_impulses[i] <= 0.0 or mu == 0.0 or k_t == 0.0:
                    continue
                v_t = relative_normal_velocity(body_a, body_b, point, tangent)
                limit = mu * normal_impulses[i]
                tangent_impulses[i] = float(np.clip(-v_t / k_t, -limit, limit))
                apply_impulse(body_a, body_b, point, tangent_impulses[i] * tangent)
            return normal_impulses, tangent_impulses
        '''),),
    expected_failures=frozenset({
        # Its 12 pairs of dynamic bodies leave with velocities unlike the reference's.
        "impulse.resolve_collision",
        # Two different impulses: momentum is not conserved, energy grows (erratum 22).
        "impulse.resolve_conserves_momentum",
        # Ball-ball contacts of the scene go wrong (ball-wall ones are right: a static
        # body adds nothing to r), so the balls end far from the reference.
        "impulse.scene",
        # Not failed: the building blocks it calls (magnitude, apply_impulse...) are the
        # reference's.
    }),
)

GRID_OWN_CELL = BuggySample(
    name="grid-own-cell",
    mistake="pairs_grid_center_cell stores each body in the cell of its centre and then tests it only "
            "against the bodies of that same cell, never the neighbouring cells.",
    erratum=5,
    replacements=(Replacement("broadphase.uniform_grid", "pairs_grid_center_cell", '''
        def pairs_grid_center_cell(aabbs, cell_size: float) -> set[tuple[int, int]]:
            boxes = np.asarray(aabbs, dtype=float).tolist()
            bodies_in_cell = defaultdict(list)
            for i, box in enumerate(boxes):
                centre_x = (box[MIN_X] + box[MAX_X]) / 2
                centre_y = (box[MIN_Y] + box[MAX_Y]) / 2
                bodies_in_cell[cell_index(centre_x, centre_y, cell_size)].append(i)
            pairs = set()
            for members in bodies_in_cell.values():
                for position, i in enumerate(members):
                    for j in members[position + 1:]:
                        if aabbs_overlap(boxes[i], boxes[j]):
                            pairs.add((i, j))
            return pairs
        '''),),
    expected_failures=frozenset({
        # Every centre-cell scene has overlapping boxes whose centres are in adjacent
        # cells (erratum 5).
        "grid.center_cell.random",
        "grid.center_cell.large_bodies",
        "grid.center_cell.clustered",
        # Not failed: the every-cell tests and grid.speed (pairs_grid_every_cell is the
        # reference's).
    }),
)

QUADTREE_DROPS_STRADDLING = BuggySample(
    name="quadtree-drops-straddling",
    mistake="Quadtree.split moves every body that fits in a quarter down and then empties the node, so "
            "bodies lying across a splitting line are lost instead of staying at the inner node.",
    erratum=5,
    replacements=(Replacement("broadphase.quadtree", "Quadtree.split", '''
        def split(self, leaf: QuadtreeNode) -> None:
            to_split = [leaf]
            while to_split:
                node = to_split.pop()
                node.children = [QuadtreeNode(bounds, node.depth + 1) for bounds in node.quarter_bounds()]
                for index in node.bodies:
                    child = self.child_holding(node, self.boxes[index])
                    if child is not None:
                        child.bodies.append(index)
                node.bodies = []   # the bodies now live in the quarters
                to_split.extend(child for child in node.children if self.stopping_rule(child) is None)
        '''),),
    expected_failures=frozenset({
        # Bodies across the root's and the quarters' lines overlap smaller ones; those
        # present when their node splits vanish with their pairs.
        "quadtree.straddling",
        # Random scenes always have bodies on the root's lines when it splits.
        "quadtree.random",
        # The 40 identical boxes straddle a splitting line at depth 4: the ones in the
        # node when it splits are lost.
        "quadtree.many_at_one_point",
        # The root splits while holding the inside bodies; those across its lines are lost.
        "quadtree.outside_root",
    }),
)

#: Every buggy sample, in the order of the errata.
BUGGY_SAMPLES: tuple[BuggySample, ...] = (GRID_OWN_CELL, QUADTREE_DROPS_STRADDLING, FLT_MIN, NO_RESET, DIAMETER,
                                          ABS_PROJECTION, UNNORMALISED_AXIS, SEPARATE_IMPULSES)


# --------------------------------------------------------------------------- building

def find_function(tree: ast.Module, qualname: str) -> ast.FunctionDef | ast.AsyncFunctionDef | None:
    """The function or method called ``qualname`` ("f", "Class.method") in ``tree``, or None.

    Examples
    --------
    >>> tree = ast.parse("class A:\\n    def f(self):\\n        pass\\n")
    >>> find_function(tree, "A.f").lineno
    2
    """
    scope: list[ast.stmt] = tree.body
    *outer, last = qualname.split(".")
    for name in outer:
        classes = [n for n in scope if isinstance(n, ast.ClassDef) and n.name == name]
        if not classes:
            return None
        scope = classes[-1].body
    functions = [n for n in scope if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)) and n.name == last]
    return functions[-1] if functions else None


def docstring_lines(lines: list[str], function: ast.FunctionDef) -> list[str] | None:
    """The source lines of ``function``'s docstring, or None if it has none."""
    if ast.get_docstring(function, clean=False) is None:
        return None
    node = function.body[0]
    return lines[node.lineno - 1:node.end_lineno]


def parameter_names(function: ast.FunctionDef) -> list[str]:
    arguments = function.args
    names = [a.arg for a in (*arguments.posonlyargs, *arguments.args, *arguments.kwonlyargs)]
    names += [f"*{a.arg}" for a in (arguments.vararg, arguments.kwarg) if a is not None]
    return names


def student_function(original_lines: list[str], original: ast.FunctionDef, replacement: Replacement,
                     where: str) -> list[str]:
    """The replacement's lines, indented like ``original``, with its docstring kept."""
    source = textwrap.dedent(replacement.source).strip("\n") + "\n"
    try:
        parsed = ast.parse(source)
    except SyntaxError as exc:
        raise ExampleClassError(f"{where}: the buggy source does not parse: {exc}") from None
    name = replacement.qualname.split(".")[-1]
    if len(parsed.body) != 1 or not isinstance(parsed.body[0], (ast.FunctionDef, ast.AsyncFunctionDef)) \
            or parsed.body[0].name != name:
        raise ExampleClassError(f"{where}: the buggy source must be exactly one function called {name!r}")
    new = parsed.body[0]
    if parameter_names(new) != parameter_names(original):
        raise ExampleClassError(f"{where}: the buggy function takes {parameter_names(new)}, the original "
                                f"{parameter_names(original)}; a student keeps the given signature")
    lines = source.splitlines(keepends=True)
    kept_doc = docstring_lines(original_lines, original)
    if kept_doc is not None and ast.get_docstring(new, clean=False) is None:
        if new.body[0].lineno == new.lineno:
            raise ExampleClassError(f"{where}: write the buggy function's body on the lines below its `def`")
        # The original docstring, moved from the original body's indentation to the new one's.
        old_indent, new_indent = original.body[0].col_offset, new.body[0].col_offset
        moved = []
        for line in kept_doc:
            text = line[old_indent:] if line[:old_indent].strip() == "" else line.lstrip()
            moved.append(" " * new_indent + text if text.strip() else "\n")
        first_body_line = new.body[0].lineno - 1
        lines = lines[:first_body_line] + moved + lines[first_body_line:]
    indent = " " * original.col_offset
    return [indent + line if line.strip() else line for line in lines]


def replace_functions(source: str, replacements: list[Replacement], where: str) -> str:
    """``source`` with each replacement's function swapped for its buggy text.

    Raises
    ------
    ExampleClassError
        When a function is not found, a buggy text does not parse, or the result does
        not parse or lacks the function.
    """
    lines = source.splitlines(keepends=True)
    tree = ast.parse(source)
    located = []
    for replacement in replacements:
        here = f"{where}, {replacement.qualname}"
        function = find_function(tree, replacement.qualname)
        if function is None:
            raise ExampleClassError(f"{here}: no function {replacement.qualname!r} in module {replacement.module!r}")
        first = min([function.lineno, *(d.lineno for d in function.decorator_list)])
        last = function.end_lineno
        # Comments right after the last statement, indented as the body, belong to it
        # (the "### END SOLUTION" marker).
        while last < len(lines) and lines[last].lstrip().startswith("#") \
                and len(lines[last]) - len(lines[last].lstrip()) > function.col_offset:
            last += 1
        located.append((first, last, function, replacement, here))
    located.sort(key=lambda item: item[0], reverse=True)  # bottom up: earlier line numbers stay valid
    for first, last, function, replacement, here in located:
        lines[first - 1:last] = student_function(lines, function, replacement, here)

    imports = [line for r in replacements for line in r.imports]
    if imports:
        tree = ast.parse("".join(lines))
        top_imports = [n for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))]
        after = top_imports[-1].end_lineno if top_imports else 0
        present = {line.strip() for line in lines}
        lines[after:after] = [line + "\n" for line in dict.fromkeys(imports) if line not in present]

    result = "".join(lines)
    try:
        tree = ast.parse(result)
    except SyntaxError as exc:
        raise ExampleClassError(f"{where}: the module with the buggy functions does not parse: {exc}") from None
    for replacement in replacements:
        if find_function(tree, replacement.qualname) is None:
            raise ExampleClassError(f"{where}: {replacement.qualname!r} is missing after the replacement")
    return result


def module_path(package_dir: Path, module: str) -> Path:
    return package_dir.joinpath(*module.split(".")).with_suffix(".py")


def copy_package(source: Path, destination: Path) -> None:
    shutil.copytree(source, destination, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))


def prepare_folder(folder: Path) -> None:
    """Make ``folder`` empty; refuse to delete a folder this module did not write."""
    if folder.exists():
        if not (folder / ABOUT_FILE).is_file():
            raise ExampleClassError(f"{folder} exists and is not a sample written by `grader example-class`; "
                                    "choose another --out folder")
        shutil.rmtree(folder)
    folder.mkdir(parents=True)


def build_buggy_sample(sample: BuggySample, out_dir: Path, reference_dir: Path = SOLUTIONS_DIR) -> Path:
    """Write ``out_dir/bug-<name>/exercises``: the reference with the sample's bug.

    The modules are rewritten in memory first, so a sample that cannot be built
    (:class:`ExampleClassError`) leaves nothing behind.
    """
    by_module: dict[str, list[Replacement]] = {}
    for replacement in sample.replacements:
        by_module.setdefault(replacement.module, []).append(replacement)
    rewritten = {}
    for module, replacements in by_module.items():
        path = module_path(reference_dir, module)
        where = f"sample {sample.name!r}, module {module!r}"
        if not path.is_file():
            raise ExampleClassError(f"{where}: no file {path}")
        rewritten[module] = replace_functions(path.read_text(encoding="utf-8"), replacements, where)
    folder = Path(out_dir) / sample.folder_name
    prepare_folder(folder)
    copy_package(reference_dir, folder / PACKAGE)
    for module, text in rewritten.items():
        module_path(folder / PACKAGE, module).write_text(text, encoding="utf-8")
    functions = ", ".join(f"`{r.module}.{r.qualname}`" for r in sample.replacements)
    failures = "\n".join(f"- `{name}`" for name in sorted(sample.expected_failures))
    (folder / ABOUT_FILE).write_text(
        f"# Sample `{sample.folder_name}` (erratum {sample.erratum})\n\n{sample.mistake}\n\n"
        f"Rewritten: {functions}; everything else is the reference.\n\nTests it should fail:\n\n{failures}\n",
        encoding="utf-8")
    return folder


def build_copy_sample(name: str, source: Path, about: str, out_dir: Path) -> Path:
    folder = Path(out_dir) / name
    prepare_folder(folder)
    copy_package(source, folder / PACKAGE)
    (folder / ABOUT_FILE).write_text(f"# Sample `{name}`\n\n{about}\n", encoding="utf-8")
    return folder


def build_example_class(out_dir: Path, samples: tuple[BuggySample, ...] = BUGGY_SAMPLES) -> list[Path]:
    """Write the example class into ``out_dir``: one folder per sample submission.

    Returns the folders: ``reference``, ``stubs``, then ``bug-<name>`` per sample.
    Folders of an earlier build are replaced; other folders are never touched.

    Raises
    ------
    ExampleClassError
        When a buggy sample cannot be built (unknown module or function, buggy source
        that does not parse), or a sample folder exists and was not written here.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    folders = [
        build_copy_sample(REFERENCE_SAMPLE, SOLUTIONS_DIR, "The reference engine (`solutions/`): full marks.", out_dir),
        build_copy_sample(STUBS_SAMPLE, EXERCISES_DIR, "The student package as handed out (`exercises/`): every "
                          "exercise raises NotImplementedError, zero marks.", out_dir),
    ]
    folders += [build_buggy_sample(sample, out_dir) for sample in samples]
    return folders


def points_lost(sample: BuggySample, tests) -> float:
    """Points at stake: those of the tests in ``tests`` (TestSpec list) that ``sample``
    should fail (it loses all of them, or a share where a test gives partial credit)."""
    return sum(t.points for t in tests if t.name in sample.expected_failures)


# --------------------------------------------------------------------------- command line

def add_example_class_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", type=Path, required=True, metavar="DIR",
                        help="folder to write the sample submissions into (one subfolder each)")


def main_example_class(args: argparse.Namespace) -> int:
    from .spec import load_spec

    tests = load_spec()
    total = sum(t.points for t in tests)
    try:
        folders = build_example_class(args.out)
    except ExampleClassError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    expected = {REFERENCE_SAMPLE: f"{total:g} / {total:g}", STUBS_SAMPLE: f"0 / {total:g}"}
    for sample in BUGGY_SAMPLES:
        expected[sample.folder_name] = f"at least {total - points_lost(sample, tests):g}, below {total:g}"
    width = max(len(f.name) for f in folders)
    print(f"wrote {len(folders)} sample submissions to {args.out}:")
    for folder in folders:
        print(f"  {folder.name:{width}s}  expected {expected[folder.name]}")
    print(f"grade them with: grader grade {args.out}/* --out REPORTS_DIR")
    return 0
