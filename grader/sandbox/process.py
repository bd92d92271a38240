"""Run student code in a separate, limited worker process and talk to it in JSON.

Isolation, strongest available first:

- ``"bwrap"`` (used when bubblewrap is installed and the grader runs as root, as it
  does in CI and on Gradescope): the worker sees a private file system holding only
  the files its Python needs (read-only, :mod:`grader.sandbox.mounts`), its own copy
  of the submission at ``/sandbox`` and an empty ``/tmp``; no network, its own process namespace (every
  process it leaves behind dies with it), and it runs as an unprivileged user of its
  own (one uid per parallel job) with no capabilities, in a user namespace of its own
  (its uid mapped to itself, nothing else: a kernel keyring and namespaces of its own).
- ``"plain"``: the same worker with the same CPU, memory and file limits but the
  host's file system (for machines without bubblewrap).  Run as root, and when Python
  is installed where any user can run it, the worker still drops to its own
  unprivileged user (with the process limit); the reference solutions are then as
  hidden as their file permissions make them (the Gradescope runner makes them
  readable by root only).  Otherwise it runs as the grader's user, without the
  process limit, which would count every process of that user.

Both apply resource limits (CPU seconds, address space, file size, processes, no core
files), a wall-clock timeout per call, and a seccomp filter (:mod:`grader.sandbox.seccomp`)
that refuses the system calls student code has no need of: the kernel keyring (a
channel between submissions), new namespaces, mounts, tracing, BPF, ``memfd_create``.  Only JSON crosses: requests on the worker's
standard input, responses on a pipe whose descriptor is its first argument; its standard output is discarded
(printed text is captured per call by the worker and returned, capped).  The parent
measures elapsed time itself.  A crash, hang or exception costs that call only: the
worker is restarted for the next one.

The parent trusts nothing the worker sends: it takes the worker's process id from a
first line written before any student code runs, accepts as an answer only a JSON line
echoing the request's id and random nonce, ignores every other line, checks that the
answer is well-formed plain data (:func:`grader.sandbox.codec.plain_data`; lone surrogates
become ``?``) and stops reading at ``RESPONSE_LIMIT`` bytes.

Each sandbox holds an exclusive lock on its user id (a file lock under ``/run``), so
that two graders on one machine (two batches, parallel test runs) never share a user:
killing "every process of this user" then only ever hits this sandbox's processes.
"""
from __future__ import annotations

import fcntl
import json
import os
import random
import resource
import secrets
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

from . import codec, mounts, seccomp
from ..errors import GradingError
from .isolation import decided_isolation
from .kept import KeptValues
from .memory_cage import MemoryCage

HERE = Path(__file__).resolve().parent
WORKER_FILES = ("worker.py", "codec.py")
#: The worker's seccomp filter (None off x86-64, where the sandbox runs without one).
SECCOMP_PROGRAM = seccomp.filter_program()
SANDBOX_MOUNT = "/sandbox"
#: An empty folder and an empty file of the worker folder, mounted over what is left out.
EMPTY_FOLDER, EMPTY_FILE = "empty-folder", "empty-file"
#: First uid of the unprivileged users the workers run as (one per parallel slot).
SANDBOX_UID_BASE = 61000
#: Number of uids from SANDBOX_UID_BASE the sandboxes may take (when the uid of their
#: slot is held by another grader on the machine, another free one is used).
SANDBOX_UID_COUNT = 1000
#: Folders (first usable one wins) for the uid locks: root-owned, not world-writable.
UID_LOCK_PARENTS = ("/run", "/var/run", "/var/lib", "/tmp")
UID_LOCK_FOLDER = "grader-sandbox-uids"
#: Statuses a worker may answer with.
WORKER_STATUSES = ("ok", "not_implemented", "import_error", "missing", "error", "unreadable")
#: Statuses of a call (CallResult.status): the worker's, and those the parent sees itself.
#: A call's status is not a test's (grader.harness.outcome.STATUS_MEANINGS): the
#: harness says what each failed call means for its test.
CALL_STATUSES = WORKER_STATUSES + ("timeout", "crashed")
RESPONSE_LIMIT = 16 * 1024 * 1024  # bytes of one JSON response (parsed, it takes about 15 times more)
TEXT_LIMIT = 20_000  # characters of a worker's message or printed output kept per call
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
    total_memory_bytes : int
        Memory of every process of the sandbox together, tmpfs included (a memory
        cgroup, :mod:`grader.sandbox.memory_cage`, where one can be made).
    disk_bytes : int
        Size of each writable folder of the bubblewrap sandbox (``/sandbox``, ``/tmp``:
        size-limited tmpfs); the student's package is mounted read-only.
    """

    call_timeout: float = 10.0
    cpu_seconds: int = 300
    memory_bytes: int = 2 * 1024**3
    file_bytes: int = 16 * 1024**2
    processes: int = 64
    total_memory_bytes: int = 3 * 1024**3
    disk_bytes: int = 64 * 1024**2


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


class SandboxBroken(GradingError):
    """The worker died before it said hello, so before any student code ran: the
    sandbox itself cannot start here (a grader or machine fault, never the student's)."""


def reachable_temp_folder() -> str | None:
    """A temporary folder that any user can reach (every folder on its path searchable
    by others), for a worker that drops to a user of its own without bubblewrap; None
    if this process's own temporary folder already is one.

    The grading folders under it (Gradescope's ``/tmp/grading-*``, made by root) are
    0700: a worker folder inside them is out of the worker's reach."""
    candidates = [tempfile.gettempdir(), "/tmp", "/var/tmp", "/dev/shm"]
    for index, folder in enumerate(candidates):
        path = Path(folder)
        try:
            if path.is_dir() and all(part.stat().st_mode & stat.S_IXOTH for part in [path, *path.parents]):
                return None if index == 0 else folder
        except OSError:
            continue
    raise SandboxBroken("no temporary folder here can be reached by the sandbox's user "
                        f"(tried {', '.join(candidates)})")


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


#: The suffixes of the files a graded package is made of: Python source and the data
#: and notes that go with it.  Nothing else is ever copied into a sandbox: no compiled
#: ``.pyc`` (Python would import it without its source), no extension module
#: (``.so``), no ``.pth``, no archive to import from.
SOURCE_SUFFIXES = (".py", ".md", ".txt", ".json")


def copy_package(source: Path, destination: Path) -> None:
    """Copy what is graded of a package folder: its regular files with a suffix of
    :data:`SOURCE_SUFFIXES`, in folders other than ``__pycache__`` and hidden ones.

    Symbolic links, special files and everything else are skipped: the package in the
    sandbox holds source only, and no bytecode cache (the worker runs ``python -B``,
    which writes none, and a cache handed in is never copied: an unchecked-hash
    ``.pyc`` in ``__pycache__`` would be imported in place of its source)."""
    destination.mkdir(parents=True, exist_ok=True)
    for entry in os.scandir(source):
        if entry.is_symlink():
            continue
        target = destination / entry.name
        if entry.is_dir(follow_symlinks=False):
            if entry.name != "__pycache__" and not entry.name.startswith("."):
                copy_package(Path(entry.path), target)
        elif entry.is_file(follow_symlinks=False) and entry.name.lower().endswith(SOURCE_SUFFIXES):
            shutil.copyfile(entry.path, target)


def uid_lock_folder() -> Path | None:
    """The folder of the uid lock files (created if needed), or None if none is safe.

    Safe: a real folder (not a link) owned by root and writable by root only, so no
    sandboxed user can plant or hold a lock.
    """
    for parent in UID_LOCK_PARENTS:
        folder = Path(parent) / UID_LOCK_FOLDER
        try:
            if not os.path.isdir(parent):
                continue
            try:
                os.mkdir(folder, 0o700)
            except FileExistsError:
                pass
            info = os.lstat(folder)
        except OSError:
            continue
        if stat.S_ISDIR(info.st_mode) and info.st_uid == 0 and not info.st_mode & 0o022:
            return folder
    return None


def claim_uid(preferred: int) -> tuple[int, int | None]:
    """``(uid, lock descriptor)``: ``preferred`` if no other sandbox holds it, else a free
    uid of the range; the lock lasts until the descriptor is closed.

    Without a safe lock folder: ``(preferred, None)`` (the uid is then shared with any
    other grader running on this machine at the same time).
    """
    folder = uid_lock_folder()
    if folder is None:
        return preferred, None
    # In random order: a uid another grader just gave back is rarely taken again at once.
    others = [SANDBOX_UID_BASE + i for i in range(SANDBOX_UID_COUNT) if SANDBOX_UID_BASE + i != preferred]
    random.shuffle(others)
    for uid in [preferred, *others]:
        try:
            fd = os.open(folder / f"{uid}.lock", os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return uid, fd
        except OSError:
            os.close(fd)
    raise RuntimeError(f"every sandbox user id from {SANDBOX_UID_BASE} to "
                       f"{SANDBOX_UID_BASE + SANDBOX_UID_COUNT - 1} is in use")


def uid_in_use(uid: int) -> bool:
    """True while a sandbox (of any grader on this machine) holds ``uid``'s lock."""
    folder = uid_lock_folder()
    if folder is None:
        return False
    try:
        fd = os.open(folder / f"{uid}.lock", os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC)
    except OSError:
        return False
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        return False
    except OSError:
        return True
    finally:
        os.close(fd)


def process_table(pids=None):
    """``(pid, fields)`` of every process (or of ``pids``), ``fields`` the lines of
    /proc/PID/status."""
    for entry in (os.listdir("/proc") if pids is None else map(str, pids)):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/status") as handle:
                yield int(entry), dict(line.split(":", 1) for line in handle if ":" in line)
        except OSError:
            continue


def processes_of(uids) -> list[tuple[int, int]]:
    """``(pid, uid)`` of the live (not zombie) processes whose real uid is in ``uids``."""
    wanted = set(uids)
    found = []
    for pid, fields in process_table():
        uid = int(fields.get("Uid", "-1").split()[0])
        if uid in wanted and not fields.get("State", "").strip().startswith("Z"):
            found.append((pid, uid))
    return found


def stray_processes() -> list[tuple[int, int]]:
    """Processes of sandbox users that no sandbox holds: left behind (should be none)."""
    uids = range(SANDBOX_UID_BASE, SANDBOX_UID_BASE + SANDBOX_UID_COUNT)
    return [(pid, uid) for pid, uid in processes_of(uids) if not uid_in_use(uid)]


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
    withheld : dict, optional
        ``{"module:function": reason}``: functions the trusted side found no source for
        (still the stub; :mod:`grader.batch.source_audit`).  A call of one is answered
        here, ``not_implemented`` with the reason, and never reaches the worker:
        whatever the package does at run time, it earns nothing its source does not hold.
    """

    def __init__(self, package_dir: Path, limits: Limits = Limits(), slot: int = 0, isolation: str = "auto",
                 withheld: dict[str, str] | None = None):
        self.withheld = dict(withheld or {})
        self.package_dir = Path(package_dir)
        self.limits = limits
        self.slot = slot
        self.isolation = decided_isolation(isolation)
        # A user of its own: the process limit then counts this sandbox alone.
        can_switch = os.geteuid() == 0 and (self.isolation == "bwrap" or python_usable_by_anyone())
        self._uid_lock = None
        self.uid = None
        if can_switch:
            self.uid, self._uid_lock = claim_uid(SANDBOX_UID_BASE + slot)
        self.workdir: Path | None = None
        self.process: subprocess.Popen | None = None
        self._responses = None
        self._stderr: list[str] = []
        self._next_id = 0
        self._seccomp_fd: int | None = None
        self._cage: MemoryCage | None = None
        self._worker_pid: int | None = None
        self._buffer = bytearray()
        self._kept = KeptValues()  # what the worker process holds (grader.sandbox.kept)
        self.restarts = 0
        self._settled: tuple[int, frozenset] | None = None  # see _reap_strays
        self.broken: SandboxBroken | None = None  # set once the worker could not even start
        self._needed: mounts.Mounts | None = None  # see _mounts

    # Life cycle -----------------------------------------------------------------
    def __enter__(self) -> "Sandbox":
        return self

    def __del__(self) -> None:
        lock = getattr(self, "_uid_lock", None)
        if lock is not None:
            try:
                os.close(lock)
            except OSError:
                pass

    def __exit__(self, *exc) -> None:
        self.close()

    def _prepare(self) -> None:
        # Without bubblewrap the worker reaches its folder through the host's file system.
        parent = reachable_temp_folder() if self.uid is not None and self.isolation == "plain" else None
        self.workdir = Path(tempfile.mkdtemp(prefix="grader-sandbox-", dir=parent))
        copy_package(self.package_dir, self.workdir / "exercises")
        tools = self.workdir / ".grader"
        tools.mkdir()
        # Mounted over what the worker's file system leaves out (grader.sandbox.mounts).
        (self.workdir / EMPTY_FOLDER).mkdir()
        (self.workdir / EMPTY_FILE).touch()
        for name in WORKER_FILES:
            shutil.copyfile(HERE / name, tools / name)
        if self.uid is not None:
            for root, dirs, files in os.walk(self.workdir):
                os.chown(root, self.uid, self.uid)
                for name in files:
                    os.chown(os.path.join(root, name), self.uid, self.uid)
        os.chmod(self.workdir, stat.S_IRWXU)

    def _mounts(self) -> mounts.Mounts:
        """Only what the worker's Python needs to run this package (grader.sandbox.mounts),
        read once per sandbox (its package is copied once)."""
        if self._needed is None:
            names = mounts.imported_names(self.workdir / "exercises")
            self._needed = mounts.worker_mounts(mounts.distributions_for(names))
        if self._needed is None:  # ELF files of a kind mounts does not read: the system folders whole
            binds = [f for f in ["/usr", "/bin", "/lib", "/lib64", "/lib32", "/sbin", *python_folders()]
                     if os.path.isdir(f)]
            binds += [f for f in mounts.ETC_FILES if os.path.exists(f)]
            self._needed = mounts.Mounts((), tuple(binds), (), (), {})
        return self._needed

    def _command(self) -> list[str]:
        python = [sys.executable, "-I", "-X", "utf8", "-B", ".grader/worker.py", str(self._response_fd_in_child)]
        if self.isolation == "plain":
            return python
        # The empty /tmp comes first: a Python or checkout under /tmp is bound into it below.
        # Writable folders are size-limited tmpfs: the disk a submission can fill.
        disk = str(self.limits.disk_bytes)
        cmd = ["bwrap", "--perms", "1777", "--size", disk, "--tmpfs", "/tmp"]
        needed = self._mounts()
        # Parents that bwrap would create root-only: make them traversable by the worker's user.
        parents = sorted({str(p) for f in [*needed.binds, *(link for _, link in needed.links)]
                          for p in Path(f).parents if str(p) != "/"}, key=len)
        for parent in parents:
            cmd += ["--perms", "0755", "--dir", parent]
        for path in needed.binds:
            cmd += ["--ro-bind", path, path]
        for target, link in needed.links:
            cmd += ["--symlink", target, link]
        for folder in needed.hidden_folders:
            cmd += ["--ro-bind", str(self.workdir / EMPTY_FOLDER), folder]
        for file in needed.hidden_files:
            cmd += ["--ro-bind", str(self.workdir / EMPTY_FILE), file]
        cmd += ["--perms", "0777", "--size", disk, "--tmpfs", SANDBOX_MOUNT]
        for name in ("exercises", ".grader"):
            cmd += ["--ro-bind", str(self.workdir / name), f"{SANDBOX_MOUNT}/{name}"]
        cmd += ["--chdir", SANDBOX_MOUNT,
                "--proc", "/proc", "--dev", "/dev",
                "--unshare-pid", "--unshare-net", "--unshare-ipc", "--unshare-uts", "--unshare-cgroup-try",
                "--die-with-parent", "--new-session", "--hostname", "sandbox"]
        drop = [needed.programs.get("setpriv", "setpriv"), f"--reuid={self.uid}", f"--regid={self.uid}",
                "--clear-groups", "--no-new-privs", "--bounding-set=-all", "--inh-caps=-all"]
        # A second bubblewrap, started as the sandbox's user, puts the worker in a user
        # namespace of its own (the sandbox uid mapped to itself, nothing else mapped, no
        # capability anywhere): a keyring and namespaces of its own.  It is unprivileged, so
        # it binds the first one's root as it is (read-only mounts stay read-only), and it
        # loads the seccomp filter last, which then refuses any further namespace.
        # Its own process namespace too: the worker and what it starts see only their
        # own init, which ignores their signals, so they cannot stop this bubblewrap.
        user_namespace = [needed.programs.get("bwrap", "bwrap"), "--unshare-user", "--uid", str(self.uid),
                          "--gid", str(self.uid), "--unshare-pid", "--bind", "/", "/", "--chdir", SANDBOX_MOUNT,
                          "--die-with-parent"]
        if self._seccomp_fd is not None:
            user_namespace += ["--seccomp", str(self._seccomp_fd)]
        return cmd + ["--", *drop, *user_namespace, "--", *python]

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
        if self._cage is not None:
            self._cage.join()
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
        if self.isolation == "plain" and SECCOMP_PROGRAM is not None:
            seccomp.install(SECCOMP_PROGRAM)

    def start(self) -> None:
        """Start (or restart) the worker process."""
        self._kill()
        if self.workdir is None:
            self._prepare()
        if self._cage is None and (os.geteuid() == 0 or self.isolation == "plain"):
            self._cage = MemoryCage.create(self.limits.total_memory_bytes, f"grader-sandbox-{self.slot}")
        read_end, write_end = os.pipe()
        self._response_fd_in_child = write_end
        self._stderr = []
        passed = [write_end]
        self._seccomp_fd = None
        if self.isolation == "bwrap" and SECCOMP_PROGRAM is not None:
            # bubblewrap reads the filter from a descriptor and loads it just before exec.
            filter_read, filter_write = os.pipe()
            os.write(filter_write, SECCOMP_PROGRAM)
            os.close(filter_write)
            self._seccomp_fd = filter_read
            passed.append(filter_read)
        try:
            self.process = subprocess.Popen(
                self._command(), cwd=self.workdir, env=self._environment(), stdin=subprocess.PIPE,
                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, pass_fds=tuple(passed),
                preexec_fn=self._limit_resources, start_new_session=True)
        finally:
            if self._seccomp_fd is not None:
                os.close(self._seccomp_fd)
                self._seccomp_fd = None
        os.close(write_end)
        self._response_fd = read_end
        self._buffer = bytearray()
        self._worker_pid = None
        self._kept = KeptValues()  # a new worker holds nothing
        self._drainer = threading.Thread(target=self._drain_stderr, args=(self.process.stderr,), daemon=True)
        self._drainer.start()

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
        # Whatever escaped the process group (setsid in plain mode) dies by its user.
        self._reap_strays(None)
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
        """Kill the worker (and everything it started), delete its folder, free its user."""
        self._kill()
        if self._cage is not None:
            self._cage.close()
            self._cage = None
        if self.workdir is not None:
            shutil.rmtree(self.workdir, ignore_errors=True)
            self.workdir = None
        if self._uid_lock is not None:
            os.close(self._uid_lock)
            self._uid_lock = None

    def cpu_seconds(self) -> float | None:
        """CPU time (s, user + system) the sandbox's live processes have used so far, read
        by this trusted process from /proc/PID/task/*/schedstat (nanoseconds): unlike the
        wall clock it does not grow while other jobs hold the machine's cores.  The
        processes are the memory cage's, else those of the sandbox's own user, else the
        worker alone; a process that has already ended no longer counts.  None when no
        worker runs or /proc cannot be read."""
        if self.process is None or self.process.poll() is not None:
            return None
        if self._cage is not None:
            pids = self._cage.pids()
        elif self.uid is not None:
            pids = [pid for pid, _ in processes_of([self.uid])]
        else:
            pids = [self.process.pid]
        total = 0
        for pid in pids:
            try:
                tasks = os.listdir(f"/proc/{pid}/task")
            except OSError:
                continue
            for task in tasks:
                try:
                    with open(f"/proc/{pid}/task/{task}/schedstat") as handle:
                        total += int(handle.read().split()[0])
                except (OSError, ValueError, IndexError):
                    continue
        return total / 1e9 if pids else None

    # Calls ------------------------------------------------------------------------------
    def call(self, module: str, function: str, args: list | tuple = (), kwargs: dict | None = None,
             timeout: float | None = None, repeat: int = 1, batch: bool = False,
             program: dict | None = None) -> CallResult:
        """Call ``module.function(*args, **kwargs)`` in the worker (arguments already encoded;
        a :class:`~grader.sandbox.kept.KeptArgument` is sent once to each worker process).

        ``repeat`` calls it that many times (for timing); ``batch=True`` takes ``args``
        as a list of argument lists and returns the list of values; ``program`` (then
        ``module`` and ``function`` are unused) runs a list of calls, one value each
        (:meth:`grader.sandbox.worker.Worker.run_program`).

        The request carries a fresh random nonce; only a line echoing it (and the
        request's id) is taken as the answer, every other line is skipped.  What this
        protects: a line written earlier or later than the answer -- by a process or
        thread the student's code left running, by code run at import time, or a
        canned line -- is never taken for the answer to this request.  What it does not:
        the student's code runs in the worker and can read the nonce from the worker's
        memory and write an answer of its choosing; that answer is still only plain
        data that this process checks (:func:`grader.sandbox.codec.plain_data`) and compares
        with values it computes itself, so it is worth no more than returning that
        value.
        """
        if self.broken is not None:
            raise self.broken
        # A program's functions are checked as a call's (none of its calls runs then).
        called = [tuple(f) for f in program.get("functions", [])] if isinstance(program, dict) else []
        for name, reason in ((f, self.withheld.get(f"{m}:{f}")) for m, f in called or [(module, function)]):
            if reason is not None:
                return CallResult("not_implemented", message=f"not implemented yet: {name}: {reason}")
        if self.process is None or self.process.poll() is not None:
            if self.process is not None:
                self.restarts += 1
            self.start()
        self._next_id += 1
        nonce = secrets.token_hex(16)
        if not batch:   # arguments to keep (grader.sandbox.kept), after a restart above
            args = [self._kept.form(a) for a in args]
            kwargs = {k: self._kept.form(v) for k, v in (kwargs or {}).items()}
        request = {"id": self._next_id, "nonce": nonce, "module": module, "function": function,
                   "args": list(args), "kwargs": kwargs or {}, "repeat": repeat, "batch": batch,
                   "program": program}
        self._discard_stale_output()
        started = time.perf_counter()
        deadline = started + (timeout if timeout is not None else self.limits.call_timeout)
        try:
            sent = self._send((json.dumps(request, allow_nan=True) + "\n").encode(), deadline)
        except (BrokenPipeError, OSError):
            return self._crashed(started)
        outcome, data = self._read_answer(self._next_id, nonce, deadline) if sent else ("timeout", None)
        elapsed = time.perf_counter() - started
        if outcome == "timeout":
            self._kill()
            return CallResult("timeout", message=f"took longer than {deadline - started:g} s (wall clock); stopped",
                              elapsed=elapsed)
        if outcome == "eof":
            return self._crashed(started)
        if outcome == "too_large":
            return CallResult("unreadable", message="the worker's answer was larger than the grader accepts "
                              f"({RESPONSE_LIMIT // 1024**2} MiB)", elapsed=elapsed)
        try:
            answer = self._checked(data)
        except (codec.NotPlainData, RecursionError) as exc:
            self._kill()
            return CallResult("unreadable", message=f"the worker's answer was not well-formed: {exc}",
                              elapsed=elapsed)
        self._reap_strays(self._worker_pid)
        return CallResult(answer["status"], answer["value"], answer["message"], answer["output"], elapsed,
                          answer["args_after"])

    def _discard_stale_output(self) -> None:
        """Drop what the worker's channel holds before a request is sent: none of it can be
        the answer to that request (a stray writer's leftovers, a partial line that would
        otherwise be glued to the next answer).  The hello line of a fresh worker is kept."""
        if self._worker_pid is None:
            return
        self._buffer = bytearray()
        dropped = 0
        with selectors.DefaultSelector() as selector:
            selector.register(self._response_fd, selectors.EVENT_READ)
            while dropped < RESPONSE_LIMIT and selector.select(timeout=0):
                chunk = os.read(self._response_fd, 1 << 20)
                if not chunk:
                    return
                dropped += len(chunk)

    def _send(self, data: bytes, deadline: float) -> bool:
        """Write a request to the worker's standard input; False if the deadline passes
        first (a worker that stops reading its input cannot block the grader)."""
        fd = self.process.stdin.fileno()
        os.set_blocking(fd, False)
        view = memoryview(data)
        drained = 0
        with selectors.DefaultSelector() as selector:
            selector.register(fd, selectors.EVENT_WRITE)
            # The answer channel is read meanwhile: a worker blocked writing lines into a
            # full channel would otherwise never read the rest of this request.  Nothing
            # it holds can answer a request not yet sent; a fresh worker's hello is kept.
            selector.register(self._response_fd, selectors.EVENT_READ)
            while view:
                remaining = deadline - time.perf_counter()
                if remaining <= 0:
                    return False
                for key, _ in selector.select(timeout=min(remaining, 0.5)):
                    if key.fd == self._response_fd:
                        chunk = os.read(self._response_fd, 1 << 20)
                        if not chunk:
                            selector.unregister(self._response_fd)
                            continue
                        if self._worker_pid is None:
                            self._buffer += chunk
                        drained += len(chunk)
                        if drained > RESPONSE_LIMIT:
                            return False
                        continue
                    try:
                        view = view[os.write(fd, view):]
                    except BlockingIOError:
                        continue
        return True

    @staticmethod
    def _checked(data: dict) -> dict:
        """The answer's fields, checked and cleaned; NotPlainData if it is malformed."""
        status = data.get("status")
        if status not in WORKER_STATUSES:
            raise codec.NotPlainData(f"unknown status {str(status)[:40]!r}")
        texts = {}
        for name in ("message", "output"):
            text = data.get(name, "")
            if type(text) is not str:
                raise codec.NotPlainData(f"{name} is not a text")
            # Capped before anything else reads them: a message is kept to what a person reads.
            texts[name] = codec.clean_text(text[:TEXT_LIMIT] + (f"\n[... {len(text) - TEXT_LIMIT} more characters "
                                                                 "not shown]" if len(text) > TEXT_LIMIT else ""))
        after = data.get("args_after") or []
        if type(after) is not list or any(a is not None and type(a) is not dict for a in after):
            raise codec.NotPlainData("args_after is not a list of bodies")
        return {"status": status, "value": codec.plain_data(data.get("value")), **texts,
                "args_after": codec.plain_data(after)}

    def _read_answer(self, number: int, nonce: str, deadline: float) -> tuple[str, dict | None]:
        """``("answer", data)``, or ``("timeout" | "eof" | "too_large", None)``.

        The first line of a fresh worker is its hello (process id); after that, lines
        that are not a JSON object with this request's id and nonce are skipped.
        Bytes received during one call are capped at RESPONSE_LIMIT.
        """
        received = 0
        scanned = 0
        while True:
            newline = self._buffer.find(b"\n", scanned)
            if newline < 0:
                scanned = len(self._buffer)
                remaining = deadline - time.perf_counter()
                if remaining <= 0:
                    return "timeout", None
                with selectors.DefaultSelector() as selector:
                    selector.register(self._response_fd, selectors.EVENT_READ)
                    if not selector.select(timeout=min(remaining, 0.5)):
                        continue
                chunk = os.read(self._response_fd, 1 << 20)
                if not chunk:  # every writer closed: the worker is gone
                    return "eof", None
                received += len(chunk)
                if received > RESPONSE_LIMIT:
                    self._kill()
                    self._buffer = bytearray()
                    return "too_large", None
                self._buffer += chunk
                continue
            line = bytes(self._buffer[:newline])
            del self._buffer[:newline + 1]
            scanned = 0
            try:
                data = codec.loads_answer(line)
            except (ValueError, RecursionError):
                continue
            if type(data) is not dict:
                continue
            if self._worker_pid is None:
                if data.get("hello") is True and type(data.get("pid")) is int:
                    self._worker_pid = data["pid"]
                continue
            if data.get("id") == number and data.get("nonce") == nonce:
                return "answer", data

    def _reap_strays(self, worker_pid: int | None) -> None:
        """Kill every process of this sandbox's user but the worker itself (all of them
        when ``worker_pid`` is None).

        Runs after each call, so nothing the student's code started (a background
        process, the children of a fork bomb) outlives the call that started it, and
        after the worker is killed.  Only when the sandbox has a user of its own (held
        by its uid lock); ``worker_pid`` is the worker's pid in its own process
        namespace, taken from its hello line.
        """
        if self.uid is None:
            return
        killed: list[str] = []
        # The memory cage lists every process of this sandbox (none can leave it): far
        # cheaper than reading the whole process table after every call.
        caged = self._cage.pids() if self._cage is not None and worker_pid is not None else None
        if caged is not None and self._settled == (worker_pid, frozenset(caged)):
            return  # the very processes found after the last call: the worker and its ancestors
        table = [(pid, fields) for pid, fields in process_table(caged)
                 if int(fields.get("Uid", "-1").split()[0]) == self.uid]
        spared: set[int] = set()
        if worker_pid is not None:
            parent_of = {pid: int(fields.get("PPid", "0").split()[0] or 0) for pid, fields in table}
            for pid, fields in table:
                if fields.get("NSpid", "").split()[-1:] == [str(worker_pid)]:
                    # The worker and its ancestors of the sandbox's user: the bubblewrap
                    # holding its user and process namespaces, and that namespace's init.
                    while pid in parent_of and pid not in spared:
                        spared.add(pid)
                        pid = parent_of[pid]
        for pid, fields in table:
            if pid in spared:
                continue
            try:
                os.kill(pid, signal.SIGKILL)
                killed.append(str(pid))
            except OSError:
                pass
        # Nothing to kill: the next call may skip reading /proc if the cage still holds
        # exactly these processes (a new one, a stray, has a pid not in the set).
        self._settled = (worker_pid, frozenset(caged)) if caged is not None and not killed else None
        deadline = time.monotonic() + 1.0
        while killed and time.monotonic() < deadline:  # SIGKILL lands asynchronously
            killed = [pid for pid in killed if _running(pid)]
            if killed:
                time.sleep(0.005)

    def _said_hello(self) -> bool:
        """True if the worker wrote its hello line (read or still in the channel)."""
        if self._worker_pid is not None:
            return True
        with selectors.DefaultSelector() as selector:
            selector.register(self._response_fd, selectors.EVENT_READ)
            while len(self._buffer) < RESPONSE_LIMIT and selector.select(timeout=0):
                chunk = os.read(self._response_fd, 1 << 20)
                if not chunk:
                    break
                self._buffer += chunk
        for line in bytes(self._buffer).split(b"\n"):
            try:
                data = json.loads(line)
            except (ValueError, RecursionError):
                continue
            if type(data) is dict and data.get("hello") is True:
                return True
        return False

    def _crashed(self, started: float) -> CallResult:
        process = self.process
        try:
            code = process.wait(timeout=2) if process is not None else None
        except subprocess.TimeoutExpired:  # alive, but it closed its answer channel
            code = None
        if code is not None and getattr(self, "_drainer", None) is not None:
            self._drainer.join(timeout=1.0)   # the worker is gone: what it wrote is all there
        stderr = "".join(self._stderr).strip()
        hello = self._said_hello()
        self._kill()
        if not hello:
            self.broken = SandboxBroken(
                f"the grader could not start its sandbox ({self.isolation} isolation): the worker process ended "
                f"with status {code} before running any student code" + (f":\n{stderr[-1500:]}" if stderr else ""))
            raise self.broken
        if code is not None and code > 128 and self.isolation == "bwrap":
            code = -(code - 128)  # bwrap's init reports a signal death as 128 + signal
        if code is None:
            why = "the worker stopped answering (it closed its answer channel) and was stopped"
        elif code < 0:
            try:
                name = signal.Signals(-code).name
            except ValueError:
                name = f"signal {-code}"
            why = {"SIGXCPU": "CPU time limit reached", "SIGSEGV": "segmentation fault",
                   "SIGKILL": "killed (memory or process limit, or a kill)", "SIGXFSZ": "file size limit reached",
                   }.get(name, name)
        elif code == 0:
            why = "the worker exited (sys.exit or os._exit in your code?)"
        else:
            why = f"the worker exited with status {code}"
        tail = f"\n{stderr[-1500:]}" if stderr else ""
        return CallResult("crashed", message=f"crashed: {why}{tail}", elapsed=time.perf_counter() - started)
