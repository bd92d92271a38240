"""Run student code in a separate, limited worker process and talk to it in JSON.

Isolation, strongest available first:

- ``"bwrap"`` (used when bubblewrap is installed and the grader runs as root, as it
  does in CI and on Gradescope): the worker sees a private file system holding only
  the system and Python folders (read-only), its own copy of the submission at
  ``/sandbox`` and an empty ``/tmp``; no network, its own process namespace (every
  process it leaves behind dies with it), and it runs as an unprivileged user of its
  own (one uid per parallel job) with no capabilities.
- ``"plain"``: the same worker with the same CPU, memory and file limits but the
  host's file system (for machines without bubblewrap).  Run as root, and when Python
  is installed where any user can run it, the worker still drops to its own
  unprivileged user (with the process limit); the reference solutions are then as
  hidden as their file permissions make them (the Gradescope runner makes them
  readable by root only).  Otherwise it runs as the grader's user, without the
  process limit, which would count every process of that user.

Both apply resource limits (CPU seconds, address space, file size, processes, no core
files) and a wall-clock timeout per call.  Only JSON crosses: requests on the worker's
standard input, responses on a pipe whose descriptor is its first argument; its standard output is discarded
(printed text is captured per call by the worker and returned, capped).  The parent
measures elapsed time itself.  A crash, hang or exception costs that call only: the
worker is restarted for the next one.
"""
from __future__ import annotations

import json
import os
import resource
import selectors
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
WORKER_FILES = ("worker.py", "codec.py", "scene_driver.py")
SANDBOX_MOUNT = "/sandbox"
#: First uid of the unprivileged users the workers run as (one per parallel slot).
SANDBOX_UID_BASE = 61000
RESPONSE_LIMIT = 64 * 1024 * 1024  # bytes of one JSON response
STDERR_KEPT = 8_000  # characters of the worker's stderr kept for messages


@dataclass(frozen=True)
class Limits:
    """Resource limits of one worker process.

    Attributes
    ----------
    call_timeout : float
        Wall-clock seconds one call may take before the worker is killed.
    cpu_seconds : int
        CPU seconds for the whole worker process (RLIMIT_CPU).
    memory_bytes : int
        Address space (RLIMIT_AS).
    file_bytes : int
        Largest file the worker may write (RLIMIT_FSIZE).
    processes : int
        Processes and threads of the worker's user (RLIMIT_NPROC).
    """

    call_timeout: float = 10.0
    cpu_seconds: int = 300
    memory_bytes: int = 2 * 1024**3
    file_bytes: int = 16 * 1024**2
    processes: int = 64


@dataclass
class CallResult:
    """What one call returned.

    ``status``: ``ok``, ``not_implemented``, ``import_error``, ``missing``, ``error``,
    ``unreadable`` (from the worker) or ``timeout``, ``crashed`` (seen by the parent).
    ``elapsed`` is the parent's wall-clock time of the round trip (s).
    """

    status: str
    value: Any = None
    message: str = ""
    output: str = ""
    elapsed: float = 0.0
    args_after: list = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.status == "ok"


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


def python_folders() -> list[str]:
    """Folders the worker's Python needs, read-only: its prefixes and the real binary."""
    folders = {sys.base_prefix, sys.prefix, str(Path(os.path.realpath(sys.executable)).parent.parent)}
    return sorted(f for f in folders if f and os.path.isdir(f))


def _running(pid: str) -> bool:
    """True while process ``pid`` exists and is not a zombie."""
    try:
        with open(f"/proc/{pid}/stat") as handle:
            return handle.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def python_usable_by_anyone() -> bool:
    """True when an unprivileged user can run this Python and read its libraries."""
    paths = [Path(os.path.realpath(sys.executable)), *map(Path, python_folders())]
    for path in paths:
        for part in [path, *path.parents]:
            try:
                mode = part.stat().st_mode
            except OSError:
                return False
            if part.is_dir() and not mode & stat.S_IXOTH:
                return False
        if not path.stat().st_mode & stat.S_IROTH:
            return False
    return True


def copy_package(source: Path, destination: Path) -> None:
    """Copy the regular files of a package folder; symlinks and special files are skipped."""
    destination.mkdir(parents=True, exist_ok=True)
    for entry in os.scandir(source):
        if entry.is_symlink():
            continue
        target = destination / entry.name
        if entry.is_dir(follow_symlinks=False):
            if entry.name != "__pycache__":
                copy_package(Path(entry.path), target)
        elif entry.is_file(follow_symlinks=False):
            shutil.copyfile(entry.path, target)


class Sandbox:
    """A worker process running a student's ``exercises`` package.

    Parameters
    ----------
    package_dir : Path
        The student's ``exercises`` folder (it is copied; the original is never touched).
    limits : Limits
    slot : int
        Parallel job number; each slot runs as its own unprivileged user.
    isolation : str
        ``"auto"``, ``"bwrap"`` or ``"plain"`` (see the module docstring).
    """

    def __init__(self, package_dir: Path, limits: Limits = Limits(), slot: int = 0, isolation: str = "auto"):
        self.package_dir = Path(package_dir)
        self.limits = limits
        self.slot = slot
        self.isolation = choose_isolation(isolation)
        # A user of its own: the process limit then counts this sandbox alone.
        can_switch = os.geteuid() == 0 and (self.isolation == "bwrap" or python_usable_by_anyone())
        self.uid = SANDBOX_UID_BASE + slot if can_switch else None
        self.workdir: Path | None = None
        self.process: subprocess.Popen | None = None
        self._responses = None
        self._stderr: list[str] = []
        self._next_id = 0
        self.restarts = 0

    # Life cycle -----------------------------------------------------------------
    def __enter__(self) -> "Sandbox":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def _prepare(self) -> None:
        self.workdir = Path(tempfile.mkdtemp(prefix="grader-sandbox-"))
        copy_package(self.package_dir, self.workdir / "exercises")
        tools = self.workdir / ".grader"
        tools.mkdir()
        for name in WORKER_FILES:
            shutil.copyfile(HERE / name, tools / name)
        if self.uid is not None:
            for root, dirs, files in os.walk(self.workdir):
                os.chown(root, self.uid, self.uid)
                for name in files:
                    os.chown(os.path.join(root, name), self.uid, self.uid)
        os.chmod(self.workdir, stat.S_IRWXU)

    def _command(self) -> list[str]:
        python = [sys.executable, "-I", "-X", "utf8", "-B", ".grader/worker.py", str(self._response_fd_in_child)]
        if self.isolation == "plain":
            return python
        cmd = ["bwrap"]
        folders = [f for f in ["/usr", "/bin", "/lib", "/lib64", "/lib32", "/sbin", *python_folders()] if os.path.isdir(f)]
        # Parents that bwrap would create root-only: make them traversable by the worker's user.
        parents = sorted({str(p) for f in folders for p in Path(f).parents if str(p) != "/"}, key=len)
        for parent in parents:
            cmd += ["--perms", "0755", "--dir", parent]
        for folder in folders:
            cmd += ["--ro-bind", folder, folder]
        for name in ["/etc/ld.so.cache", "/etc/ld.so.conf", "/etc/ld.so.conf.d", "/etc/localtime"]:
            if os.path.exists(name):
                cmd += ["--ro-bind", name, name]
        cmd += ["--bind", str(self.workdir), SANDBOX_MOUNT, "--chdir", SANDBOX_MOUNT,
                "--proc", "/proc", "--dev", "/dev", "--tmpfs", "/tmp",
                "--unshare-pid", "--unshare-net", "--unshare-ipc", "--unshare-uts", "--unshare-cgroup-try",
                "--die-with-parent", "--new-session", "--hostname", "sandbox"]
        drop = ["setpriv", f"--reuid={self.uid}", f"--regid={self.uid}", "--clear-groups", "--no-new-privs",
                "--bounding-set=-all", "--inh-caps=-all"]
        return cmd + ["--", *drop, *python]

    def _environment(self) -> dict[str, str]:
        env = {"PATH": "/usr/bin:/bin", "HOME": SANDBOX_MOUNT if self.isolation == "bwrap" else str(self.workdir),
               "LANG": "C.UTF-8", "PYTHONHASHSEED": "0", "MPLBACKEND": "Agg",
               "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
        for name in ("OPENBLAS_CORETYPE", "OPENBLAS_L2_SIZE"):
            if name in os.environ:
                env[name] = os.environ[name]
        return env

    def _limit_resources(self) -> None:
        """Runs in the child between fork and exec."""
        limits = self.limits
        resource.setrlimit(resource.RLIMIT_CPU, (limits.cpu_seconds, limits.cpu_seconds))
        resource.setrlimit(resource.RLIMIT_AS, (limits.memory_bytes, limits.memory_bytes))
        resource.setrlimit(resource.RLIMIT_FSIZE, (limits.file_bytes, limits.file_bytes))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))
        if self.uid is not None:
            resource.setrlimit(resource.RLIMIT_NPROC, (limits.processes, limits.processes))
            if self.isolation == "plain":
                os.setgroups([])
                os.setgid(self.uid)
                os.setuid(self.uid)

    def start(self) -> None:
        """Start (or restart) the worker process."""
        self._kill()
        if self.workdir is None:
            self._prepare()
        read_end, write_end = os.pipe()
        self._response_fd_in_child = write_end
        self._stderr = []
        self.process = subprocess.Popen(
            self._command(), cwd=self.workdir, env=self._environment(), stdin=subprocess.PIPE,
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, pass_fds=(write_end,),
            preexec_fn=self._limit_resources, start_new_session=True)
        os.close(write_end)
        self._response_fd = read_end
        self._buffer = b""
        threading.Thread(target=self._drain_stderr, args=(self.process.stderr,), daemon=True).start()

    def _drain_stderr(self, stream) -> None:
        kept = 0
        for raw in iter(lambda: stream.read(4096), b""):
            if kept < STDERR_KEPT:
                text = raw.decode("utf-8", "replace")
                self._stderr.append(text[: STDERR_KEPT - kept])
                kept += len(text)

    def _kill(self) -> None:
        if self.process is None:
            return
        try:
            os.killpg(self.process.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
        try:
            self.process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            pass
        for stream in (self.process.stdin, self.process.stderr):
            try:
                stream.close()
            except Exception:
                pass
        try:
            os.close(self._response_fd)
        except OSError:
            pass
        self.process = None

    def close(self) -> None:
        """Kill the worker (and everything it started) and delete its folder."""
        self._kill()
        if self.workdir is not None:
            shutil.rmtree(self.workdir, ignore_errors=True)
            self.workdir = None

    # Calls ------------------------------------------------------------------------
    def call(self, module: str, function: str, args: list | tuple = (), kwargs: dict | None = None,
             timeout: float | None = None, repeat: int = 1, batch: bool = False) -> CallResult:
        """Call ``module.function(*args, **kwargs)`` in the worker (arguments already encoded).

        ``repeat`` calls it that many times (for timing); ``batch=True`` takes ``args``
        as a list of argument lists and returns the list of values.
        """
        if self.process is None or self.process.poll() is not None:
            if self.process is not None:
                self.restarts += 1
            self.start()
        self._next_id += 1
        request = {"id": self._next_id, "module": module, "function": function, "args": list(args),
                   "kwargs": kwargs or {}, "repeat": repeat, "batch": batch}
        started = time.perf_counter()
        try:
            self.process.stdin.write((json.dumps(request, allow_nan=True) + "\n").encode())
            self.process.stdin.flush()
        except (BrokenPipeError, OSError):
            return self._crashed(started)
        deadline = started + (timeout if timeout is not None else self.limits.call_timeout)
        outcome, line = self._read_line(deadline)
        elapsed = time.perf_counter() - started
        if outcome == "timeout":
            self._kill()
            return CallResult("timeout", message=f"took longer than {deadline - started:g} s (wall clock); stopped",
                              elapsed=elapsed)
        if outcome == "eof":
            return self._crashed(started)
        if outcome == "too_large":
            return CallResult("unreadable", message="the worker's answer was larger than the grader accepts",
                              elapsed=elapsed)
        try:
            data = json.loads(line)
        except ValueError:
            self._kill()
            return CallResult("unreadable", message="the worker's answer was not valid JSON", elapsed=elapsed)
        if data.get("id") != self._next_id:
            self._kill()
            return CallResult("unreadable", message="the worker answered out of turn", elapsed=elapsed)
        self._reap_strays(data.get("pid"))
        return CallResult(str(data.get("status")), data.get("value"), str(data.get("message", "")),
                          str(data.get("output", "")), elapsed, data.get("args_after") or [])

    def _read_line(self, deadline: float) -> tuple[str, bytes]:
        """``("line", bytes)``, or ``("timeout" | "eof" | "too_large", b"")``."""
        while b"\n" not in self._buffer:
            remaining = deadline - time.perf_counter()
            if remaining <= 0:
                return "timeout", b""
            with selectors.DefaultSelector() as selector:
                selector.register(self._response_fd, selectors.EVENT_READ)
                if not selector.select(timeout=min(remaining, 0.5)):
                    continue
            chunk = os.read(self._response_fd, 1 << 20)
            if not chunk:  # every writer closed: the worker is gone
                return "eof", b""
            self._buffer += chunk
            if len(self._buffer) > RESPONSE_LIMIT:
                self._kill()
                self._buffer = b""
                return "too_large", b""
        line, _, self._buffer = self._buffer.partition(b"\n")
        return "line", line

    def _reap_strays(self, worker_pid) -> None:
        """Kill every process of this sandbox's user but the worker itself.

        Runs after each call, so nothing the student's code started (a background
        process, the children of a fork bomb) outlives the call that started it.
        Only with bubblewrap, where the user is this sandbox's alone.
        """
        if self.uid is None:
            return
        killed: list[str] = []
        for entry in os.listdir("/proc"):
            if not entry.isdigit():
                continue
            try:
                with open(f"/proc/{entry}/status") as handle:
                    fields = dict(line.split(":", 1) for line in handle if ":" in line)
            except OSError:
                continue
            if int(fields.get("Uid", "-1").split()[0]) != self.uid:
                continue
            if fields.get("NSpid", "").split()[-1:] == [str(worker_pid)]:
                continue
            try:
                os.kill(int(entry), signal.SIGKILL)
                killed.append(entry)
            except OSError:
                pass
        deadline = time.monotonic() + 1.0
        while killed and time.monotonic() < deadline:  # SIGKILL lands asynchronously
            killed = [pid for pid in killed if _running(pid)]
            if killed:
                time.sleep(0.005)

    def _crashed(self, started: float) -> CallResult:
        process = self.process
        code = process.wait(timeout=10) if process is not None else None
        stderr = "".join(self._stderr).strip()
        self._kill()
        if code is not None and code > 128 and self.isolation == "bwrap":
            code = -(code - 128)  # bwrap's init reports a signal death as 128 + signal
        if code is not None and code < 0:
            name = signal.Signals(-code).name
            why = {"SIGXCPU": "CPU time limit reached", "SIGSEGV": "segmentation fault",
                   "SIGKILL": "killed (memory or process limit, or a kill)", "SIGXFSZ": "file size limit reached",
                   }.get(name, name)
        elif code == 0:
            why = "the worker exited (sys.exit or os._exit in your code?)"
        else:
            why = f"the worker exited with status {code}"
        tail = f"\n{stderr[-1500:]}" if stderr else ""
        return CallResult("crashed", message=f"crashed: {why}{tail}", elapsed=time.perf_counter() - started)
