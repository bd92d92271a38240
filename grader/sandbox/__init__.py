"""Running student code: a worker process in a sandbox (bubblewrap, or plain limits where
bubblewrap cannot start), the JSON codec between them, the isolation decision, the
seccomp filter, the memory cage and the files a worker sees (``mounts``).  Ships to
students; imports nothing of the grader but :mod:`grader.errors`.  ``worker.py`` and
``codec.py`` run inside the sandbox, copied beside each other; nothing else of the
grader does (scenes are stepped in the trusted process, calling the student's functions
through the worker)."""
from .isolation import resolve_isolation
from .process import CallResult, Limits, Sandbox, SandboxBroken

__all__ = ["CallResult", "Limits", "Sandbox", "SandboxBroken", "resolve_isolation"]
