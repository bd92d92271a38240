"""Compiled machine code is forgotten when a module it was compiled from changes.

Oracle: numba itself, run in fresh processes on a small package written for the test:
a compiled function reading a constant from a sibling module, with and without
:func:`solutions.compiled_cache.forget_stale_machine_code`.
"""
import os
import subprocess
import sys
from pathlib import Path

from solutions.compiled_cache import source_files

REPO = Path(__file__).resolve().parents[1]

TWIN = '''
from numba import njit

from .constants import SCALE
{forget_import}

@njit(cache=True)
def scaled(x):
    return x * SCALE

{forget_call}
'''


def run(package_parent: Path, module: str) -> tuple[float, int]:
    """``scaled(2.0)`` in a fresh process, and how many signatures came from the cache."""
    code = f"import {module} as m; print(m.scaled(2.0), len(m.scaled.stats.cache_hits))"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(package_parent), str(REPO)])}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True,
                         timeout=120).stdout.split()
    return float(out[0]), int(out[1])


def write_package(root: Path, scale: float) -> None:
    package = root / "twinpkg"
    package.mkdir(exist_ok=True)
    (package / "__init__.py").write_text("")
    (package / "constants.py").write_text(f"SCALE = {scale}\n")
    (package / "guarded.py").write_text(TWIN.format(
        forget_import="from solutions.compiled_cache import forget_stale_machine_code",
        forget_call="forget_stale_machine_code(globals())"))
    (package / "unguarded.py").write_text(TWIN.format(forget_import="", forget_call=""))


def test_a_cached_function_is_compiled_again_when_a_module_it_reads_changes(tmp_path):
    write_package(tmp_path, 1.0)
    assert run(tmp_path, "twinpkg.guarded") == (2.0, 0)      # compiled and cached
    assert run(tmp_path, "twinpkg.unguarded") == (2.0, 0)
    assert run(tmp_path, "twinpkg.guarded") == (2.0, 1)      # loaded from the cache
    write_package(tmp_path, 3.0)                            # only constants.py changes
    assert run(tmp_path, "twinpkg.guarded") == (6.0, 0)      # forgotten, compiled again
    assert run(tmp_path, "twinpkg.guarded") == (6.0, 1)      # and cached again
    # numba alone keeps the stale machine code (the reason for the guard):
    assert run(tmp_path, "twinpkg.unguarded") == (2.0, 1)


def test_the_sources_of_the_compiled_soft_step_are_its_package_imports():
    import solutions.response.soft_step_numba as soft_step_numba

    solutions = REPO / "solutions"
    files = {path.relative_to(solutions).as_posix() for path in source_files(soft_step_numba.__file__)}
    assert {"response/soft_step_numba.py", "narrowphase/box_pairs_numba.py", "solver/kernel_numba.py",
            "broadphase/grid_numba.py", "shapes.py", "narrowphase/polygon_polygon.py"} <= files
    assert "world.py" not in files and "scenes.py" not in files          # not imported by it
    assert all((solutions / file).is_file() for file in files)
    kernel = {path.name for path in source_files(solutions / "solver" / "kernel_numba.py")}
    assert "box_pairs_numba.py" not in kernel and "kernel_numba.py" in kernel


def test_every_compiled_module_forgets_stale_machine_code():
    for path in (REPO / "solutions").rglob("*.py"):
        text = path.read_text()
        if "\n@njit(cache=True" in text:
            assert text.rstrip().endswith("forget_stale_machine_code(globals())"), path


def test_a_module_without_cached_functions_has_nothing_to_forget():
    from numba import njit

    from solutions.compiled_cache import forget_stale_machine_code

    def twice(x):
        return 2 * x

    module = {"__name__": __name__, "__file__": __file__, "twice": njit(cache=False)(twice)}
    assert forget_stale_machine_code(module) is False
    assert forget_stale_machine_code({"__name__": __name__, "__file__": __file__}) is False


def test_a_cache_that_cannot_be_emptied_is_not_read(tmp_path, monkeypatch):
    import importlib

    from solutions.compiled_cache import forget_stale_machine_code

    write_package(tmp_path, 1.0)
    monkeypatch.syspath_prepend(str(tmp_path))
    module = importlib.import_module("twinpkg.guarded")
    cache = module.scaled._cache
    assert cache._enabled and forget_stale_machine_code(vars(module)) is False     # stamp written at import

    def refuse():
        raise PermissionError("read-only cache")

    monkeypatch.setattr(cache, "flush", refuse)
    (tmp_path / "twinpkg" / "constants.py").write_text("SCALE = 3.0\n")
    assert forget_stale_machine_code(vars(module)) is True
    assert not cache._enabled
