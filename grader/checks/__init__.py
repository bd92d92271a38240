"""Grader checks: one function per test, registered by name.

A check takes a :class:`~grader.student.StudentCode` and returns an
:class:`~grader.outcome.Outcome`.  Points, visibility and the exercise a test belongs
to come from the test spec (:mod:`grader.spec`), not from here.  Expected values are
computed here, in the trusted process, from the reference engine, pymunk and sympy.
"""
from __future__ import annotations

from typing import Callable

CHECKS: dict[str, Callable] = {}


def check(name: str):
    """Register the decorated function as the check called ``name``."""
    def register(function):
        if name in CHECKS:
            raise ValueError(f"two checks are called {name!r}")
        CHECKS[name] = function
        return function
    return register


def load_all() -> dict[str, Callable]:
    """Import every check module (they register themselves) and return the registry."""
    from . import contacts, grid, impulse, momentum, quadtree, sat  # noqa: F401
    return CHECKS
