"""Compiled machine code kept between runs, and forgotten when what it was made from changes.

``@njit(cache=True)`` keeps each compiled function's machine code in ``__pycache__`` and
reuses it while the function's own source file keeps its modification time and size.
numba does not look at the other modules the function was compiled from: the compiled
functions it calls (whose machine code is copied in) and the constants it reads (which
are frozen into it).  After an update that changes only ``box_pairs_numba.py`` or a
tolerance in ``shapes.py``, the cached soft step would go on running the old code, and
the compiled twin would no longer equal the readable step.

:func:`forget_stale_machine_code`, called at the end of each compiled module, closes
that gap: it hashes the module's source together with every module of its package that
it imports, directly or not, and when the hash differs from the one stored beside the
cache it empties the module's cache index, so that each function is compiled again on
its first call.
"""
from __future__ import annotations

### INSTRUCTOR ONLY: not in the student edition (it serves the compiled twins).

import ast
import functools
import hashlib
from pathlib import Path

from numba.core.dispatcher import Dispatcher


def package_root(module_file: str | Path) -> Path:
    """The directory of the top-level package holding ``module_file``."""
    root = Path(module_file).resolve().parent
    while (root.parent / "__init__.py").exists():
        root = root.parent
    return root


@functools.cache
def _imported_files(path: Path, root: Path) -> tuple[Path, ...]:
    """Files of the package at ``root`` that the module at ``path`` imports (anywhere in it)."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(node, ast.ImportFrom):
            continue
        if node.level:
            base = path.parent
            for _ in range(node.level - 1):
                base = base.parent
        elif node.module and node.module.split(".")[0] == root.name:
            base = root.parent
        else:
            continue
        module = base.joinpath(*(node.module or "").split(".")) if node.module else base
        # ``from .x import y`` names a module x, or a package x; ``from . import y`` modules y.
        targets = [module.with_suffix(".py"), module / "__init__.py"] if node.module else []
        targets += [module / f"{alias.name}.py" for alias in node.names]
        found += [target.resolve() for target in targets if target.is_file()]
    return tuple(file for file in found if file.is_relative_to(root))


def source_files(module_file: str | Path) -> list[Path]:
    """``module_file`` and every file of its package it imports, directly or not, sorted."""
    root = package_root(module_file)
    seen: set[Path] = set()
    todo = [Path(module_file).resolve()]
    while todo:
        path = todo.pop()
        if path not in seen:
            seen.add(path)
            todo.extend(_imported_files(path, root))
    return sorted(seen)


def sources_digest(module_file: str | Path) -> str:
    """SHA-256 of the names (relative to the package) and contents of :func:`source_files`."""
    root = package_root(module_file).parent
    digest = hashlib.sha256()
    for path in source_files(module_file):
        digest.update(path.relative_to(root).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def forget_stale_machine_code(module_globals: dict) -> bool:
    """Empty the cache index of every cached compiled function defined in the module of
    ``module_globals`` (pass ``globals()``) if its sources changed since the last call;
    returns whether it did.  The digest is kept in ``<module>.sources`` in numba's cache
    directory for the module (numba only caches where it can write)."""
    name, file = module_globals["__name__"], module_globals["__file__"]
    caches = [value._cache for value in module_globals.values()
              if isinstance(value, Dispatcher) and value.py_func.__module__ == name
              and getattr(value._cache, "cache_path", None)]       # (None: not cached)
    if not caches:
        return False
    stamp = Path(caches[0].cache_path) / f"{Path(file).stem}.sources"
    digest = sources_digest(file)
    try:
        if stamp.read_text(encoding="ascii") == digest:
            return False
    except OSError:
        pass
    try:
        for cache in caches:
            cache.flush()
        stamp.parent.mkdir(parents=True, exist_ok=True)
        stamp.write_text(digest, encoding="ascii")
    except OSError:         # a cache that cannot be emptied is not read either
        for cache in caches:
            cache.disable()
    return True
