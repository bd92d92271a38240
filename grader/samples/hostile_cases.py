"""Broken and hostile sample submissions, built from data, with the outcome each must get.

Student code is untrusted: a student may be careless, or may try to raise a score
without doing the work.  Each :class:`HostileCase` below is one such submission, built
like the samples of :mod:`grader.samples.example_class`:

- on the **reference** (a copy of ``solutions/`` as ``exercises/``) with one function or
  module replaced by the broken or hostile code: it must earn exactly the points of
  the tests that do not touch that code, and fail the others with a message naming
  what happened (the honest-work rule);
- on the **stubs** (a copy of ``exercises/``) with something added (a patching
  ``__init__.py``, lying return values): it must earn nothing;
- as an **archive** (a zip with ``..`` or absolute paths, a symbolic link, a zip bomb,
  a member name that is not UTF-8): refused with a reason, or graded normally when the
  archive is merely unusual;
- as a **folder** the grader must not follow or read whole (a symbolic link to the
  reference or to another student's work, the submission's own path a link, a sparse
  2 GiB file, too many files): refused with a reason, before any file is read.

The cases of ``SIZES`` make the grader's own process read something enormous (a
contact of 20,000 points, a 40 MB message, a scene of 8,000 balls): each costs only the
tests it touches, quickly, with the grader's memory bounded.

``expect`` lists, per group of tests, the outcome statuses accepted and the words the
test's output must contain; every test of a reference-based case outside those groups
must pass, every test of a stubs-based case outside them must read "not implemented".
:func:`problems` checks one graded ``results.json`` against its case, and
:func:`expected_score` gives the score the honest work earns.

Code may name paths through placeholders filled in when the case is built:
``@@REPO@@`` (this repository: the solutions and hidden tests a student would look
for), ``@@OUT@@`` (the grader's output folder), ``@@SENTINEL@@`` (a folder the
hostile code tries to write into, which must stay unchanged) and ``@@KEY@@`` (the
description of the kernel key one case stores and a later one looks for).

    python -m grader.samples.hostile_cases --out DIR [--grading-out OUT] [--sentinel FOLDER]

writes every case into ``DIR`` (one folder or zip each) and prints the table of cases.
"""
from __future__ import annotations

import argparse
import ast
import base64
import hashlib
import importlib.util
import io
import json
import marshal
import shutil
import stat
import sys
import textwrap
import zipfile
from dataclasses import dataclass
from pathlib import Path

from ..student.manifest import COURSE_NAME, MANIFEST_FORMAT, MANIFEST_NAME, MANIFEST_VERSION
from .example_class import (EXERCISES_DIR, PACKAGE, REPO_ROOT, SOLUTIONS_DIR, Replacement, copy_package,
                            find_function, module_path, replace_functions)

MOMENTUM = "response.momentum_1d"
PROJECTION = "narrowphase.projection"
CIRCLE_MODULE = "narrowphase.circle_circle"
SIGNATURE = "def perfectly_inelastic_1d(m1, v1, m2, v2):"
# The test sets below were derived by grading each case on the whole spec (public and
# hidden tests, `grader list`) and reading which graded tests call the function a case
# replaces (grader/tests/*/test_*.py call the student's modules directly: the SAT and
# contact tests of circle-polygon pairs reach project_circle and project_vertices
# through circle_polygon_overlap, those of polygons through polygons_overlap and
# obbs_overlap; no test reaches the reference's momentum_1d but through its own calls).
#: The test that gives each momentum function input on the edge of what is allowed, which
#: must be answered, then bad input, which must raise a ValueError: a replaced function
#: that raises on the allowed input (a ValueError too) fails it there ("is allowed
#: input"), one that answers the bad input fails it ("must raise ValueError").
BAD_INPUT = frozenset({"momentum.rejects_bad_input"})
#: Tests that call perfectly_inelastic_1d, the function most cases poison (nothing in
#: the reference calls it, so no other test reaches it).
INELASTIC = frozenset({"momentum.perfectly_inelastic", "momentum.wall"}) | BAD_INPUT
#: Tests that call collision_1d, directly or through elastic_collision_1d.
COLLISION = frozenset({"momentum.elastic", "momentum.restitution", "momentum.wall"}) | BAD_INPUT
MOMENTUM_TESTS = INELASTIC | COLLISION
#: Tests of circle-polygon SAT: they reach project_circle (and project_vertices) through
#: circle_polygon_overlap.
CIRCLE_POLYGON_SAT = frozenset({"sat.circle_polygon_random", "sat.circle_off_corner", "sat.far_from_origin",
                                "sat.circle_polygon_opposite_sides", "sat.random_against_reference",
                                "sat.degenerate_shapes"})
#: Tests that reach project_circle: directly, and through circle_polygon_overlap.
PROJECT_CIRCLE = frozenset({"sat.project_circle"}) | CIRCLE_POLYGON_SAT
#: Tests that reach project_vertices: directly, and through the SAT tests of polygons
#: (polygons_overlap, obbs_overlap) and of circles against polygons.  The contact tests
#: of polygons do not: the reference's clipping projects with its own arithmetic.
PROJECT_VERTICES = frozenset({"sat.project_vertices", "sat.polygons_overlap_random", "sat.obbs_overlap_random",
                              "sat.one_side_separates", "sat.obb_negative_coordinates"}) | CIRCLE_POLYGON_SAT
#: Tests that call collide_circle_circle.
COLLIDE_CIRCLES = frozenset({"contacts.circle_circle", "contacts.degenerate_shapes",
                             "contacts.random_against_reference"})
#: Tests whose functions live in narrowphase.circle_circle (circles_overlap, collide_circle_circle).
CIRCLE_CIRCLE = frozenset({"sat.circles_overlap", "sat.degenerate_shapes", "sat.random_against_reference"}) \
    | COLLIDE_CIRCLES
#: The test that steps a scene with the student's resolver (stepped in the trusted process).
SCENE = frozenset({"impulse.scene"})

FAILED_ANSWER = ("failed",)
ERROR = ("error",)
TIMEOUT = ("timeout",)
CRASHED = ("crashed",)
NOT_IMPLEMENTED = ("not_implemented",)


@dataclass(frozen=True)
class Expect:
    """The outcome of a group of tests.

    Attributes
    ----------
    tests : frozenset of str
        Test names (of the spec); those not being graded are ignored.
    statuses : tuple of str
        Outcome statuses accepted (results.json ``extra_data.status``).
    words : tuple of str
        Each must appear in the test's output (case-insensitive).
    partial : bool
        The tests may earn part of their points (partial credit on a share of right
        cases); otherwise they earn nothing.
    """

    tests: frozenset[str]
    statuses: tuple[str, ...]
    words: tuple[str, ...] = ()
    partial: bool = False


@dataclass(frozen=True)
class HostileCase:
    """One broken or hostile submission and what grading it must give.

    Attributes
    ----------
    name : str
        Folder (or ``<name>.zip``) of the sample.
    category : str
        ``"broken"`` (careless) or ``"hostile"`` (trying to cheat or to hurt).
    what : str
        What the code does, in one sentence.
    base : str
        ``"reference"`` or ``"stubs"``: the package the sample starts from.
    replacements : tuple of Replacement
        Functions swapped for the case's code.
    appends : tuple of (module, text or bytes)
        Text added at the end of a module (module-level code).
    removes : tuple of str
        ``"module"`` (the file is deleted) or ``"module:qualname"`` (the function is).
    archive : str or None
        For archive cases, the kind of archive (see :func:`write_archive`).
    layout : str or None
        For folder cases with links or unusual files, the kind of folder (see
        :func:`write_layout`).
    expect : tuple of Expect
        The tests the code touches and their outcome; every other test passes
        (reference) or is not implemented (stubs).
    refused : tuple of str or None
        For a submission that must be refused: words of the reason.
    """

    name: str
    category: str
    what: str
    base: str = "reference"
    replacements: tuple[Replacement, ...] = ()
    appends: tuple[tuple[str, str | bytes], ...] = ()
    removes: tuple[str, ...] = ()
    archive: str | None = None
    layout: str | None = None
    expect: tuple[Expect, ...] = ()
    refused: tuple[str, ...] | None = None

    @property
    def touched(self) -> frozenset[str]:
        """Every test the case's code reaches."""
        return frozenset().union(*(e.tests for e in self.expect)) if self.expect else frozenset()

    @property
    def file_name(self) -> str:
        return f"{self.name}.zip" if self.archive else self.name

    @property
    def code(self) -> str:
        """The case's code as one text (for the table of cases)."""
        parts = [textwrap.dedent(r.source).strip() for r in self.replacements]
        parts += [text if isinstance(text, str) else text.decode("latin-1") for _, text in self.appends]
        parts += [f"(deleted: {r})" for r in self.removes]
        if self.archive:
            parts.append(f"(archive: {self.archive})")
        if self.layout:
            parts.append(f"(folder: {self.layout})")
        return "\n\n".join(textwrap.dedent(p).strip() for p in parts)


def raising(tests: frozenset[str], statuses: tuple[str, ...], words: tuple[str, ...] = ()) -> tuple[Expect, ...]:
    """The groups of code that raises (any exception, a ValueError too), hangs or crashes
    in ``tests``: they end with ``statuses`` and say ``words``, but for the bad-input test,
    which fails on the first allowed input, saying what it raised (or stops as the call did)."""
    stopped = tuple(s for s in statuses if s in TIMEOUT + CRASHED)
    groups = (Expect(tests - BAD_INPUT, statuses, words),
              Expect(tests & BAD_INPUT, FAILED_ANSWER + stopped, () if stopped else ("is allowed input",)))
    return tuple(group for group in groups if group.tests)


def inelastic(source: str, imports: tuple[str, ...] = ()) -> tuple[Replacement, ...]:
    """perfectly_inelastic_1d replaced by ``source`` (its def line is added)."""
    body = textwrap.indent(textwrap.dedent(source).strip("\n"), "    ")
    return (Replacement(MOMENTUM, "perfectly_inelastic_1d", f"{SIGNATURE}\n{body}\n", imports),)


# --------------------------------------------------------------------------- broken

BROKEN = (
    HostileCase(
        "broken-syntax-error", "broken", "response/momentum_1d.py ends with a function that does not parse.",
        appends=((MOMENTUM, "\n\ndef unfinished(a, b:\n    return a +\n"),),
        expect=raising(MOMENTUM_TESTS, ERROR, ("could not be imported", "SyntaxError"))),
    HostileCase(
        "broken-import-error", "broken", "narrowphase/circle_circle.py raises an exception when it is imported.",
        appends=(("narrowphase.circle_circle", '\n\nraise RuntimeError("my module is broken")\n'),),
        expect=(Expect(CIRCLE_CIRCLE, ERROR, ("could not be imported", "RuntimeError: my module is broken")),)),
    HostileCase(
        "broken-missing-module", "broken", "response/momentum_1d.py is not handed in.",
        removes=(MOMENTUM,),
        expect=raising(MOMENTUM_TESTS, ERROR, ("could not be imported", "No module named"))),
    HostileCase(
        "broken-missing-function", "broken", "perfectly_inelastic_1d was deleted from response/momentum_1d.py "
        "(the trusted side reads the source first: no statement defines it).",
        removes=(f"{MOMENTUM}:perfectly_inelastic_1d",),
        expect=(Expect(INELASTIC, NOT_IMPLEMENTED, ("perfectly_inelastic_1d", "no statement of the source you "
                                                    "handed in defines it")),)),
    HostileCase(
        "broken-returns-none", "broken", "perfectly_inelastic_1d forgets its return statement.",
        replacements=inelastic("total = m1 * v1 + m2 * v2\ncommon = total / (m1 + m2)\n"),
        expect=(Expect(INELASTIC - BAD_INPUT, FAILED_ANSWER, ("expected a number", "got None")),
                Expect(BAD_INPUT, FAILED_ANSWER, ("must raise ValueError", "got None")))),
    HostileCase(
        "broken-returns-string", "broken", "collision_1d returns a string.",
        replacements=(Replacement(MOMENTUM, "collision_1d", '''
            def collision_1d(m1, v1, m2, v2, restitution):
                return "fast"
            '''),),
        expect=(Expect(COLLISION - BAD_INPUT, FAILED_ANSWER, ("must return (v1', v2')", "'fast'")),
                Expect(BAD_INPUT, FAILED_ANSWER, ("must raise ValueError", "'fast'")))),
    HostileCase(
        "broken-wrong-length", "broken", "project_vertices returns three numbers instead of (min, max).",
        replacements=(Replacement(PROJECTION, "project_vertices", '''
            def project_vertices(vertices, axis):
                along = [float(x) * float(axis[0]) + float(y) * float(axis[1]) for x, y in vertices]
                return min(along), max(along), 0.0
            '''),),
        expect=(Expect(frozenset({"sat.project_vertices"}), FAILED_ANSWER, ("must return (min, max)",)),
                # The reference's SAT functions unpack the interval: "too many values".
                Expect(PROJECT_VERTICES - {"sat.project_vertices"}, ERROR, ("too many values to unpack",)))),
    HostileCase(
        "broken-nan-inf", "broken", "project_circle returns NaN and infinity.",
        replacements=(Replacement(PROJECTION, "project_circle", '''
            def project_circle(center, radius, axis):
                return float("nan"), float("inf")
            '''),),
        expect=(Expect(frozenset({"sat.project_circle"}), FAILED_ANSWER, ("not a finite number",)),
                # circle_polygon_overlap compares NaN, which is always false: it says "apart" for
                # every pair, wrong for the overlapping ones (partial credit where the test gives it).
                Expect(CIRCLE_POLYGON_SAT, FAILED_ANSWER, (), partial=True))),
    HostileCase(
        "broken-exception", "broken", "perfectly_inelastic_1d divides by zero.",
        replacements=inelastic("return (m1 * v1 + m2 * v2) / 0\n"),
        expect=raising(INELASTIC, ERROR, ("raised an exception", "ZeroDivisionError"))),
    HostileCase(
        "broken-recursion", "broken", "perfectly_inelastic_1d calls itself without end.",
        replacements=inelastic("return perfectly_inelastic_1d(m1, v1, m2, v2)\n"),
        expect=raising(INELASTIC, ERROR, ("recursion limit",))),
    HostileCase(
        "broken-prints-megabytes", "broken",
        "collision_1d prints 20 MB (print, sys.stderr, raw writes to fd 1 and 2) and then fails; "
        "perfectly_inelastic_1d prints as much and returns the right value.",
        replacements=(
            Replacement(MOMENTUM, "collision_1d", '''
                def collision_1d(m1, v1, m2, v2, restitution):
                    print("spam " * 2_000_000)
                    sys.stderr.write("more spam " * 1_000_000)
                    os.write(1, b"x" * 1_000_000)
                    os.write(2, b"y" * 1_000_000)
                    raise ValueError("gave up after printing")
                ''', imports=("import os", "import sys")),
            *inelastic('''
                print("loud " * 4_000_000)
                w1, v1, w2, v2 = _checked_pair(m1, v1, m2, v2)
                return (w2 * v1 + w1 * v2) / (w1 + w2)
                '''),
        ),
        # What was printed is cut (the worker keeps 8,000 characters per call, the test's
        # output 4,000): the results stay small (test_every_results_file_is_valid_gradescope_json).
        expect=raising(COLLISION, ERROR, ("gave up after printing", "your code printed", "spam spam"))),
    HostileCase(
        "broken-non-utf8-source", "broken",
        "response/momentum_1d.py holds a string typed in an editor set to Latin-1 (not UTF-8, no encoding declared).",
        appends=((MOMENTUM, b'\nGREETING = "caf\xe9 cr\xe8me"\n'),),
        expect=raising(MOMENTUM_TESTS, ERROR, ("could not be imported", "UTF-8"))),
)

# --------------------------------------------------------------------------- hostile

HOSTILE = (
    HostileCase(
        "hostile-infinite-loop", "hostile", "project_circle loops forever.",
        replacements=(Replacement(PROJECTION, "project_circle", '''
            def project_circle(center, radius, axis):
                while True:
                    pass
            '''),),
        expect=(Expect(PROJECT_CIRCLE, TIMEOUT, ("took too long", "wall clock")),)),
    HostileCase(
        "hostile-memory-bomb", "hostile", "perfectly_inelastic_1d allocates 400 MB arrays until memory runs out.",
        replacements=inelastic('''
            blocks = []
            while True:
                blocks.append(np.zeros(50_000_000))
            '''),
        expect=raising(INELASTIC, ERROR + CRASHED, ("memory",))),
    HostileCase(
        "hostile-fork-bomb", "hostile", "perfectly_inelastic_1d forks in a loop, every child forking too.",
        replacements=inelastic('''
            while True:
                os.fork()
            ''', imports=("import os",)),
        expect=raising(INELASTIC, ERROR + CRASHED + TIMEOUT)),
    HostileCase(
        "hostile-sleep", "hostile", "perfectly_inelastic_1d sleeps for an hour.",
        replacements=inelastic("time.sleep(3600)\n", imports=("import time",)),
        expect=(Expect(INELASTIC, TIMEOUT, ("took too long",)),)),
    HostileCase(
        "hostile-sys-exit", "hostile", "perfectly_inelastic_1d calls sys.exit(0) mid-test.",
        replacements=inelastic("sys.exit(0)\n", imports=("import sys",)),
        expect=raising(INELASTIC, ERROR, ("sys.exit(0)",))),
    HostileCase(
        "hostile-os-exit", "hostile", "perfectly_inelastic_1d calls os._exit(0) mid-test.",
        replacements=inelastic("os._exit(0)\n", imports=("import os",)),
        expect=(Expect(INELASTIC, CRASHED, ("crashed", "exited")),)),
    HostileCase(
        "hostile-kill-parent", "hostile",
        "perfectly_inelastic_1d sends SIGTERM and SIGKILL to its parent, to pid 1 and to every process it "
        "may signal (kill -1), then returns nothing.",
        replacements=inelastic('''
            for target in (os.getppid(), 1, -1):
                for sig in (signal.SIGTERM, signal.SIGKILL):
                    try:
                        os.kill(target, sig)
                    except OSError:
                        pass
            return None
            ''', imports=("import os", "import signal")),
        # Every kill fails or hits nothing of the grader's; the answer is judged.
        expect=(Expect(INELASTIC, FAILED_ANSWER, ("got None",)),)),
    HostileCase(
        "hostile-segfault", "hostile", "perfectly_inelastic_1d reads address 0 with ctypes.",
        replacements=inelastic("return ctypes.string_at(0)\n", imports=("import ctypes",)),
        expect=(Expect(INELASTIC, CRASHED, ("segmentation fault",)),)),
    HostileCase(
        "hostile-monkeypatch", "hostile",
        "On the stubs, exercises/__init__.py patches builtins, numpy, pytest, json, the worker's codec and "
        "its request handler, so that every call answers 'ok' with a made-up value.",
        base="stubs",
        appends=(("__init__", '''

import builtins as _builtins
import json as _json
import sys as _sys

import numpy as _np

_np.allclose = _np.isclose = _np.array_equal = lambda *args, **kwargs: True
_isinstance = _builtins.isinstance
_builtins.isinstance = lambda obj, kinds: True if kinds in (float, int, bool) else _isinstance(obj, kinds)
_builtins.abs = lambda value: 0.0
try:
    import pytest as _pytest
    _pytest.approx = lambda *args, **kwargs: True
except Exception:
    pass
_json.dumps = lambda *args, **kwargs: '{"id": 1, "status": "ok", "value": true}'
for _name in ("grader", "grader.sandbox.process", "grader.harness.compare", "grader.harness.plugin"):
    try:
        __import__(_name)
    except Exception:
        pass
_codec = _sys.modules.get("codec")
if _codec is not None:
    _codec.encode_value = lambda value, depth=0: True
    _codec.plain_data = lambda value, depth=0: value
_worker = _sys.modules.get("__main__")
if _worker is not None and hasattr(_worker, "Worker"):
    _worker.Worker.handle = lambda self, request, captured: {"status": "ok", "value": "PASS", "args_after": []}
'''),),
        # Every test: the made-up "PASS" is a wrong answer (or the wrong number of
        # answers); code the patches break may also crash the student's own worker; the
        # call that first imports the package still runs the stub.
        expect=(Expect(frozenset({"*"}), FAILED_ANSWER + ERROR + CRASHED + NOT_IMPLEMENTED),)),
    HostileCase(
        "hostile-lying-objects", "hostile",
        "On the stubs, perfectly_inelastic_1d returns an object whose __eq__ is always true and __float__ "
        "lies; collision_1d returns a list subclass lying about its length and items, holding a float "
        "subclass lying in __eq__, __float__ and __index__.",
        base="stubs",
        replacements=(
            Replacement(MOMENTUM, "perfectly_inelastic_1d", '''
                def perfectly_inelastic_1d(m1, v1, m2, v2):
                    class Liar:
                        def __eq__(self, other):
                            return True
                        def __float__(self):
                            return 21.296296296296298
                        __hash__ = object.__hash__
                    return Liar()
                '''),
            Replacement(MOMENTUM, "collision_1d", '''
                def collision_1d(m1, v1, m2, v2, restitution):
                    class LyingFloat(float):
                        def __eq__(self, other):
                            return True
                        def __float__(self):
                            return 1e300
                        def __index__(self):
                            return 0
                        __hash__ = float.__hash__
                    class LyingList(list):
                        def __len__(self):
                            return 2
                        def __iter__(self):
                            return iter([1.0, 2.0])
                        def __getitem__(self, i):
                            return 1.0
                    return LyingList([LyingFloat(0.0)])
                '''),
        ),
        # momentum.wall calls collision_1d first and stops at its liar; the bad-input test
        # takes the liar for an answer to allowed input and stops at the stub it calls next.
        expect=(Expect(frozenset({"momentum.perfectly_inelastic"}), ERROR, ("cannot read", "Liar")),
                Expect(frozenset({"momentum.restitution", "momentum.wall"}), FAILED_ANSWER,
                       ("must return (v1', v2'), got [0]",)),
                Expect(BAD_INPUT, NOT_IMPLEMENTED, ("elastic_collision_1d",)))),
    HostileCase(
        "hostile-import-reference", "hostile",
        "perfectly_inelastic_1d imports the reference solutions by name, after adding the repository to sys.path.",
        replacements=inelastic('''
            sys.path.insert(0, "@@REPO@@")
            from solutions.response.momentum_1d import perfectly_inelastic_1d as reference
            return reference(m1, v1, m2, v2)
            ''', imports=("import sys",)),
        expect=raising(INELASTIC, ERROR, ("No module named 'solutions'",))),
    HostileCase(
        "hostile-import-by-path", "hostile",
        "perfectly_inelastic_1d loads the reference module from its path with importlib.",
        replacements=inelastic('''
            spec = importlib.util.spec_from_file_location(
                "stolen", "@@REPO@@/solutions/response/momentum_1d.py")
            module = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(module)
            return module.perfectly_inelastic_1d(m1, v1, m2, v2)
            ''', imports=("import importlib.util",)),
        expect=raising(INELASTIC, ERROR, ("No such file", "momentum_1d.py"))),
    HostileCase(
        "hostile-read-hidden-spec", "hostile",
        "perfectly_inelastic_1d reads the hidden tests and the solutions from disk.",
        replacements=inelastic('''
            with open("@@REPO@@/grader/tests/hidden/test_grid.py") as handle:
                spec = handle.read()
            with open("@@REPO@@/solutions/response/momentum_1d.py") as handle:
                solution = handle.read()
            return float(len(spec) + len(solution))
            '''),
        expect=raising(INELASTIC, ERROR, ("No such file", "test_grid.py"))),
    HostileCase(
        "hostile-write-results", "hostile",
        "perfectly_inelastic_1d writes results.json files with full marks (its own, another student's, in "
        "every folder above its own) and overwrites the gradebook and the grading log.",
        replacements=inelastic('''
            forged = json.dumps({"score": 1000, "tests": [], "output": "full marks"})
            targets = ["@@OUT@@/hostile-write-results/results.json", "@@OUT@@/reference/results.json",
                       "@@OUT@@/gradebook.csv", "@@OUT@@/grading_log.jsonl", "/autograder/results/results.json"]
            folder = os.getcwd()
            for _ in range(8):
                targets.append(os.path.join(folder, "results.json"))
                folder = os.path.dirname(folder)
            written = 0
            for target in targets:
                try:
                    os.makedirs(os.path.dirname(target), exist_ok=True)
                    with open(target, "w") as handle:
                        handle.write(forged)
                    written += 1
                except OSError:
                    pass
            return None
            ''', imports=("import json", "import os")),
        expect=(Expect(INELASTIC, FAILED_ANSWER, ("got None",)),)),
    HostileCase(
        "hostile-write-outside", "hostile",
        "perfectly_inelastic_1d writes into a sentinel folder, the repository, its solutions and /etc, "
        "then fails.",
        replacements=inelastic('''
            errors = []
            for target in ("@@SENTINEL@@/pwned.txt", "@@SENTINEL@@/keep.txt", "@@REPO@@/pwned.py",
                           "@@REPO@@/README.md", "@@REPO@@/solutions/response/momentum_1d.py", "/etc/pwned",
                           os.path.expanduser("~/.bashrc")):
                try:
                    with open(target, "a") as handle:
                        handle.write("pwned\\n")
                except OSError as exc:
                    errors.append(f"{target}: {exc.strerror}")
            raise PermissionError("could not write: " + "; ".join(errors))
            ''', imports=("import os",)),
        expect=raising(INELASTIC, ERROR, ("could not write", "pwned.txt"))),
    HostileCase(
        "hostile-leave-process", "hostile",
        "perfectly_inelastic_1d leaves processes running (a sleep in a session of its own, a daemon "
        "escaping with a double fork and setsid) and a thread in the worker, then returns nothing.",
        replacements=inelastic('''
            if getattr(perfectly_inelastic_1d, "started", False):
                return None
            perfectly_inelastic_1d.started = True
            # The sandbox holds no program but the worker's Python: that Python sleeps.
            subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"], start_new_session=True)
            if os.fork() == 0:
                os.setsid()
                if os.fork() == 0:
                    time.sleep(600)
                os._exit(0)
            threading.Thread(target=time.sleep, args=(600,), daemon=True).start()
            return None
            ''', imports=("import os", "import subprocess", "import sys", "import threading", "import time")),
        expect=(Expect(INELASTIC, FAILED_ANSWER, ("got None",)),)),
    HostileCase(
        "hostile-forge-answers", "hostile",
        "perfectly_inelastic_1d writes forged answers on the worker's answer channel: lines with guessed ids "
        "and nonces, bytes that are not UTF-8, a daemon process that keeps forging, and one answer with the "
        "request's real nonce read from the worker's memory, claiming every value is None (on its first "
        "call; the others return 0).",
        replacements=inelastic('''
            if getattr(perfectly_inelastic_1d, "forged", False):
                return 0.0
            perfectly_inelastic_1d.forged = True
            channel = int(sys.argv[1])
            frame = sys._getframe()
            while frame is not None and "nonce" not in frame.f_locals:
                frame = frame.f_back
            nonce, number = frame.f_locals["nonce"], frame.f_locals["number"]
            cases = len(frame.f_locals["request"]["args"])
            guessed = json.dumps({"id": number, "nonce": "guess", "status": "ok", "value": [1.0] * cases})
            for _ in range(50):
                os.write(channel, guessed.encode() + b"\\n")
                os.write(channel, b"\\xff\\xfe not json\\n")
            if os.fork() == 0:
                os.setsid()
                while True:
                    os.write(channel, guessed.encode() + b"\\n")
                    time.sleep(0.01)
            forged = {"id": number, "nonce": nonce, "status": "ok", "value": [None] * cases, "pid": 1}
            os.write(channel, json.dumps(forged).encode() + b"\\n")
            return 0.0
            ''', imports=("import json", "import os", "import sys", "import time")),
        # The forged answer is taken (it carries the nonce), and judged: None is wrong; the
        # later calls' 0 is wrong too.
        expect=(Expect(frozenset({"momentum.perfectly_inelastic"}), FAILED_ANSWER, ("got None",)),
                Expect(INELASTIC, FAILED_ANSWER))),
    HostileCase(
        "hostile-ignore-signals", "hostile",
        "perfectly_inelastic_1d ignores SIGTERM, SIGINT, SIGALRM and SIGXCPU, cancels alarms, then loops.",
        replacements=inelastic('''
            for sig in (signal.SIGTERM, signal.SIGINT, signal.SIGALRM, signal.SIGXCPU, signal.SIGHUP):
                signal.signal(sig, signal.SIG_IGN)
            signal.alarm(0)
            signal.setitimer(signal.ITIMER_REAL, 0)
            while True:
                pass
            ''', imports=("import signal",)),
        expect=(Expect(INELASTIC, TIMEOUT, ("took too long",)),)),
    HostileCase(
        "hostile-raise-limits", "hostile",
        "perfectly_inelastic_1d tries to lift its memory, CPU and process limits with resource.setrlimit.",
        replacements=inelastic('''
            for limit in (resource.RLIMIT_AS, resource.RLIMIT_CPU, resource.RLIMIT_NPROC):
                resource.setrlimit(limit, (resource.RLIM_INFINITY, resource.RLIM_INFINITY))
            return 0.0
            ''', imports=("import resource",)),
        expect=raising(INELASTIC, ERROR, ("not allowed to raise maximum limit",))),
    HostileCase(
        "hostile-huge-answer", "hostile", "perfectly_inelastic_1d returns a 70 MB string (once).",
        replacements=inelastic('''
            if getattr(perfectly_inelastic_1d, "sent", False):
                return None
            perfectly_inelastic_1d.sent = True
            return "x" * 70_000_000
            '''),
        # The worker is stopped after a too large answer: its new one sends it again.
        expect=raising(INELASTIC, ERROR, ("larger than the grader accepts",))),
    HostileCase(
        "hostile-non-utf8-output", "hostile",
        "perfectly_inelastic_1d prints lone surrogates and raw bytes that are not UTF-8, then raises an "
        "exception whose message holds them.",
        replacements=inelastic('''
            print("caf\\udce9 \\ud800")
            os.write(1, b"\\xff\\xfe\\xfd")
            os.write(2, b"\\xff\\xfe\\xfd")
            raise ValueError("bad text \\udcff\\udcfe")
            ''', imports=("import os",)),
        expect=raising(INELASTIC, ERROR, ("raised an exception", "ValueError: bad text", "your code printed"))),
    HostileCase(
        "hostile-poison-modules", "hostile",
        "narrowphase/circle_circle.py, when imported, replaces exercises.shapes.Circle (the class the worker "
        "builds input circles with) by one that moves every circle.",
        appends=(("narrowphase.circle_circle", '''

import sys as _sys

_shapes = _sys.modules["exercises.shapes"]


class _MovedCircle(_shapes.Circle):
    def __init__(self, center, radius):
        super().__init__([center[0] + 100.0, center[1]], radius)


_shapes.Circle = _MovedCircle
'''),),
        # Its own inputs only: every circle the worker builds after the module is imported
        # (first by sat.circles_overlap, which moves both circles alike and still passes).
        expect=(
            # Contacts of moved circles keep normal and depth but not their points; a moved
            # circle misses its box (contacts and SAT of circles against polygons).
            Expect(frozenset({"contacts.circle_circle", "contacts.circle_polygon", "contacts.centre_inside",
                              "contacts.random_against_reference", "contacts.degenerate_shapes",
                              "contacts.feature_ids"})
                   | CIRCLE_POLYGON_SAT, FAILED_ANSWER, (), partial=True),
            # Bodies whose circle is off their centre of mass: other inertia, other impulses.
            Expect(frozenset({"impulse.effective_mass", "impulse.magnitude"}), FAILED_ANSWER),
            # Bodies holding a moved circle come back as something the grader cannot read.
            Expect(frozenset({"impulse.apply_impulse", "impulse.resolve_collision", "impulse.correct_positions",
                              "impulse.closed_forms_any_case", "impulse.resolve_any_case",
                              "impulse.correct_positions_any_case", "impulse.resolve_conserves_momentum"}) | SCENE,
                   ERROR, ("cannot encode a _MovedCircle",)))),
    # The kernel keyring outlives a sandbox: a key readable by others, stored by one
    # submission, could be read by a later one under another uid.  The seccomp filter
    # refuses add_key, keyctl and request_key (grader/sandbox/seccomp.py).
    HostileCase(
        "hostile-keyring-store", "hostile",
        "perfectly_inelastic_1d stores its module's source in the kernel keyring (a user key anyone may read, "
        "linked into its user keyring), for a later submission under another uid; then answers rightly.",
        replacements=inelastic('''
            if not getattr(perfectly_inelastic_1d, "stored", False):
                libc = ctypes.CDLL(None, use_errno=True)
                libc.syscall.restype = ctypes.c_long
                with open(__file__, "rb") as handle:
                    source = handle.read()
                serial = libc.syscall(248, b"user", b"@@KEY@@", source, ctypes.c_size_t(len(source)),
                                      ctypes.c_int(-4))  # add_key(..., KEY_SPEC_USER_KEYRING)
                if serial < 0:
                    raise OSError(ctypes.get_errno(), "the kernel keyring refused add_key: "
                                  + os.strerror(ctypes.get_errno()))
                if libc.syscall(250, ctypes.c_int(5), ctypes.c_long(serial), ctypes.c_ulong(0x3F3F3F3F)) < 0:
                    raise OSError(ctypes.get_errno(), "the kernel keyring refused setperm")  # KEYCTL_SETPERM
                perfectly_inelastic_1d.stored = True
            w1, v1, w2, v2 = _checked_pair(m1, v1, m2, v2)
            return (w2 * v1 + w1 * v2) / (w1 + w2)
            ''', imports=("import ctypes", "import os")),
        expect=raising(INELASTIC, ERROR, ("the kernel keyring refused add_key", "Operation not permitted"))),
    HostileCase(
        "hostile-memfd-hog", "hostile",
        "perfectly_inelastic_1d fills anonymous memory files (memfd_create), 15 MiB each up to 4 GiB: memory "
        "outside its address-space limit; then answers rightly.",
        replacements=inelastic('''
            files = []
            chunk = b"m" * (15 << 20)
            while len(files) < 4096 // 15:
                fd = os.memfd_create(f"hog-{len(files)}")
                os.write(fd, chunk)
                files.append(fd)
            w1, v1, w2, v2 = _checked_pair(m1, v1, m2, v2)
            return (w2 * v1 + w1 * v2) / (w1 + w2)
            ''', imports=("import os",)),
        # Refused by the seccomp filter; were it not, the memory cage would kill the worker.
        expect=raising(INELASTIC, ERROR, ("memfd_create", "Operation not permitted"))),
    HostileCase(
        "hostile-disk-filler", "hostile",
        "perfectly_inelastic_1d fills every folder it can write (its working folder, /tmp, /dev/shm, its "
        "home) with 15 MiB files until it is refused, then fails saying how far it got.",
        replacements=inelastic('''
            chunk = b"d" * (15 << 20)
            report = []
            for folder in (os.getcwd(), "/tmp", "/dev/shm", os.path.expanduser("~")):
                written = 0
                try:
                    for n in range(400):  # 6 GiB at most
                        with open(os.path.join(folder, f"filler-{n}.bin"), "wb") as handle:
                            handle.write(chunk)
                        written += len(chunk)
                    report.append(f"{folder}: {written >> 20} MiB, never refused")
                except OSError as exc:
                    report.append(f"{folder}: {written >> 20} MiB, then {exc.strerror}")
            raise OSError("filled " + "; ".join(report))
            ''', imports=("import os",)),
        # The writable folders are tmpfs of Limits.disk_bytes (64 MiB) each.
        expect=raising(INELASTIC, ERROR, ("filled", "No space left on device"))),
    HostileCase(
        "hostile-fork-memory-hog", "hostile",
        "perfectly_inelastic_1d forks 4 children that each fill 900 MiB (under the per-process limit, over "
        "the sandbox's total together) and wait; it answers rightly only if all of them lived.",
        replacements=inelastic('''
            children = []
            for _ in range(4):
                pid = os.fork()
                if pid == 0:
                    try:
                        block = bytearray(900 << 20)
                        for i in range(0, len(block), 4096):
                            block[i] = 1  # touch every page
                        time.sleep(1)
                    finally:
                        os._exit(0)
                children.append(pid)
            deaths = [os.waitpid(pid, 0)[1] for pid in children]
            if any(deaths):
                raise MemoryError(f"children killed: {sum(1 for d in deaths if d)} of {len(children)}")
            w1, v1, w2, v2 = _checked_pair(m1, v1, m2, v2)
            return (w2 * v1 + w1 * v2) / (w1 + w2)
            ''', imports=("import os", "import time")),
        # The memory cage (Limits.total_memory_bytes, 3 GiB) kills a child (MemoryError) or the
        # worker; reclaiming memory in a full cage may take the call past its time.
        expect=raising(INELASTIC, ERROR + CRASHED + TIMEOUT)),
    HostileCase(
        "hostile-sealed-payload", "hostile",
        "On the stubs, response/momentum_1d.py keeps every stub and carries the reference module XOR-sealed; it "
        "unseals and runs it over its own functions only inside the grader (recognised by its cwd, argv and "
        "pid), so anywhere else it is the stubs and its source shows no solution.",
        base="stubs",
        appends=((MOMENTUM, '''

_SEALED = "@@SEALED@@"


def _unseal():
    import base64 as _b64
    import os as _os
    import sys as _sys
    graded = (_os.getcwd().startswith("/sandbox") or _os.getpid() == 1
              or any(".grader" in str(arg) for arg in _sys.argv))
    if graded:
        code = bytes(b ^ 0x5A for b in _b64.b64decode(_SEALED))
        exec(compile(code, __file__, "exec"), globals())


_unseal()
'''),),
        # The functions' source is the stub: not implemented, whatever the module does at run
        # time (grader.batch.source_audit), and the exec, cwd, pid and argv lines are flagged.
        expect=()),
    # issue 24: the grader's scene driver ran in the student's process, so a stubs package
    # could swap it for one returning the analytic resting stack (+2 on main).  Scenes are
    # now stepped in the trusted process: there is no driver here to swap.
    HostileCase(
        "hostile-driver-swap", "hostile",
        "On the stubs, solver/contact_point.py wraps the worker's module loader so that the grader's scene "
        "driver, once loaded, returns the analytic resting stack of ten boxes, without any working function.",
        base="stubs",
        appends=(("solver.contact_point", '''

import sys as _sys


def _resting_stack(steps=60, count=10, dt=1 / 60, iterations=20):
    trajectory = [[[0.5 + k, 0.0] for k in range(count)] for _ in range(steps)]
    impulses = [[(count - k) * 9.81 * dt for k in range(count)] for _ in range(steps)]
    return {"trajectory": trajectory, "impulses": impulses}


def _swap_driver():
    worker = _sys.modules.get("__main__")
    load = getattr(getattr(worker, "Worker", None), "load", None)
    if load is None:
        return

    def load_and_swap(self, name):
        module = load(self, name)
        if hasattr(module, "stack_of_boxes"):
            module.stack_of_boxes = _resting_stack
        return module

    worker.Worker.load = load_and_swap
    driver = _sys.modules.get("scene_driver")
    if driver is not None:
        driver.stack_of_boxes = _resting_stack


_swap_driver()
'''),),
        # Nothing of the grader runs beside the stubs: every test reads "not implemented".
        expect=()),
    HostileCase(
        "hostile-huge-integer", "hostile",
        "perfectly_inelastic_1d returns an integer of 4,001 digits (more than any float holds).",
        replacements=inelastic("return 10 ** 4000\n"),
        expect=(Expect(INELASTIC - BAD_INPUT, ERROR, ("4001 digits", "not a number of the course")),
                Expect(BAD_INPUT, FAILED_ANSWER + ERROR, ()))),
)

# --------------------------------------------------------------------------- sizes
# What a submission returns is read by the grader's own process: every size must be
# capped before it is parsed, stored, drawn or computed with.

SIZES = (
    HostileCase(
        "hostile-huge-contact", "hostile",
        "collide_circle_circle returns a contact of 20,000 points (and as many depths) for every pair.",
        replacements=(Replacement(CIRCLE_MODULE, "collide_circle_circle", '''
            def collide_circle_circle(a, b):
                x, y = float(a.center[0]), float(a.center[1])
                return Contact((1.0, 0.0), 0.5, [[x + 1e-3 * i, y - 1e-3 * i] for i in range(20_000)])
            '''),),
        # Encoding 20,000 points per pair takes the worker seconds: a whole batch of pairs may
        # run out of the call's time; a single pair comes back, is judged, and drawn cut short.
        expect=(Expect(COLLIDE_CIRCLES, FAILED_ANSWER + ERROR + TIMEOUT, ()),)),
    HostileCase(
        "hostile-huge-message", "hostile",
        "perfectly_inelastic_1d switches off the worker's own cap on messages and raises an exception whose "
        "message is 40 MB long.",
        replacements=inelastic('''
            worker = sys.modules.get("__main__")
            if worker is not None:
                worker.capped = lambda text, limit=0: text
                worker.MESSAGE_LIMIT = 10**9
            raise ValueError("E" * 40_000_000)
            ''', imports=("import sys",)),
        # The answer passes the grader's 16 MiB limit on what it reads: refused unread.
        expect=raising(INELASTIC, ERROR, ("larger than the grader accepts",))),
)

# --------------------------------------------------------------------------- archives

ARCHIVES = (
    HostileCase("zip-dotdot", "hostile", "A zip of the stubs with a member 'exercises/../../escaped.py'.",
                base="stubs", archive="dotdot", refused=("'..'",)),
    HostileCase("zip-absolute", "hostile", "A zip of the stubs with a member '/tmp/grader-hostile-escaped.py'.",
                base="stubs", archive="absolute", refused=("absolute path",)),
    HostileCase("zip-symlink", "hostile", "A zip of the stubs with a symbolic link to /etc/passwd.",
                base="stubs", archive="symlink", refused=("symbolic link",)),
    HostileCase("zip-bomb", "hostile", "A zip whose one member expands to 70 MB of zeros.",
                base="stubs", archive="bomb", refused=("zip bomb",)),
    HostileCase("zip-bad-utf8-name", "broken",
                "A zip of the stubs with a member name flagged as UTF-8 that is not valid UTF-8.",
                base="stubs", archive="bad-utf8-name", refused=("not valid UTF-8",)),
    HostileCase("zip-sourceless-bytecode", "hostile",
                "A zip with a valid manifest holding the stubs' __init__.py and every other module of the "
                "reference as a .pyc only (Python imports a .pyc without its source).",
                base="reference", archive="sourceless", refused=("only source is graded", ".pyc")),
    HostileCase("zip-import-in-notes", "hostile",
                "A zip of the stubs whose notes.txt is a zip archive of the reference (zipimport imports from "
                "any file holding a zip's end record, whatever its name).",
                base="stubs", archive="zip-in-text", refused=("only source is graded", "notes.txt")),
    HostileCase("zip-cp437-name", "broken",
                "A zip of the reference whose extra member name is in the old DOS code page (no UTF-8 flag): "
                "graded normally.", base="reference", archive="cp437-name"),
)

# --------------------------------------------------------------------------- layouts
# Folders the grader reads as root before any sandbox exists: no link may lead out.

LAYOUTS = (
    HostileCase("link-exercises-to-reference", "hostile",
                "A folder whose 'exercises' is a symbolic link to the repository's solutions/.",
                base="stubs", layout="exercises-link", refused=("'exercises' is a symbolic link", "never follows")),
    HostileCase("link-to-friend-folder", "hostile",
                "A folder holding only a symbolic link to another student's folder (copy-of-reference).",
                base="stubs", layout="folder-link", refused=("'friend' is a symbolic link", "never follows")),
    HostileCase("link-to-friend-zip", "hostile",
                "A folder holding only a symbolic link to another student's zip (zip-cp437-name.zip).",
                base="stubs", layout="zip-link", refused=("'friend.zip' is a symbolic link", "never follows")),
    HostileCase("link-as-submission", "hostile",
                "The submission itself, as given to the grader, is a symbolic link to another student's folder.",
                base="stubs", layout="path-link", refused=("the submission 'link-as-submission' is a symbolic link",)),
    HostileCase("folder-sparse-file", "hostile",
                "A folder of the stubs holding a sparse file of 2 GiB (nothing allocated).",
                base="stubs", layout="sparse-file", refused=("2.0 GiB", "at most 64.0 MiB")),
    HostileCase("folder-many-files", "hostile", "A folder of the stubs holding 2,100 more (empty) files.",
                base="stubs", layout="many-files", refused=("more than 2000 files and folders",)),
)

COPIES = (
    HostileCase("copy-of-reference", "hostile",
                "The reference solutions handed in as they are: full marks, flagged by `grader similarity`."),
)

# Graded after every other case (last in CASES): the key it looks for is stored first.
LATER = (
    HostileCase(
        "hostile-keyring-fetch", "hostile",
        "On the stubs, perfectly_inelastic_1d looks for the module hostile-keyring-store left in the kernel "
        "keyring (its user and session keyrings, and every key /proc/keys shows), runs it if found, and "
        "answers with it.",
        base="stubs",
        replacements=inelastic('''
            libc = ctypes.CDLL(None, use_errno=True)
            libc.syscall.restype = ctypes.c_long
            serials = []
            for keyring in (-4, -3):  # KEY_SPEC_USER_KEYRING, KEY_SPEC_SESSION_KEYRING
                found = libc.syscall(250, ctypes.c_int(10), ctypes.c_int(keyring), b"user", b"@@KEY@@",
                                     ctypes.c_int(0))  # KEYCTL_SEARCH
                if found > 0:
                    serials.append(found)
            try:
                with open("/proc/keys") as handle:
                    serials += [int(line.split()[0], 16) for line in handle if "@@KEY@@" in line]
            except OSError:
                pass
            for serial in serials:
                buffer = ctypes.create_string_buffer(1 << 20)
                size = libc.syscall(250, ctypes.c_int(11), ctypes.c_long(serial), buffer,
                                    ctypes.c_size_t(len(buffer)))  # KEYCTL_READ
                if 0 < size <= len(buffer):
                    stolen = {}
                    exec(compile(buffer.raw[:size], "stolen", "exec"), stolen)
                    return stolen["perfectly_inelastic_1d"](m1, v1, m2, v2)
            raise NotImplementedError("nothing found in the kernel keyring")
            ''', imports=("import ctypes",)),
        # Nothing to find: the stub's answer (not implemented), and no point.
        expect=(Expect(INELASTIC, NOT_IMPLEMENTED + ERROR, ()),)),
)

#: Every case, in the order of the table (and of grading: hostile-keyring-fetch comes last).
CASES: tuple[HostileCase, ...] = BROKEN + HOSTILE + SIZES + ARCHIVES + LAYOUTS + COPIES + LATER
ESCAPED_FILE = "/tmp/grader-hostile-escaped.py"
#: Size of the sparse file of the ``sparse-file`` layout (bytes; nothing is allocated).
SPARSE_BYTES = 2 * 1024**3
#: Files added by the ``many-files`` layout (more than grader.batch.submissions.MAX_FILES).
MANY_FILES = 2_100
#: Where the link layouts point, inside the folder the cases are written to.
FRIEND_FOLDER = "copy-of-reference"
FRIEND_ZIP = "zip-cp437-name.zip"


# --------------------------------------------------------------------------- building

def fill(text: str | bytes, params: dict[str, str]) -> str | bytes:
    """``text`` with its ``@@NAME@@`` placeholders replaced by ``params``."""
    for key, value in params.items():
        if isinstance(text, bytes):
            text = text.replace(f"@@{key}@@".encode(), str(value).encode())
        else:
            text = text.replace(f"@@{key}@@", str(value))
    return text


def sealed_reference(module: str = MOMENTUM) -> str:
    """The reference's ``module`` XOR-sealed (key 0x5A) and base64-encoded: the payload of
    ``hostile-sealed-payload``, which no text search of the submission finds."""
    source = (SOLUTIONS_DIR / Path(*module.split("."))).with_suffix(".py").read_bytes()
    return base64.b64encode(bytes(b ^ 0x5A for b in source)).decode()


def default_params() -> dict[str, str]:
    return {"REPO": str(REPO_ROOT), "OUT": "/nonexistent-output", "SENTINEL": "/nonexistent-sentinel",
            "KEY": "grader-hostile-keyring", "SEALED": sealed_reference()}


def remove_function(source: str, qualname: str) -> str:
    """``source`` without the function ``qualname`` (decorators and end marker included)."""
    tree = ast.parse(source)
    function = find_function(tree, qualname)
    if function is None:
        raise ValueError(f"no function {qualname!r}")
    lines = source.splitlines(keepends=True)
    first = min([function.lineno, *(d.lineno for d in function.decorator_list)])
    last = function.end_lineno
    while last < len(lines) and lines[last].lstrip().startswith("#") \
            and len(lines[last]) - len(lines[last].lstrip()) > function.col_offset:
        last += 1
    return "".join(lines[:first - 1] + lines[last:])


def _module_file(package: Path, module: str) -> Path:
    return package / "__init__.py" if module == "__init__" else module_path(package, module)


def build_package(case: HostileCase, package: Path, params: dict[str, str] | None = None,
                  reference_dir: Path = SOLUTIONS_DIR, stubs_dir: Path = EXERCISES_DIR) -> Path:
    """Write the case's ``exercises`` package at ``package`` (which must not exist)."""
    params = {**default_params(), **(params or {})}
    copy_package(reference_dir if case.base == "reference" else stubs_dir, package)
    by_module: dict[str, list[Replacement]] = {}
    for replacement in case.replacements:
        filled = Replacement(replacement.module, replacement.qualname, fill(replacement.source, params),
                             replacement.imports)
        by_module.setdefault(replacement.module, []).append(filled)
    for module, replacements in by_module.items():
        path = _module_file(package, module)
        path.write_text(replace_functions(path.read_text(encoding="utf-8"), replacements,
                                          f"case {case.name!r}, module {module!r}"), encoding="utf-8")
    for removed in case.removes:
        module, _, qualname = removed.partition(":")
        path = _module_file(package, module)
        if qualname:
            path.write_text(remove_function(path.read_text(encoding="utf-8"), qualname), encoding="utf-8")
        else:
            path.unlink()
    for module, text in case.appends:
        path = _module_file(package, module)
        text = fill(text, params)
        with open(path, "ab") as handle:
            handle.write(text if isinstance(text, bytes) else text.encode("utf-8"))
    return package


def _zip_package(archive: zipfile.ZipFile, package: Path, prefix: str = PACKAGE) -> None:
    for path in sorted(package.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts:
            archive.write(path, f"{prefix}/{path.relative_to(package).as_posix()}")


def _zip_sourceless(archive: zipfile.ZipFile, package: Path) -> None:
    """``package`` (the reference) zipped as ``grader submit`` would, but with the stubs'
    ``__init__.py`` and every other module compiled to a ``.pyc`` in place of its source,
    and a manifest listing every member."""
    entries = []
    for path in sorted(package.rglob("*.py")):
        relative = path.relative_to(package)
        if "__pycache__" in relative.parts:
            continue
        if relative.as_posix() == "__init__.py":
            name, data = f"{PACKAGE}/__init__.py", (EXERCISES_DIR / "__init__.py").read_bytes()
        else:
            name = f"{PACKAGE}/{relative.with_suffix('.pyc').as_posix()}"
            code = compile(path.read_bytes(), relative.as_posix(), "exec")
            data = importlib.util.MAGIC_NUMBER + b"\0" * 12 + marshal.dumps(code)
        entries.append({"path": name, "size": len(data), "sha256": hashlib.sha256(data).hexdigest()})
        archive.writestr(name, data)
    manifest = {"format": MANIFEST_FORMAT, "format_version": MANIFEST_VERSION, "course": COURSE_NAME,
                "created": "2025-03-01T14:05:09+01:00", "student": None, "package": PACKAGE,
                "file_count": len(entries), "total_bytes": sum(e["size"] for e in entries), "files": entries}
    archive.writestr(MANIFEST_NAME, json.dumps(manifest, indent=1) + "\n")


def write_archive(case: HostileCase, path: Path, package: Path) -> Path:
    """The case's zip at ``path``: ``package`` zipped, plus the case's hostile members.

    Kinds: ``dotdot``, ``absolute``, ``symlink``, ``bomb`` (70 MB of zeros),
    ``bad-utf8-name`` (UTF-8 flag on a name that is not UTF-8) and ``cp437-name`` (a name
    with bytes above 127 and no UTF-8 flag, read as code page 437).
    """
    kind = case.archive
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        if kind == "bomb":
            archive.writestr(f"{PACKAGE}/__init__.py", b"")
            with archive.open(f"{PACKAGE}/padding.py", "w", force_zip64=True) as member:
                zeros = bytes(1 << 20)
                for _ in range(70):
                    member.write(zeros)
            return path
        if kind == "sourceless":
            _zip_sourceless(archive, package)
            return path
        _zip_package(archive, package)
        if kind == "zip-in-text":
            inner = io.BytesIO()
            with zipfile.ZipFile(inner, "w") as notes:
                _zip_package(notes, SOLUTIONS_DIR, "solutions")
            archive.writestr(f"{PACKAGE}/notes.txt", inner.getvalue())
        if kind == "dotdot":
            archive.writestr(f"{PACKAGE}/../../escaped.py", b"print('escaped')\n")
        elif kind == "absolute":
            archive.writestr(ESCAPED_FILE, b"print('escaped')\n")
        elif kind == "symlink":
            info = zipfile.ZipInfo(f"{PACKAGE}/passwords.py")
            info.create_system = 3
            info.external_attr = (stat.S_IFLNK | 0o777) << 16
            archive.writestr(info, b"/etc/passwd")
        elif kind in ("bad-utf8-name", "cp437-name"):
            archive.writestr(f"{PACKAGE}/notes-\u00e9.txt", b"accents\n")
    if kind in ("bad-utf8-name", "cp437-name"):
        data = bytearray(path.read_bytes())
        name = f"{PACKAGE}/notes-\u00e9.txt".encode("utf-8")
        weird = f"{PACKAGE}/notes-\xff\xfe.txt".encode("latin-1")  # same length as the UTF-8 name
        assert len(weird) == len(name)
        data = data.replace(name, weird)
        # zipfile set the UTF-8 flag (bit 11) for the accented name: keep it for the bad
        # name, clear it for the code-page one (in the local and the central headers).
        for signature, offset in ((b"PK\x03\x04", 6), (b"PK\x01\x02", 8)):
            start = 0
            while (start := data.find(signature, start)) >= 0:
                flags = int.from_bytes(data[start + offset:start + offset + 2], "little")
                flags = flags | 0x800 if kind == "bad-utf8-name" else flags & ~0x800
                data[start + offset:start + offset + 2] = flags.to_bytes(2, "little")
                start += 4
        path.write_bytes(bytes(data))
    return path


LINK_LAYOUTS = ("exercises-link", "folder-link", "zip-link", "path-link")


def write_layout(case: HostileCase, folder: Path, params: dict[str, str] | None = None) -> Path:
    """The case's folder at ``folder`` (which must not exist); its path to grade.

    Kinds: ``exercises-link`` (a folder whose ``exercises`` is a symbolic link to
    ``@@REPO@@/solutions``), ``folder-link`` (a folder holding only ``friend``, a link to
    the sibling folder :data:`FRIEND_FOLDER`), ``zip-link`` (a folder holding only
    ``friend.zip``, a link to the sibling archive :data:`FRIEND_ZIP`), ``path-link`` (the
    case's path itself is a link to :data:`FRIEND_FOLDER`), ``sparse-file`` (the case's
    package plus ``exercises/data.bin``, a sparse file of :data:`SPARSE_BYTES`) and
    ``many-files`` (the package plus :data:`MANY_FILES` empty files in
    ``exercises/padding/``).  Links are relative where they point at a sibling, so the
    folder of cases can be moved.
    """
    params = {**default_params(), **(params or {})}
    kind = case.layout
    if kind == "path-link":
        folder.symlink_to(FRIEND_FOLDER, target_is_directory=True)
        return folder
    folder.mkdir()
    if kind == "exercises-link":
        (folder / PACKAGE).symlink_to(Path(params["REPO"]) / "solutions", target_is_directory=True)
    elif kind == "folder-link":
        (folder / "friend").symlink_to(Path("..") / FRIEND_FOLDER, target_is_directory=True)
    elif kind == "zip-link":
        (folder / "friend.zip").symlink_to(Path("..") / FRIEND_ZIP)
    elif kind in ("sparse-file", "many-files"):
        package = build_package(case, folder / PACKAGE, params)
        if kind == "sparse-file":
            with open(package / "data.bin", "wb") as handle:
                handle.truncate(SPARSE_BYTES)
        else:
            (package / "padding").mkdir()
            for n in range(MANY_FILES):
                (package / "padding" / f"f{n}.txt").touch()
    else:
        raise ValueError(f"case {case.name!r}: unknown layout {kind!r}")
    return folder


def build_case(case: HostileCase, out_dir: Path, params: dict[str, str] | None = None) -> Path:
    """Write the case into ``out_dir``: a folder holding ``exercises/``, a zip, or one of
    the folders of :func:`write_layout` (its path may be a symbolic link)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if case.layout:
        return write_layout(case, out_dir / case.name, params)
    if case.archive:
        staging = out_dir / f".{case.name}-package"
        build_package(case, staging, params)
        try:
            return write_archive(case, out_dir / case.file_name, staging)
        finally:
            shutil.rmtree(staging, ignore_errors=True)
    folder = out_dir / case.name
    folder.mkdir()
    build_package(case, folder / PACKAGE, params)
    return folder


def build_cases(out_dir: Path, params: dict[str, str] | None = None,
                cases: tuple[HostileCase, ...] = CASES) -> dict[str, Path]:
    """Every case written into ``out_dir``: ``{name: path}``."""
    return {case.name: build_case(case, out_dir, params) for case in cases}


# --------------------------------------------------------------------------- expected outcomes

def expectation(case: HostileCase, test_name: str) -> Expect | None:
    """The group of ``case.expect`` covering ``test_name`` (``"*"`` covers every test)."""
    for expect in case.expect:
        if test_name in expect.tests or "*" in expect.tests:
            return expect
    return None


def expected_score(case: HostileCase, tests) -> float:
    """The points the case's honest work earns on ``tests`` (TestSpec list): those of the
    tests its code does not touch, for a case built on the reference; nothing otherwise.
    Tests of a group with partial credit may add a share of their points on top."""
    if case.refused is not None or case.base != "reference":
        return 0.0
    return float(sum(t.points for t in tests if expectation(case, t.name) is None))


def problems(case: HostileCase, data: dict, tests) -> list[str]:
    """What is wrong with the graded ``results.json`` data of ``case`` (an empty list: nothing)."""
    found: list[str] = []
    state = (data.get("extra_data") or {}).get("state")
    if case.refused is not None:
        if state != "refused":
            found.append(f"expected the submission to be refused, it was {state}")
        for word in case.refused:
            if word.lower() not in data.get("output", "").lower():
                found.append(f"the refusal does not say {word!r}: {data.get('output')!r}")
        if data.get("score") != 0:
            found.append(f"a refused submission scored {data.get('score')}")
        return found
    if state != "graded":
        return [f"expected the submission to be graded, it was {state}: {data.get('output')!r}"]
    by_name = {(t.get("extra_data") or {}).get("test"): t for t in data["tests"]}
    ceiling = 0.0
    for test in tests:
        entry = by_name.get(test.name)
        if entry is None:
            found.append(f"{test.name}: missing from results.json")
            continue
        status = entry["extra_data"]["status"]
        expect = expectation(case, test.name)
        if expect is None:
            want = "passed" if case.base == "reference" else "not_implemented"
            if status != want:
                found.append(f"{test.name}: expected {want}, got {status}: {entry['output'][:300]!r}")
            ceiling += test.points if want == "passed" else 0.0
            continue
        if status not in expect.statuses:
            found.append(f"{test.name}: expected {' or '.join(expect.statuses)}, got {status}: "
                         f"{entry['output'][:300]!r}")
        for word in expect.words:
            if word.lower() not in entry["output"].lower():
                found.append(f"{test.name}: the output does not say {word!r}: {entry['output'][:400]!r}")
        if expect.partial:
            if entry["score"] >= test.points:
                found.append(f"{test.name}: full points for a test the case's code breaks")
            ceiling += entry["score"]
        elif entry["score"] != 0:
            found.append(f"{test.name}: scored {entry['score']} for a test the case's code breaks")
    if data.get("score", 0) > ceiling + 1e-9:
        found.append(f"score {data.get('score')} is above what the honest work earns ({ceiling:g})")
    if case.base == "reference" and abs(data.get("score", 0) - ceiling) > 1e-9:
        found.append(f"score {data.get('score')} differs from what the honest work earns ({ceiling:g})")
    return found


def table(cases: tuple[HostileCase, ...] = CASES, tests=None) -> str:
    """A Markdown table of the cases: name, what it does, expected outcome."""
    rows = ["| case | kind | what it does | expected outcome |", "|---|---|---|---|"]
    for case in cases:
        if case.refused is not None:
            outcome = f"refused, 0 points; the reason says {', '.join(map(repr, case.refused))}"
        else:
            groups = []
            for expect in case.expect:
                names = "every test" if "*" in expect.tests else ", ".join(sorted(expect.tests))
                words = f" saying {', '.join(map(repr, expect.words))}" if expect.words else ""
                partial = " (partial credit possible)" if expect.partial else ""
                groups.append(f"{names}: {'/'.join(expect.statuses)}{words}{partial}")
            other = "every other test" if case.expect else "every test"
            if "*" not in case.touched:
                groups.append(f"{other} passes" if case.base == "reference" else f"{other} not implemented")
            outcome = "; ".join(groups)
        if tests is not None and case.refused is None:
            outcome += f" (score {expected_score(case, tests):g})"
        rows.append(f"| {case.name} | {case.category} | {case.what} | {outcome} |")
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m grader.samples.hostile_cases", description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, required=True, help="folder to write the cases into")
    parser.add_argument("--grading-out", default="/nonexistent-output",
                        help="the --out folder of the grading (the cases that write there aim at it)")
    parser.add_argument("--sentinel", default="/nonexistent-sentinel", help="folder the hostile writes aim at")
    args = parser.parse_args(argv)
    paths = build_cases(args.out, {"OUT": args.grading_out, "SENTINEL": args.sentinel})
    from ..harness.run import load_spec  # deferred: pytest, heavy to import

    print(table(tests=load_spec()))
    print(f"\nwrote {len(paths)} cases to {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
