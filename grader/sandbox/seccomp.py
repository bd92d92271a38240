"""A seccomp filter for the student worker: system calls it has no need of fail.

Student code may compute, allocate, print and fork (the sandbox's process limit caps
that); it may not reach the kernel keyring (a channel to a later submission under
another uid), make namespaces (``unshare``, ``setns``, ``clone`` with a ``CLONE_NEW*``
flag: a way around the sandbox's users and mounts), mount, trace other processes,
load BPF programs or kernel modules, or create anonymous memory files
(``memfd_create``, memory outside the address-space limit).  Nor may it open a
channel to another submission through what sandboxes share (the kernel's page cache,
file locks and watches on the read-only system files every sandbox mounts, sockets
that leave the sandbox's own network namespace): ``mincore``, ``cachestat``,
``fadvise64``, ``readahead``, ``preadv2``/``pwritev2`` (``RWF_NOWAIT`` reads page-cache
residency), ``madvise`` with ``MADV_COLD``/``MADV_PAGEOUT`` (evict a file's pages),
``flock``, the lock, lease and notify commands of ``fcntl`` (``F_GETLK``, ``F_SETLK``,
``F_SETLKW``, ``F_OFD_*``, ``F_SETLEASE``, ``F_NOTIFY``), ``inotify`` and ``fanotify``,
and ``socket``/``socketpair`` of any family but ``AF_UNIX`` (``AF_VSOCK`` reaches the
host).  Python, numpy and the standard library's pure-computation modules need none of
them.  Those calls return ``EPERM``; ``clone3``, whose flags live in memory a filter cannot read, returns
``ENOSYS`` so that the C library falls back to ``clone``, whose flags it can.

The filter is a classic BPF program built here by hand (no library needed), for
x86-64 only; on another architecture :func:`filter_program` returns None and the
sandbox says so.  32-bit and x32 system calls are refused outright.  It is loaded by
bubblewrap (``--seccomp FD``) or, without bubblewrap, by :func:`install` between
fork and exec.
"""
from __future__ import annotations

import ctypes
import errno
import platform
import struct

AUDIT_ARCH_X86_64 = 0xC000003E
X32_SYSCALL_BIT = 0x40000000
SECCOMP_RET_ALLOW = 0x7FFF0000
SECCOMP_RET_ERRNO = 0x00050000
# struct seccomp_data: nr (u32) at 0, arch (u32) at 4, args[6] (u64) from 16 (little endian).
NR_OFFSET, ARCH_OFFSET = 0, 4


def arg_low_offset(index: int) -> int:
    """Offset of the low 32 bits of system-call argument ``index`` in struct seccomp_data."""
    return 16 + 8 * index
# Classic BPF opcodes.
LD_W_ABS = 0x20
JEQ_K = 0x15
JGE_K = 0x35
JSET_K = 0x45
JA = 0x05
RET_K = 0x06

#: x86-64 numbers of the refused system calls.
DENIED_X86_64 = {
    "ptrace": 101, "syslog": 103, "pivot_root": 155, "acct": 163, "settimeofday": 164, "mount": 165,
    "umount2": 166, "swapon": 167, "swapoff": 168, "reboot": 169, "init_module": 175, "delete_module": 176,
    "quotactl": 179, "kexec_load": 246, "add_key": 248, "request_key": 249, "keyctl": 250, "unshare": 272,
    "perf_event_open": 298, "name_to_handle_at": 303, "open_by_handle_at": 304, "setns": 308,
    "process_vm_readv": 310, "process_vm_writev": 311, "finit_module": 313, "memfd_create": 319, "bpf": 321,
    "userfaultfd": 323, "kexec_file_load": 320, "io_uring_setup": 425, "open_tree": 428, "move_mount": 429,
    "fsopen": 430, "fsconfig": 431, "fsmount": 432, "fspick": 433, "mount_setattr": 442, "memfd_secret": 447,
    # Channels between sandboxes through shared files and the page cache (module docstring).
    "mincore": 27, "flock": 73, "readahead": 187, "fadvise64": 221, "inotify_init": 253, "inotify_add_watch": 254,
    "inotify_init1": 294, "fanotify_init": 300, "fanotify_mark": 301, "preadv2": 327, "pwritev2": 328,
    "cachestat": 451,
}
CLONE_X86_64 = 56
CLONE3_X86_64 = 435
FCNTL_X86_64 = 72
MADVISE_X86_64 = 28
SOCKET_X86_64, SOCKETPAIR_X86_64 = 41, 53
AF_UNIX = 1
#: fcntl commands refused (second argument): POSIX locks (F_GETLK 5, F_SETLK 6, F_SETLKW 7),
#: open-file-description locks (F_OFD_GETLK 36, F_OFD_SETLK 37, F_OFD_SETLKW 38), leases
#: (F_SETLEASE 1024) and directory notification (F_NOTIFY 1026): each lets one sandbox
#: see another's use of a file both mount.
FCNTL_DENIED_COMMANDS = (5, 6, 7, 36, 37, 38, 1024, 1026)
#: madvise advice refused (third argument): MADV_COLD 20, MADV_PAGEOUT 21 evict a shared
#: file's pages from the page cache.
MADVISE_DENIED_ADVICE = (20, 21)
#: clone() flags that make a namespace.
CLONE_NEW_FLAGS = (0x00020000 | 0x02000000 | 0x04000000 | 0x08000000 | 0x10000000 | 0x20000000 | 0x40000000
                   | 0x00000080)  # NEWNS, NEWCGROUP, NEWUTS, NEWIPC, NEWUSER, NEWPID, NEWNET, NEWTIME


def _op(code: int, k: int, jt: int = 0, jf: int = 0) -> bytes:
    return struct.pack("<HBBI", code, jt, jf, k)


def filter_program() -> bytes | None:
    """The filter as raw ``struct sock_filter`` records, or None off x86-64."""
    if platform.machine() not in ("x86_64", "AMD64", "amd64"):
        return None
    denied = sorted(DENIED_X86_64.values())
    # (code, k, jump-true label or None, jump-false label or None); a str alone is a label.
    body: list = []
    body.append((LD_W_ABS, ARCH_OFFSET, None, None))
    body.append((JEQ_K, AUDIT_ARCH_X86_64, None, "deny"))  # fall through when x86-64
    body.append((LD_W_ABS, NR_OFFSET, None, None))
    body.append((JGE_K, X32_SYSCALL_BIT, "deny", None))
    for number in denied:
        body.append((JEQ_K, number, "deny", None))
    body.append((JEQ_K, CLONE3_X86_64, "enosys", None))
    body.append((JEQ_K, CLONE_X86_64, "clone", None))
    body.append((JEQ_K, FCNTL_X86_64, "fcntl", None))
    body.append((JEQ_K, MADVISE_X86_64, "madvise", None))
    body.append((JEQ_K, SOCKET_X86_64, "socket", None))
    body.append((JEQ_K, SOCKETPAIR_X86_64, "socket", "allow"))
    body.append("clone")
    body.append((LD_W_ABS, arg_low_offset(0), None, None))
    body.append((JSET_K, CLONE_NEW_FLAGS, "deny", "allow"))
    body.append("fcntl")
    body.append((LD_W_ABS, arg_low_offset(1), None, None))
    for command in FCNTL_DENIED_COMMANDS:
        body.append((JEQ_K, command, "deny", None))
    body.append((JA, 0, "allow", None))
    body.append("madvise")
    body.append((LD_W_ABS, arg_low_offset(2), None, None))
    for advice in MADVISE_DENIED_ADVICE:
        body.append((JEQ_K, advice, "deny", None))
    body.append((JA, 0, "allow", None))
    body.append("socket")
    body.append((LD_W_ABS, arg_low_offset(0), None, None))
    body.append((JEQ_K, AF_UNIX, "allow", "deny"))
    labels: dict[str, int] = {}
    instructions = []
    for item in body:
        if isinstance(item, str):
            labels[item] = len(instructions)
        else:
            instructions.append(item)
    labels.update({"allow": len(instructions), "deny": len(instructions) + 1, "enosys": len(instructions) + 2})
    out = []
    for index, (code, k, true, false) in enumerate(instructions):
        if code == JA:  # an unconditional jump: its offset is k
            k, true = labels[true] - index - 1, None
        jt = labels[true] - index - 1 if true else 0
        jf = labels[false] - index - 1 if false else 0
        if not (0 <= jt < 256 and 0 <= jf < 256 and k >= 0):
            raise AssertionError("seccomp filter jump out of range")
        out.append(_op(code, k, jt, jf))
    out.append(_op(RET_K, SECCOMP_RET_ALLOW))
    out.append(_op(RET_K, SECCOMP_RET_ERRNO | errno.EPERM))
    out.append(_op(RET_K, SECCOMP_RET_ERRNO | errno.ENOSYS))
    return b"".join(out)


class _SockFprog(ctypes.Structure):
    _fields_ = [("len", ctypes.c_ushort), ("filter", ctypes.c_void_p)]


PR_SET_NO_NEW_PRIVS = 38
PR_SET_SECCOMP = 22
SECCOMP_MODE_FILTER = 2


def install(program: bytes) -> None:
    """Load ``program`` into this process (irreversible; children inherit it)."""
    libc = ctypes.CDLL(None, use_errno=True)
    if libc.prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_NO_NEW_PRIVS) failed")
    buffer = ctypes.create_string_buffer(program, len(program))
    fprog = _SockFprog(len(program) // 8, ctypes.cast(buffer, ctypes.c_void_p))
    if libc.prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, ctypes.byref(fprog), 0, 0) != 0:
        raise OSError(ctypes.get_errno(), "prctl(PR_SET_SECCOMP) failed")
