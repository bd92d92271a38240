"""A memory cgroup around one sandbox: a cap on the total memory of every process the
student's code starts, tmpfs pages included.

The address-space limit (RLIMIT_AS) caps each process; a submission that forks its
process allowance of memory hogs, or fills a tmpfs, would still take the machine's
memory.  A cage is a cgroup of the memory controller (cgroup v2 when its memory
controller is enabled, else v1) made for one sandbox, under the grader's own cgroup
when it can be written, with ``limit`` bytes; the worker joins it between fork and exec
(:meth:`MemoryCage.join`, children follow), and the kernel's OOM killer stops the cage
alone when it is over.  Without a writable cgroup file system (not root, read-only
mount) :func:`MemoryCage.create` returns None and the sandbox keeps the per-process
limits only.
"""
from __future__ import annotations

import os
import secrets
import signal
import time
from pathlib import Path

CGROUP_ROOT = Path("/sys/fs/cgroup")


def _own_path(controller: str) -> str:
    """This process's cgroup path in the v1 hierarchy of ``controller`` ("" for v2)."""
    try:
        for line in Path("/proc/self/cgroup").read_text().splitlines():
            number, controllers, path = line.split(":", 2)
            if controller in controllers.split(",") or (controller == "" and number == "0"):
                return path.lstrip("/")
    except OSError:
        pass
    return ""


def _candidates() -> list[tuple[Path, str]]:
    """(parent folder, version) where a cage may be made, best first."""
    out = []
    unified = CGROUP_ROOT / "unified" if (CGROUP_ROOT / "unified").is_dir() else CGROUP_ROOT
    controllers = unified / "cgroup.controllers"
    if controllers.is_file() and "memory" in controllers.read_text().split():
        own = unified / _own_path("")
        out += [(own, "v2"), (unified, "v2")]
    v1 = CGROUP_ROOT / "memory"
    if (v1 / "memory.limit_in_bytes").is_file():
        own = v1 / _own_path("memory")
        out += [(own, "v1"), (v1, "v1")]
    return out


class MemoryCage:
    """One memory cgroup; ``limit`` in bytes."""

    def __init__(self, path: Path, version: str, limit: int):
        self.path = path
        self.version = version
        self.limit = limit

    @classmethod
    def create(cls, limit: int, label: str = "grader") -> "MemoryCage | None":
        """A new cage, or None when no cgroup can be made here."""
        for parent, version in _candidates():
            if not parent.is_dir():
                continue
            path = parent / f"{label}-{os.getpid()}-{secrets.token_hex(4)}"
            try:
                path.mkdir()
            except OSError:
                continue
            try:
                if version == "v2":
                    (path / "memory.max").write_text(str(limit))
                    (path / "memory.swap.max").write_text("0") if (path / "memory.swap.max").exists() else None
                else:
                    (path / "memory.limit_in_bytes").write_text(str(limit))
                return cls(path, version, limit)
            except OSError:
                try:
                    path.rmdir()
                except OSError:
                    pass
        return None

    def join(self) -> None:
        """Move the calling process into the cage (between fork and exec)."""
        (self.path / "cgroup.procs").write_text(str(os.getpid()))

    def pids(self) -> list[int]:
        try:
            return [int(p) for p in (self.path / "cgroup.procs").read_text().split()]
        except OSError:
            return []

    def out_of_memory(self) -> bool:
        """True when the kernel had to kill or refuse in the cage for lack of memory."""
        try:
            if self.version == "v2":
                events = dict(line.split() for line in (self.path / "memory.events").read_text().splitlines())
                return int(events.get("oom_kill", 0)) > 0 or int(events.get("max", 0)) > 0
            return int((self.path / "memory.failcnt").read_text()) > 0
        except (OSError, ValueError):
            return False

    def close(self) -> None:
        """Kill what is left in the cage and remove it."""
        for _ in range(50):
            pids = self.pids()
            if not pids:
                break
            for pid in pids:
                try:
                    os.kill(pid, signal.SIGKILL)
                except OSError:
                    pass
            time.sleep(0.02)
        try:
            self.path.rmdir()
        except OSError:
            pass
