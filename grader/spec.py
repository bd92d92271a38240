"""The test spec: which tests exist, their points, exercise and visibility.

One spec drives everything: ``grader check`` runs the visible tests of an exercise,
``grader grade`` runs all of them and scores them, and the Gradescope results carry
each test's visibility.  Public tests are in ``spec/public.toml``; hidden ones in
``spec/hidden.toml``, which the student worker can never read (the sandbox does not
mount it) and which an instructor leaves out of anything given to students.
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path

from .checks import load_all

SPEC_DIR = Path(__file__).resolve().parent / "spec"
PUBLIC_SPEC = SPEC_DIR / "public.toml"
HIDDEN_SPEC = SPEC_DIR / "hidden.toml"
VISIBILITIES = ("visible", "hidden", "after_due_date", "after_published")
EXERCISES = ("momentum", "grid", "quadtree", "sat", "contacts", "impulse")


class SpecError(ValueError):
    """The spec file is wrong; the message names the file and the test."""


@dataclass(frozen=True)
class TestSpec:
    """One test: ``name`` is also the check's registered name."""

    name: str
    exercise: str
    title: str
    points: float
    visibility: str
    leaderboard: str | None = None
    #: When true a failed test earns the share of its cases that were right.
    partial_credit: bool = False

    @property
    def public(self) -> bool:
        return self.visibility == "visible"


def load_spec(paths: list[Path] | None = None) -> list[TestSpec]:
    """Every test of the given spec files (default: public, then hidden if present)."""
    if paths is None:
        paths = [PUBLIC_SPEC] + ([HIDDEN_SPEC] if HIDDEN_SPEC.exists() else [])
    checks = load_all()
    tests: list[TestSpec] = []
    seen: set[str] = set()
    for path in paths:
        try:
            data = tomllib.loads(Path(path).read_text(encoding="utf-8"))
        except (OSError, tomllib.TOMLDecodeError) as exc:
            raise SpecError(f"{path}: cannot read the test spec: {exc}") from exc
        for number, entry in enumerate(data.get("test", []), start=1):
            where = f"{path}, test {number} ({entry.get('name', '?')})"
            unknown = set(entry) - {"name", "exercise", "title", "points", "visibility", "leaderboard", "partial_credit"}
            if unknown:
                raise SpecError(f"{where}: unknown keys {sorted(unknown)}")
            try:
                test = TestSpec(name=str(entry["name"]), exercise=str(entry["exercise"]),
                                title=str(entry.get("title", entry["name"])), points=float(entry["points"]),
                                visibility=str(entry.get("visibility", "visible")), leaderboard=entry.get("leaderboard"),
                                partial_credit=bool(entry.get("partial_credit", False)))
            except KeyError as exc:
                raise SpecError(f"{where}: missing key {exc}") from None
            except (TypeError, ValueError) as exc:
                raise SpecError(f"{where}: {exc}") from None
            if test.name in seen:
                raise SpecError(f"{where}: a test called {test.name!r} is already defined")
            if test.name not in checks:
                raise SpecError(f"{where}: no check called {test.name!r} in grader/checks")
            if test.exercise not in EXERCISES:
                raise SpecError(f"{where}: exercise must be one of {EXERCISES}, got {test.exercise!r}")
            if test.visibility not in VISIBILITIES:
                raise SpecError(f"{where}: visibility must be one of {VISIBILITIES}, got {test.visibility!r}")
            if not test.points >= 0:
                raise SpecError(f"{where}: points must be >= 0, got {test.points}")
            seen.add(test.name)
            tests.append(test)
    return tests
