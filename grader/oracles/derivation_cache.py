"""What a slow, pure derivation returns, kept on disk once per version of its source.

:func:`grader.oracles.impulse_sympy.derived` has sympy solve the impulse-momentum
equations: about 3 s of CPU in every process that grades an impulse test (each grading
worker, each ``grader check``, each kernel of a chapter that checks one).  Its result
depends on nothing but the module's text and the versions of Python and sympy, so it is
pickled beside the module, as Python keeps bytecode and numba machine code:
``__pycache__/<module>.<name>.<key>.pickle`` with ``key`` a hash of the module's bytes
and those versions.  Editing the module derives again; a file that cannot be read or
unpickled is derived again; a folder that cannot be written (a read-only sandbox) only
costs the derivation.
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import pickle
import sys
from pathlib import Path
from typing import Callable, TypeVar

T = TypeVar("T")


def sympy_versions() -> tuple[str, str]:
    """What a sympy derivation depends on besides its module's text: the versions of Python and sympy."""
    import sympy

    return sys.version, sympy.__version__


def cache_path(module_file: str | os.PathLike, name: str, versions: tuple[str, ...]) -> Path:
    """Where ``name`` derived by ``module_file`` is kept: the key changes with the module's bytes or ``versions``."""
    source = Path(module_file)
    digest = hashlib.sha256(source.read_bytes())
    digest.update(repr(versions).encode())
    return source.parent / "__pycache__" / f"{source.stem}.{name}.{digest.hexdigest()[:16]}.pickle"


def cached(module_file: str | os.PathLike, name: str, derive: Callable[[], T], versions: tuple[str, ...]) -> T:
    """``derive()``, read from its file when one was kept for this version, else derived and kept."""
    path = cache_path(module_file, name, versions)
    try:
        with open(path, "rb") as handle:
            return pickle.load(handle)
    except Exception:   # absent, unreadable, truncated or from another library: derive it again
        pass
    value = derive()
    temporary = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    try:
        path.parent.mkdir(exist_ok=True)
        with open(temporary, "wb") as handle:
            pickle.dump(value, handle, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(temporary, path)       # whole or not at all, whoever reads it meanwhile
        for stale in path.parent.glob(f"{Path(module_file).stem}.{name}.*.pickle"):
            if stale != path:
                stale.unlink(missing_ok=True)
    except OSError:     # a read-only folder: derived again next time
        with contextlib.suppress(OSError):
            temporary.unlink(missing_ok=True)
    return value
