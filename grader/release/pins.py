"""Which pinned distributions provide the modules a shipped folder imports.

The repository's ``pyproject.toml`` pins every distribution it uses (its dependencies
and extras).  What ships (the student edition, Gradescope's archive) installs the pins
of the distributions that provide the modules its code imports, found through the
installed packages' metadata (``numba`` -> numba, ``Box2D`` -> box2d), and, for an
image built once, what those pins pulled in here, at the versions tested here.
"""
from __future__ import annotations

import re
import tomllib
from importlib import metadata
from pathlib import Path


class PinError(RuntimeError):
    """A module is imported that no pin of ``pyproject.toml`` provides."""


def normal_name(name: str) -> str:
    """A distribution name as PEP 503 compares them (``Foo_bar`` -> ``foo-bar``)."""
    return re.sub(r"[-_.]+", "-", name).lower()


def requirement_name(requirement: str) -> str:
    """The distribution a requirement string names, normalised."""
    return normal_name(re.split(r"[\s\[<>=!~;]", requirement.strip(), maxsplit=1)[0])


def project_pins(pyproject: Path) -> dict[str, str]:
    """{distribution: requirement} of every pin of ``pyproject.toml`` (dependencies, then
    the extras in their order)."""
    project = tomllib.loads(Path(pyproject).read_text(encoding="utf-8"))["project"]
    pins: dict[str, str] = {}
    for requirement in [*project.get("dependencies", []),
                        *(r for extra in project.get("optional-dependencies", {}).values() for r in extra)]:
        pins.setdefault(requirement_name(requirement), requirement)
    return pins


def installed_closure(requirements: list[str]) -> set[str]:
    """The distributions ``requirements`` bring, as installed here (names normalised);
    a requirement that applies only elsewhere (an extra, another Python) is not installed
    here and is left out."""
    seen: set[str] = set()
    stack = [requirement_name(r) for r in requirements]
    while stack:
        name = stack.pop()
        if name in seen:
            continue
        try:
            requires = metadata.requires(name) or []
        except metadata.PackageNotFoundError:
            continue
        seen.add(name)
        stack += [requirement_name(r) for r in requires if "extra ==" not in r.replace('"', "").replace("'", "")]
    return seen


def pins_for_modules(modules: dict[str, str], pyproject: Path) -> list[str]:
    """The pins of ``pyproject.toml`` whose distributions provide ``modules`` ({top-level
    module: the file importing it}), in the order of pyproject.toml.  PinError names a
    module that is not installed here or that no pin provides."""
    provided = metadata.packages_distributions()
    pins = project_pins(pyproject)
    wanted: set[str] = set()
    for module, where in sorted(modules.items()):
        distributions = [normal_name(d) for d in provided.get(module, [])]
        if not distributions:
            raise PinError(f"{where} imports {module}, which is not installed here")
        pinned = [d for d in distributions if d in pins]
        if not pinned:
            raise PinError(f"{where} imports {module} ({', '.join(distributions)}), which no pin of "
                           f"{Path(pyproject).name} provides: pin it there")
        wanted.update(pinned)
    return [requirement for name, requirement in pins.items() if name in wanted]


def locked(requirements: list[str]) -> list[str]:
    """``name==version`` of every distribution ``requirements`` pulled in here that they
    do not pin themselves, sorted: the versions the grader was tested with."""
    own = {requirement_name(r) for r in requirements}
    return [f"{name}=={metadata.version(name)}" for name in sorted(installed_closure(requirements) - own)]
