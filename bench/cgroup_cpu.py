"""Processor time of a command and of everything it starts, sandboxes included.

``getrusage(RUSAGE_CHILDREN)`` counts only the descendants that were waited for, by a
parent that was itself waited for: a bubblewrap sandbox killed with SIGKILL (how the
grader ends one) never waits for its own worker, and its worker runs in another process
namespace, so the student's code -- most of a submission's processor time -- is missed.
A control group counts every process started inside it, whatever becomes of it.

:class:`CpuMeter` makes a cgroup of its own for each measurement, best first:

- ``cgroup v1 cpuacct``: ``/sys/fs/cgroup/cpuacct/<name>``, ``cpuacct.usage``
  (nanoseconds).  Preferred where it exists: the grader's memory cages
  (:mod:`grader.sandbox.memory_cage`) move sandboxes between cgroups of the *memory*
  hierarchy only, so every sandbox stays in the meter's cgroup;
- ``cgroup v2``: ``/sys/fs/cgroup/<name>`` (or ``/sys/fs/cgroup/unified/<name>``),
  ``cpu.stat`` ``usage_usec`` (microseconds).  A memory cage made under the grader's own
  cgroup is a child of the meter's and counts too; one the kernel would only let the
  grader make at the root would not;
- ``getrusage``: the command and the descendants waited for, sandboxes not included
  (said in :attr:`CpuMeter.method`), where no cgroup can be made (not root, read-only
  ``/sys/fs/cgroup``).
"""
from __future__ import annotations

import os
import resource
import secrets
import subprocess
from pathlib import Path

CGROUP_ROOT = Path("/sys/fs/cgroup")


def _own_group(kind: str) -> str:
    """This process's cgroup path (relative) in the v1 cpuacct or the v2 hierarchy."""
    try:
        for line in Path("/proc/self/cgroup").read_text().splitlines():
            number, controllers, path = line.split(":", 2)
            if (kind == "v1" and "cpuacct" in controllers.split(",")) or (kind == "v2" and number == "0"):
                return path.lstrip("/")
    except (OSError, ValueError):
        pass
    return ""


def _v2_root() -> Path | None:
    """The mount point of the unified (v2) hierarchy, if any."""
    for root in (CGROUP_ROOT / "unified", CGROUP_ROOT):
        if (root / "cgroup.procs").is_file() and (root / "cgroup.controllers").is_file():
            return root
    return None


class CpuMeter:
    """Measures the processor seconds of commands run through :meth:`run`, or of a block
    of this process (:meth:`enter`, :meth:`seconds`)."""

    def __init__(self, label: str = "bench-grading"):
        self.label = label
        self.kind = "getrusage"
        self.parent: Path | None = None
        self.own: Path | None = None   # the group this process joined (enter)
        v1 = CGROUP_ROOT / "cpuacct"
        candidates = []
        if (v1 / "cpuacct.usage").is_file():
            candidates.append(("v1", v1))
        v2 = _v2_root()
        if v2 is not None:
            candidates.append(("v2", v2))
        for kind, root in candidates:
            path = root / f"{label}-{os.getpid()}-{secrets.token_hex(3)}"
            try:
                path.mkdir()
            except OSError:
                continue
            if self._usage(kind, path) is None:
                path.rmdir()
                continue
            self.kind, self.parent = kind, path
            self.home = root / _own_group(kind)   # where close() puts this process back
            break

    @property
    def method(self) -> str:
        """How the figures are measured, in words."""
        if self.kind == "v1":
            return f"cgroup v1 cpuacct ({self.parent.parent}): every process, sandboxes included"
        if self.kind == "v2":
            return f"cgroup v2 cpu.stat ({self.parent.parent}): every process, sandboxes included"
        return ("getrusage (no cgroup could be made here): the processes waited for only, NOT the sandboxed "
                "workers, which a cgroup would count")

    @staticmethod
    def _usage(kind: str, path: Path) -> float | None:
        try:
            if kind == "v1":
                return int((path / "cpuacct.usage").read_text()) / 1e9
            for line in (path / "cpu.stat").read_text().splitlines():
                name, _, value = line.partition(" ")
                if name == "usage_usec":
                    return int(value) / 1e6
        except (OSError, ValueError):
            pass
        return None

    def _child(self) -> Path:
        path = self.parent / f"run-{secrets.token_hex(3)}"
        path.mkdir()
        return path

    def run(self, command: list[str], **kwargs) -> float:
        """Run ``command`` (``subprocess.run`` keyword arguments, ``check=True``); its
        processor seconds and those of every process it started."""
        if self.parent is None:
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            subprocess.run(command, check=True, **kwargs)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            return (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
        group = self._child()
        procs = str(group / "cgroup.procs")

        def join() -> None:  # in the child, before exec: all it starts stays in the group
            with open(procs, "w") as handle:
                handle.write(str(os.getpid()))

        try:
            subprocess.run(command, check=True, preexec_fn=join, **kwargs)
            return self._usage(self.kind, group)
        finally:
            _remove(group)

    def enter(self) -> None:
        """Move this process (and what it starts from now on) into a cgroup of its own."""
        if self.parent is not None and self.own is None:
            self.own = self._child()
            (self.own / "cgroup.procs").write_text(str(os.getpid()))

    def seconds(self) -> float | None:
        """Processor seconds of this process and what it started since :meth:`enter`;
        None without a cgroup."""
        return None if self.own is None else self._usage(self.kind, self.own)

    def close(self) -> None:
        """Remove the cgroups (this process leaves them first)."""
        if self.parent is None:
            return
        if self.own is not None:
            try:
                (self.home / "cgroup.procs").write_text(str(os.getpid()))
            except OSError:
                pass
        _remove(self.parent)
        self.parent = self.own = None


def _remove(group: Path) -> None:
    """Remove an emptied cgroup (its children first); a group still holding processes stays."""
    for child in [p for p in group.iterdir() if p.is_dir()] if group.is_dir() else []:
        _remove(child)
    try:
        group.rmdir()
    except OSError:
        pass
