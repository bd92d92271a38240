"""The sandbox: student code runs isolated, limited, and every failure is contained."""
import os
import sys
import textwrap
import time
from pathlib import Path

import pytest

from grader.sandbox.isolation import bwrap_available
from grader.sandbox.process import Limits, Sandbox

REPO = Path(__file__).resolve().parent.parent
needs_bwrap = pytest.mark.skipif(not bwrap_available(), reason="bubblewrap isolation needs bwrap and root")

HOSTILE = '''
import os, sys, time, subprocess

def add(a, b):
    return a + b

def total_then_zero(rows):
    total = float(sum(map(sum, rows)))
    for row in rows:           # the argument changed in place: the worker's kept copy must not
        row[:] = [0.0] * len(row)
    return total

def loud():
    print("x" * 10_000_000)
    return 1

def stub():
    raise NotImplementedError

def fill_disk():
    # Files of 8 MB each (under the per-file limit) until the folder is full.
    written = 0
    try:
        for n in range(40):
            with open(f"fill{n}.bin", "wb") as handle:
                handle.write(b"x" * 8_000_000)
            written += 8_000_000
    except OSError as exc:
        return [written, exc.errno]
    return [written, 0]

def write_own_package():
    try:
        with open("exercises/hostile.py", "a") as handle:
            handle.write("# changed")
        return "changed"
    except OSError as exc:
        return exc.errno

def hogs_together(children, megabytes):
    # Each child stays under the per-process limit; together they pass the total.
    import signal
    pids = []
    for _ in range(children):
        pid = os.fork()
        if pid == 0:
            block = bytearray(megabytes * 1024 * 1024)
            for i in range(0, len(block), 4096):
                block[i] = 1
            time.sleep(2)
            os._exit(0)
        pids.append(pid)
    killed = 0
    for pid in pids:
        _, status = os.waitpid(pid, 0)
        killed += os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGKILL
    return killed

def user_namespace():
    # Which user namespace the worker runs in, and what it maps.
    return [os.readlink("/proc/self/ns/user"), open("/proc/self/uid_map").read().split(), os.getuid()]

def kernel_channels():
    # The keyring (a channel to a later submission), namespaces, anonymous memory files.
    import ctypes
    libc = ctypes.CDLL(None, use_errno=True)
    found = {}
    found["keyctl"] = [libc.syscall(250, 0, 0, 0, 0, 0), ctypes.get_errno()]
    found["add_key"] = [libc.syscall(248, b"user", b"k", b"v", 1, -4), ctypes.get_errno()]
    found["unshare_user"] = [libc.unshare(0x10000000), ctypes.get_errno()]
    found["clone_newuser"] = [libc.syscall(56, 0x10000000 | 17, 0, 0, 0, 0), ctypes.get_errno()]
    try:
        os.memfd_create("m")
        found["memfd"] = "made"
    except OSError as exc:
        found["memfd"] = exc.errno
    # A child process still starts (the worker's own Python: the sandbox holds no other program).
    found["subprocess"] = subprocess.run([sys.executable, "-I", "-c", "pass"]).returncode
    return found

def boom():
    raise ValueError("bad input")

def forever():
    while True:
        pass

def sleepy():
    time.sleep(60)

def exit_quietly():
    sys.exit(0)

def hard_exit():
    os._exit(0)

def segfault():
    import ctypes
    ctypes.string_at(0)

def hog_memory():
    blocks = []
    while True:
        blocks.append(bytearray(100 * 1024 * 1024))

def fork_bomb():
    children = 0
    try:
        while True:
            if os.fork() == 0:
                time.sleep(30)
                os._exit(0)
            children += 1
    except OSError:
        return children

def read_file(path):
    with open(path) as handle:
        return handle.read()[:100]

def what_is_there(paths):
    """Per path: absent, empty (a folder or file mounted over it) or present."""
    found = {}
    for path in paths:
        if not os.path.lexists(path):
            found[path] = "absent"
        elif os.path.isdir(path):
            found[path] = "present" if os.listdir(path) else "empty"
        else:
            found[path] = "present" if os.path.getsize(path) else "empty"
    return found

def importable(names):
    import importlib
    found = {}
    for name in names:
        try:
            importlib.import_module(name)
            found[name] = "yes"
        except ImportError as exc:
            found[name] = f"no: {exc}"
    return found

def write_file(path):
    with open(path, "w") as handle:
        handle.write("pwned")
    return path

def import_reference():
    import solutions
    return "imported"

def leave_process():
    subprocess.Popen([sys.executable, "-c", "import time; time.sleep(300)"])  # no other program is there
    return os.getpid()

def count_processes():
    alive = 0
    for p in os.listdir("/proc"):
        if p.isdigit():
            with open(f"/proc/{p}/stat") as handle:
                alive += handle.read().rsplit(")", 1)[1].split()[0] != "Z"  # zombies hold no resources
    return alive

def whoami():
    return [os.getuid(), os.getcwd()]

def recurse(n=0):
    return recurse(n + 1)

class Sneaky:
    def __eq__(self, other):
        return True

def sneaky():
    return Sneaky()
'''


#: Channels between two submissions through what every sandbox mounts read-only: bits
#: as page-cache residency of a Python file (dropped with posix_fadvise, set by reading a
#: byte, read back with preadv2(RWF_NOWAIT) or mincore), bytes as the start offsets of
#: POSIX read locks on the venv's pyvenv.cfg (listed with F_GETLK), and sockets that
#: leave the sandbox's own network namespace (AF_VSOCK reaches the host).
CHANNELS = '''
import ctypes, fcntl, mmap, os, socket, struct, sys

PAGE = mmap.PAGESIZE
BITS = 16
held = []  # descriptors whose locks outlive the call

def cache_file():
    import pydoc_data
    return os.path.join(os.path.dirname(pydoc_data.__file__), "topics.py")

def write_cache(token):
    """Page k of the file in the page cache when bit k of token is set, else not."""
    fd = os.open(cache_file(), os.O_RDONLY)
    try:
        os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
        os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_RANDOM)  # no readahead: one page per read
        for k in range(BITS):
            if token >> k & 1:
                os.pread(fd, 1, k * PAGE)
        return "written"
    except OSError as exc:
        return f"refused: {exc}"
    finally:
        os.close(fd)

def read_cache():
    """The token as page-cache residency says it, by mincore and by preadv2(RWF_NOWAIT)."""
    fd = os.open(cache_file(), os.O_RDONLY)
    found = {}
    try:
        os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_RANDOM)
    except OSError:
        pass
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        libc.mmap.restype = ctypes.c_void_p
        libc.mmap.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_int, ctypes.c_int, ctypes.c_int,
                              ctypes.c_long]
        address = libc.mmap(None, BITS * PAGE, mmap.PROT_READ, mmap.MAP_SHARED, fd, 0)
        vector = ctypes.create_string_buffer(BITS)
        if libc.mincore(ctypes.c_void_p(address), ctypes.c_size_t(BITS * PAGE), vector) != 0:
            raise OSError(ctypes.get_errno(), os.strerror(ctypes.get_errno()))
        found["mincore"] = sum((vector.raw[k] & 1) << k for k in range(BITS))
    except OSError as exc:
        found["mincore"] = f"refused: {exc}"
    try:
        token = 0
        for k in range(BITS):
            try:
                if os.preadv(fd, [bytearray(1)], k * PAGE, os.RWF_NOWAIT) == 1:
                    token |= 1 << k
            except BlockingIOError:
                pass
        found["preadv2"] = token
    except OSError as exc:
        found["preadv2"] = f"refused: {exc}"
    os.close(fd)
    return found

def lock_file():
    return os.path.join(sys.prefix, "pyvenv.cfg")

def write_locks(token):
    """A read lock of one byte at offset token, held after the call returns."""
    fd = os.open(lock_file(), os.O_RDONLY)
    held.append(fd)
    try:
        fcntl.lockf(fd, fcntl.LOCK_SH | fcntl.LOCK_NB, 1, token)
        return "locked"
    except OSError as exc:
        return f"refused: {exc}"

def read_locks():
    """The start offset of a lock another process holds on the file, by F_GETLK."""
    fd = os.open(lock_file(), os.O_RDONLY)
    try:
        asked = struct.pack("hhqqi", fcntl.F_WRLCK, os.SEEK_SET, 0, 0, 0)
        kind, _, start, _, _ = struct.unpack("hhqqi", fcntl.fcntl(fd, fcntl.F_GETLK, asked))
        return start if kind != fcntl.F_UNLCK else "no lock seen"
    except OSError as exc:
        return f"refused: {exc}"
    finally:
        os.close(fd)

def other_sockets():
    found = {}
    for name in ("AF_VSOCK", "AF_INET", "AF_NETLINK", "AF_UNIX"):
        try:
            socket.socket(getattr(socket, name), socket.SOCK_DGRAM if name != "AF_VSOCK" else socket.SOCK_STREAM
                          ).close()
            found[name] = "made"
        except OSError as exc:
            found[name] = exc.errno
    try:
        fd = os.open(lock_file(), os.O_RDONLY)
        fcntl.flock(fd, fcntl.LOCK_SH)
        found["flock"] = "locked"
    except OSError as exc:
        found["flock"] = exc.errno
    return found
'''


@pytest.fixture(scope="module")
def package(tmp_path_factory):
    root = tmp_path_factory.mktemp("submission") / "exercises"
    root.mkdir()
    (root / "__init__.py").write_text("")
    (root / "hostile.py").write_text(textwrap.dedent(HOSTILE))
    (root / "channels.py").write_text(textwrap.dedent(CHANNELS))
    return root


@pytest.fixture(scope="module")
def sandbox(package):
    with Sandbox(package, Limits(call_timeout=5.0, memory_bytes=1024**3)) as box:
        yield box


@pytest.mark.skipif(os.uname().machine != "x86_64", reason="the seccomp filter is built for x86-64")
@pytest.mark.parametrize("isolation", ["plain", pytest.param("bwrap", marks=needs_bwrap)])
def test_seccomp_refuses_keyring_namespaces_and_memfd(package, isolation):
    with Sandbox(package, isolation=isolation) as box:
        result = box.call("exercises.hostile", "kernel_channels")
    assert result.status == "ok", result.message
    eperm = [-1, 1]
    assert result.value == {"keyctl": eperm, "add_key": eperm, "unshare_user": eperm, "clone_newuser": eperm,
                            "memfd": 1, "subprocess": 0}


#: Tokens of 16 bits sent from one submission to another (any two with a few bits set).
TOKENS = (0b1011_0010_1100_0101, 0b0100_1101_0011_1010)


@needs_bwrap
@pytest.mark.skipif(os.uname().machine != "x86_64", reason="the seccomp filter is built for x86-64")
def test_nothing_crosses_from_one_submission_to_a_later_one_through_the_page_cache(package):
    """Graded one after the other (the writer's sandbox closed), as in two batches."""
    for token in TOKENS:
        with Sandbox(package, slot=0, isolation="bwrap") as writer:
            wrote = writer.call("exercises.channels", "write_cache", [token])
        with Sandbox(package, slot=1, isolation="bwrap") as reader:
            found = reader.call("exercises.channels", "read_cache")
        assert wrote.status == found.status == "ok", (wrote.message, found.message)
        assert token not in found.value.values(), found.value
        assert wrote.value.startswith("refused") and "Operation not permitted" in wrote.value
        assert all(str(v).startswith("refused") for v in found.value.values()), found.value


@needs_bwrap
@pytest.mark.skipif(os.uname().machine != "x86_64", reason="the seccomp filter is built for x86-64")
def test_nothing_crosses_between_submissions_graded_together_through_file_locks(package):
    """Graded side by side (two slots, two users, as ``--jobs 2``): the writer's locks are held."""
    with Sandbox(package, slot=0, isolation="bwrap") as writer, \
            Sandbox(package, slot=1, isolation="bwrap") as reader:
        wrote = writer.call("exercises.channels", "write_locks", [TOKENS[0]])
        found = reader.call("exercises.channels", "read_locks")
        assert wrote.status == found.status == "ok", (wrote.message, found.message)
        assert found.value != TOKENS[0], "the reader read the writer's token"
        assert wrote.value.startswith("refused") and found.value.startswith("refused"), (wrote.value, found.value)
        sockets = reader.call("exercises.channels", "other_sockets")
    assert sockets.status == "ok", sockets.message
    assert sockets.value == {"AF_VSOCK": 1, "AF_INET": 1, "AF_NETLINK": 1, "AF_UNIX": "made", "flock": 1}


@needs_bwrap
def test_the_worker_has_a_user_namespace_of_its_own(package):
    with Sandbox(package, isolation="bwrap") as box:
        result = box.call("exercises.hostile", "user_namespace")
    assert result.status == "ok", result.message
    namespace, uid_map, uid = result.value
    assert namespace != os.readlink("/proc/self/ns/user")
    assert uid == box.uid and uid != 0
    # One line: the sandbox uid, seen from the namespace's parent, is the sandbox uid (never root).
    assert len(uid_map) == 3 and int(uid_map[0]) == uid and int(uid_map[2]) == 1


@needs_bwrap
def test_writable_folders_are_capped_and_the_package_is_read_only(package):
    with Sandbox(package, Limits(disk_bytes=32 * 1024**2), isolation="bwrap") as box:
        written, error = box.call("exercises.hostile", "fill_disk").value
        changed = box.call("exercises.hostile", "write_own_package").value
    assert written <= 32 * 1024**2 and error == 28  # ENOSPC
    assert changed == 30  # EROFS
    assert not (package / "hostile.py").read_text().endswith("# changed")


@pytest.mark.skipif(os.geteuid() != 0, reason="a memory cgroup needs root")
def test_the_total_memory_of_a_sandbox_is_capped(package):
    from grader.sandbox.memory_cage import MemoryCage

    probe = MemoryCage.create(64 * 1024**2, "grader-probe")
    if probe is None:
        pytest.skip("no writable memory cgroup on this machine")
    probe.close()
    limits = Limits(total_memory_bytes=400 * 1024**2, memory_bytes=1024**3)
    with Sandbox(package, limits) as box:
        killed = box.call("exercises.hostile", "hogs_together", [3, 250], timeout=30).value
    assert killed >= 1


def test_a_call_returns_plain_data(sandbox):
    result = sandbox.call("exercises.hostile", "add", [2, 3])
    assert result.status == "ok" and result.value == 5


def test_a_stub_says_not_implemented(sandbox):
    result = sandbox.call("exercises.hostile", "stub")
    # The message names the function that raised, inside the package: the stub to write.
    assert result.status == "not_implemented" and result.message == "not implemented yet: stub in hostile.py"


def test_an_exception_is_reported_with_the_students_traceback(sandbox):
    result = sandbox.call("exercises.hostile", "boom")
    assert result.status == "error" and "ValueError: bad input" in result.message and "hostile.py" in result.message


def test_printed_megabytes_are_capped(sandbox):
    result = sandbox.call("exercises.hostile", "loud")
    assert result.status == "ok" and len(result.output) < 20_000 and "more characters not shown" in result.output


def test_recursion_limit_is_an_error(sandbox):
    result = sandbox.call("exercises.hostile", "recurse")
    assert result.status == "error" and "recursion" in result.message


def test_an_object_with_a_lying_eq_cannot_pass_for_a_value(sandbox):
    result = sandbox.call("exercises.hostile", "sneaky")
    assert result.status == "unreadable"


@pytest.mark.parametrize("function", ["forever", "sleepy"])
def test_a_hang_times_out_and_the_next_call_works(sandbox, function):
    started = time.perf_counter()
    result = sandbox.call("exercises.hostile", function, timeout=1.0)
    assert result.status == "timeout" and time.perf_counter() - started < 5
    assert sandbox.call("exercises.hostile", "add", [1, 1]).value == 2


@pytest.mark.parametrize("function, words", [("exit_quietly", "sys.exit"), ("hard_exit", "exited"),
                                             ("segfault", "segmentation fault")])
def test_exits_and_crashes_cost_only_that_call(sandbox, function, words):
    result = sandbox.call("exercises.hostile", function)
    assert result.status in ("error", "crashed") and words in result.message
    assert sandbox.call("exercises.hostile", "add", [1, 2]).value == 3


def test_a_memory_bomb_is_stopped(sandbox):
    result = sandbox.call("exercises.hostile", "hog_memory", timeout=20.0)
    assert result.status in ("error", "crashed") and ("memory" in result.message.lower() or "killed" in result.message)
    assert sandbox.call("exercises.hostile", "add", [1, 2]).value == 3


@needs_bwrap
def test_a_fork_bomb_hits_the_process_limit(sandbox):
    result = sandbox.call("exercises.hostile", "fork_bomb", timeout=20.0)
    assert result.status == "ok" and result.value < 64


@needs_bwrap
def test_the_reference_solutions_cannot_be_read_or_imported(sandbox):
    result = sandbox.call("exercises.hostile", "read_file", [str(REPO / "solutions" / "shapes.py")])
    assert result.status == "error" and ("No such file" in result.message or "Permission" in result.message)
    assert sandbox.call("exercises.hostile", "read_file", [str(REPO / "grader" / "tests" / "hidden" / "test_grid.py")]).status == "error"
    assert sandbox.call("exercises.hostile", "import_reference").status == "error"


@needs_bwrap
def test_the_worker_sees_only_the_files_its_python_needs(sandbox):
    """No headers, static libraries, tests, compilers or shells, and no installed package
    the submission does not import; the standard library and its extension modules work."""
    import glob
    import sysconfig

    stdlib = Path(os.__file__).resolve().parent
    site = Path(sysconfig.get_paths()["purelib"])
    static = [*glob.glob("/usr/lib/*/*.a")[:2], *glob.glob(f"{stdlib}/config-*/libpython*.a"),
              *glob.glob(f"{site}/numpy/_core/lib/*.a")]
    left_out = [p for p in ["/usr/include", str(stdlib / "test"), str(site / "numpy" / "_core" / "tests"),
                            "/usr/bin/gcc", "/usr/bin/cc", "/bin/sh", str(site / "numpy"), *static]
                if os.path.exists(p)]
    assert static and str(stdlib / "test") in left_out and "/usr/include" in left_out, left_out
    result = sandbox.call("exercises.hostile", "what_is_there", [left_out])
    assert result.ok, result.message
    assert {p: s for p, s in result.value.items() if s not in ("absent", "empty")} == {}
    assert result.value["/usr/include"] == "absent" and result.value[static[0]] in ("absent", "empty")
    names = ["test.support", "numpy", "json", "decimal", "ssl", "sqlite3", "lzma", "ctypes", "multiprocessing"]
    result = sandbox.call("exercises.hostile", "importable", [names])
    assert result.ok, result.message
    assert [n for n in names if result.value[n] != "yes"] == ["test.support", "numpy"], result.value


@needs_bwrap
def test_writes_outside_the_sandbox_change_nothing(sandbox, tmp_path):
    target = tmp_path / "results.json"
    result = sandbox.call("exercises.hostile", "write_file", [str(target)])
    assert result.status == "error" or not target.exists()
    assert not target.exists()
    assert sandbox.call("exercises.hostile", "write_file", [str(REPO / "README.md")]).status == "error"


@needs_bwrap
def test_runs_as_an_unprivileged_user_in_its_own_folder(sandbox):
    result = sandbox.call("exercises.hostile", "whoami")
    assert result.status == "ok", (result.status, result.message)
    uid, cwd = result.value
    assert uid != 0 and uid != os.getuid() and cwd == "/sandbox"


@needs_bwrap
def test_no_process_outlives_the_call_or_the_sandbox(package):
    with Sandbox(package, slot=7) as box:
        assert box.call("exercises.hostile", "leave_process").status == "ok"
        uid = box.uid
        # The sandbox's /proc: bubblewrap's init, the bubblewrap holding the worker's user
        # and process namespaces, that namespace's init, and the worker; the process the
        # last call left behind is gone.
        assert box.call("exercises.hostile", "count_processes").value == 4
    time.sleep(0.5)
    leftovers = [p for p in os.listdir("/proc") if p.isdigit() and _uid_of(p) == uid]
    assert leftovers == []


def _uid_of(pid: str):
    try:
        with open(f"/proc/{pid}/status") as handle:
            for line in handle:
                if line.startswith("Uid:"):
                    return int(line.split()[1])
    except OSError:
        return None


def test_the_original_submission_is_never_changed(package):
    before = {p: p.read_bytes() for p in package.rglob("*.py")}
    with Sandbox(package) as box:
        box.call("exercises.hostile", "write_file", ["exercises/hostile.py"])
    assert {p: p.read_bytes() for p in package.rglob("*.py")} == before


@needs_bwrap
def test_a_python_installed_under_tmp_stays_visible(package, monkeypatch, tmp_path):
    # The sandbox's empty /tmp must be mounted before the Python folders are bound, or a
    # checkout (and its .venv) under /tmp, as in CI, would be hidden from the worker.
    from grader.sandbox import mounts

    venv = tmp_path / ".venv"
    venv.mkdir()
    assert str(venv).startswith("/tmp/")
    monkeypatch.setattr(mounts, "worker_mounts", lambda distributions: mounts.Mounts((), (str(venv),), (), (), {}))
    box = Sandbox(package)
    box.workdir = Path("/tmp/work")
    box._response_fd_in_child = 5
    command = box._command()
    tmpfs = command.index("--tmpfs")
    assert command[tmpfs + 1] == "/tmp"
    assert tmpfs < command.index(str(venv))


def test_a_sandbox_that_cannot_start_is_the_graders_failure_not_a_crash(package, monkeypatch):
    """A worker that dies before its hello line never ran student code (a folder out of
    its user's reach, a refused namespace): SandboxBroken, every later call too, and
    run_tests gives no result at all rather than a column of "crashed"."""
    from grader.harness.run import run_tests
    from grader.sandbox.process import SandboxBroken
    from grader.harness.run import load_spec

    broken = [sys.executable, "-c", "import sys; sys.stderr.write('cannot open worker.py'); sys.exit(2)"]
    monkeypatch.setattr(Sandbox, "_command", lambda self: broken)
    with Sandbox(package, Limits(call_timeout=5.0)) as box:
        for _ in range(2):
            with pytest.raises(SandboxBroken, match="(?s)before running any student code.*cannot open worker.py"):
                box.call("exercises.hostile", "anything")
        assert box.restarts == 0   # not restarted for each call
    tests = [t for t in load_spec() if t.exercise == "momentum"][:3]
    with pytest.raises(SandboxBroken):
        run_tests(package.parent, tests, Limits(call_timeout=5.0))



def test_every_sandbox_of_a_process_isolates_as_one_decision_says(package, monkeypatch):
    """`grader check`, a batch, a direct pytest run: the sandbox decides, once per process."""
    from grader.sandbox import isolation

    trials = []
    monkeypatch.setattr(isolation, "bwrap_works", lambda: trials.append(1) or False)
    monkeypatch.setattr(isolation, "bwrap_available", lambda: True)
    isolation.decided_isolation.cache_clear()
    try:
        boxes = [Sandbox(package, Limits(call_timeout=5.0)) for _ in range(3)]
        assert [box.isolation for box in boxes] == ["plain"] * 3   # bubblewrap refused here: the fallback
        assert len(trials) == 1
        # What a batch decided and handed to its workers is not tried again (a busy moment
        # must not turn a grading worker's sandbox into an error).
        assert isolation.decided_isolation("bwrap") == "bwrap" and len(trials) == 1
        for box in boxes:
            box.close()
    finally:
        isolation.decided_isolation.cache_clear()


def test_a_kept_argument_crosses_the_channel_once_per_worker_and_each_call_gets_a_fresh_copy(package):
    """A large scene read by several calls (grader.sandbox.kept): sent with the first
    request, referred to by its key after, sent again to a restarted worker."""
    from grader.sandbox.kept import KeptArgument

    rows = [[float(4 * i + k) for k in range(4)] for i in range(1000)]
    kept = KeptArgument("scene", lambda: [list(row) for row in rows], 4000)
    with Sandbox(package, Limits(call_timeout=5.0)) as box:
        sent = []
        send = box._send
        box._send = lambda data, deadline: sent.append(data) or send(data, deadline)
        results = [box.call("exercises.hostile", "total_then_zero", [kept]) for _ in range(2)]
        box.start()                       # a new worker process holds nothing
        results.append(box.call("exercises.hostile", "total_then_zero", [kept]))
    assert [(r.status, r.value) for r in results] == [("ok", float(sum(map(sum, rows))))] * 3, results
    assert [b'"$keep"' in data for data in sent] == [True, False, True]
    assert len(sent[1]) < 400 < len(sent[0])
