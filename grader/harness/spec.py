"""The graded tests: which exist, their points, exercise and visibility.

Graded tests are pytest functions (:mod:`grader.harness.plugin`); their points, visibility,
title and partial-credit rule are pytest markers, so the test modules are the one
source.  :func:`grader.harness.run.load_spec` collects them (without running anything) into
:class:`TestSpec` records: ``grader check`` runs the visible ones of an exercise,
``grader grade`` runs them all and scores them, the Gradescope results carry each
test's visibility.  Public tests live in ``grader/tests/public``, which students hold;
hidden ones in ``grader/tests/hidden``, which never leaves the instructor's side.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

VISIBILITIES = ("visible", "hidden", "after_due_date", "after_published")
#: The exercises in the order the book teaches them (its chapters 3, 4 (the dynamic tree), 6, 7,
#: 8, 9 and 11): ``grader check`` lists them in this order.
EXERCISES = ("grid", "quadtree", "dynamic_tree", "sat", "contacts", "momentum", "impulse", "sequential")
#: Where the graded tests are: public (students hold them) and hidden (the instructor's).
TESTS_DIR = Path(__file__).resolve().parents[1] / "tests"
PUBLIC_TESTS = TESTS_DIR / "public"
HIDDEN_TESTS = TESTS_DIR / "hidden"


class SpecError(ValueError):
    """A graded test is declared wrongly; the message names the test."""


@dataclass(frozen=True)
class TestSpec:
    """One graded test: ``name`` is ``<exercise>.<function without test_>``."""

    name: str
    exercise: str
    title: str
    points: float
    visibility: str
    leaderboard: str | None = None
    #: When true a failed test earns points for a high share of right cases (grader.harness.credit).
    partial_credit: bool = False
    #: pytest's node id and the module's path, to run this test alone.
    nodeid: str = ""
    path: str = ""

    @property
    def public(self) -> bool:
        return self.visibility == "visible"


def graded_test_folders() -> list[Path]:
    """The folders of graded tests here: public, then hidden when present."""
    return [folder for folder in (PUBLIC_TESTS, HIDDEN_TESTS) if folder.is_dir()]
