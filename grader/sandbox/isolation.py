"""Which isolation student code runs in: bubblewrap when it works on this machine, else plain.

One decision per process, made here for every sandbox (:func:`decided_isolation`), so
``grader check``, ``grader grade``, a direct pytest run and Gradescope isolate alike:
:func:`choose_isolation` says what is installed; :func:`bwrap_works` tries a real
sandbox (bubblewrap may be installed but refused by the kernel or a container, as in
many Docker set-ups).  ``"auto"`` falls back to plain isolation with a warning, an
explicit ``"bwrap"`` fails.
"""
from __future__ import annotations

import functools
import os
import shutil
import subprocess
from typing import Callable

from ..errors import GradingError


def bwrap_available() -> bool:
    """True when bubblewrap can be used (installed, and the grader runs as root)."""
    return shutil.which("bwrap") is not None and shutil.which("setpriv") is not None and os.geteuid() == 0


def choose_isolation(requested: str = "auto") -> str:
    """``"bwrap"`` or ``"plain"``; ValueError if ``"bwrap"`` is asked for but missing."""
    if requested not in ("auto", "bwrap", "plain"):
        raise ValueError(f"isolation must be auto, bwrap or plain, got {requested!r}")
    if requested == "bwrap" and not bwrap_available():
        raise ValueError("bubblewrap isolation needs `bwrap` and `setpriv` installed and the grader run as root")
    if requested == "auto":
        return "bwrap" if bwrap_available() else "plain"
    return requested


def bwrap_works() -> bool:
    """True when bubblewrap can build the worker's sandbox here (it may be installed but
    refused by the kernel or a container, as in many Docker setups)."""
    command = ["bwrap", "--unshare-pid", "--unshare-net", "--unshare-ipc", "--unshare-uts", "--unshare-cgroup-try",
               "--die-with-parent", "--new-session", "--ro-bind", "/", "/", "--proc", "/proc", "--dev", "/dev",
               "--tmpfs", "/tmp", "--", "setpriv", "--reuid=61000", "--regid=61000", "--clear-groups",
               "--no-new-privs", "--bounding-set=-all", "--inh-caps=-all",
               # the worker's own user namespace, made by an unprivileged bubblewrap (grader.sandbox.process)
               "bwrap", "--unshare-user", "--uid", "61000", "--gid", "61000", "--bind", "/", "/", "--", "/bin/true"]
    try:
        return subprocess.run(command, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, timeout=20).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


@functools.cache
def decided_isolation(requested: str = "auto") -> str:
    """The isolation a sandbox asked for ``requested`` runs in, decided once per process.

    ``"auto"``: :func:`resolve_isolation`, its trial run included (it costs a bubblewrap
    start).  An explicit ``"bwrap"`` or ``"plain"`` was decided by the caller (a batch
    resolves it once and hands it to its grading workers): only what is installed is
    checked, never a second trial that a busy moment could fail."""
    if requested == "auto":
        return resolve_isolation(requested)
    try:
        return choose_isolation(requested)
    except ValueError as exc:
        raise GradingError(str(exc)) from None


def resolve_isolation(requested: str = "auto", warn: Callable[[str], None] | None = None) -> str:
    """``"bwrap"`` or ``"plain"``: :func:`choose_isolation`, then a trial run.

    ``"auto"`` falls back to ``"plain"`` (with a warning) when bubblewrap is installed
    but cannot start a sandbox; an explicit ``"bwrap"`` raises GradingError then.
    """
    try:
        chosen = choose_isolation(requested)
    except ValueError as exc:
        raise GradingError(str(exc)) from None
    if chosen == "bwrap" and not bwrap_works():
        if requested == "bwrap":
            raise GradingError("bubblewrap is installed but cannot create a sandbox on this machine "
                               "(no user or mount namespaces here?); use --isolation plain")
        if warn is not None:
            warn("warning: bubblewrap cannot create a sandbox here; grading with --isolation plain "
                 "(student code runs as this user and can read the grader's files)")
        return "plain"
    return chosen


def isolation_words(isolation: str) -> str:
    """How the student's code was isolated, said for the instructor."""
    return {"bwrap": "isolation: bubblewrap (a private file system, no network, an unprivileged user)",
            "plain": "isolation: plain, resource limits only (bubblewrap could not start here: the student's "
                     "code could read the grader's files that its user may read)"}.get(
        isolation, f"isolation: {isolation}")
