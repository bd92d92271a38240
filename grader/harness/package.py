"""Where the student's ``exercises`` package is: the one answer for ``grader check``, the
graded tests' fixtures, a batch and Gradescope.

A submission or course folder holds the package as ``exercises/`` (or is the package
folder itself, or holds one folder that holds ``exercises/``, as a zip of the course
folder unpacks).  Without a path, the student's own package is found from the
``GRADER_CHECK_PACKAGE`` variable, then the current folder and its parents, then the
checkout this grader sits in.
"""
from __future__ import annotations

import os
from pathlib import Path

PACKAGE_NAME = "exercises"
PACKAGE_VARIABLE = "GRADER_CHECK_PACKAGE"
#: The checkout (or course folder) this grader sits in.
COURSE_ROOT = Path(__file__).resolve().parents[2]


class PackageNotFound(FileNotFoundError):
    """No ``exercises`` package where one was looked for; the message says where and what to do."""


def package_folder(path: str | os.PathLike) -> Path:
    """The ``exercises`` package inside the folder ``path`` (or ``path`` itself)."""
    path = Path(path)
    for candidate in (path / PACKAGE_NAME, path):
        if (candidate / "__init__.py").is_file():
            return candidate
    nested = [p.parent for p in path.glob(f"*/{PACKAGE_NAME}/__init__.py")]
    if len(nested) == 1:
        return nested[0]
    raise PackageNotFound(f"no {PACKAGE_NAME} package (a folder '{PACKAGE_NAME}' with __init__.py) in {path}")


def find_package(package: str | os.PathLike | None = None) -> Path:
    """The student's package folder: ``package`` (absolute, or relative to the current
    folder or to the course folder), else as the module docstring says."""
    if package is None:
        package = os.environ.get(PACKAGE_VARIABLE) or None
    if package is not None:
        given = Path(package).expanduser()
        tries = [given] if given.is_absolute() else [Path.cwd() / given, COURSE_ROOT / given]
        for folder in tries:
            if folder.is_dir():
                try:
                    return package_folder(folder)
                except PackageNotFound:
                    raise PackageNotFound(f"{folder} holds no Python package: expected an '{PACKAGE_NAME}' folder "
                                          "with __init__.py, or a package folder itself") from None
        raise PackageNotFound(f"no folder {package} (looked in {' and '.join(str(t) for t in tries)})")
    cwd = Path.cwd()
    for folder in (cwd, *cwd.parents, COURSE_ROOT):
        if (folder / PACKAGE_NAME / "__init__.py").is_file():
            return folder / PACKAGE_NAME
    raise PackageNotFound(f"no {PACKAGE_NAME} package found: run this from your course folder (the one holding "
                          f"{PACKAGE_NAME}/), pass package=... (--package PATH), or set {PACKAGE_VARIABLE}")
