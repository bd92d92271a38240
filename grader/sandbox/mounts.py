"""The files a bubblewrap worker sees: what its Python needs to run the graded code, and
nothing else of the machine.

Bound read-only, each at its own path:

- the interpreter (the venv's ``python`` and the symbolic links leading to the real
  binary, ``pyvenv.cfg``), the standard library and its extension modules;
- from the venv's site-packages, only the distributions the graded package imports
  (its ``import`` statements, read by :func:`imported_names`) and what they require;
- the shared libraries all of these load: the ELF closure of the interpreter, of every
  extension module bound and of the two programs the sandbox runs before Python
  (``setpriv``, the second ``bwrap``), read from their ``DT_NEEDED`` entries;
- ``/etc/ld.so.cache``, the loader's configuration, ``/etc/localtime``, the C.UTF-8 locale.

Left out inside those folders (an empty folder or file is mounted over them): test
folders (``test``, ``tests``, ``idle_test``) and test extension modules, header folders
(``include``), static libraries (``*.a``) and the parts of the standard library no
graded code runs (IDLE, Tk, ``ensurepip`` and its wheels, the ``config-*`` build folder).  ``/usr/include``,
compilers, shells and every other program are simply absent.

Where the ELF files cannot be read (not 64-bit little-endian), :func:`worker_mounts`
returns None and the sandbox binds the system folders whole, as before.
"""
from __future__ import annotations

import functools
import glob
import importlib.metadata
import os
import re
import shutil
import struct
import sys
import sysconfig
from dataclasses import dataclass
from pathlib import Path

#: Folders of the standard library, site-packages and bound packages that are never mounted.
LEFT_OUT_FOLDERS = frozenset({"test", "tests", "idle_test", "include", "idlelib", "tkinter", "turtledemo",
                              "ensurepip", "site-packages", "dist-packages", "__phello__"})
LEFT_OUT_FOLDER_PREFIXES = ("config-",)  # the standard library's build folder: libpythonX.Y.a, Makefile
LEFT_OUT_SUFFIXES = (".a",)  # static libraries (headers: the include folders)
#: Extension modules of the standard library left out: its tests' and Tk's (Tk would pull
#: in X11 and fonts).
LEFT_OUT_MODULES = ("_test", "_ctypes_test", "_xxtestfuzz", "xxlimited", "xxsubtype", "_tkinter")
#: Files of /etc the loader and Python read.
ETC_FILES = ("/etc/ld.so.cache", "/etc/ld.so.conf", "/etc/ld.so.conf.d", "/etc/localtime")
LOCALES = ("/usr/lib/locale/C.utf8", "/usr/lib/locale/C.UTF-8")
#: Programs the sandbox runs before the worker's Python (grader.sandbox.process).
PROGRAMS = ("setpriv", "bwrap")
SYMLINK_HOPS = 40

IMPORT_LINE = re.compile(r"(?:^|;)[ \t]*(?:from[ \t]+([A-Za-z_]\w*)|import[ \t]+([^#;\n]+))", re.MULTILINE)
REQUIREMENT_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*")


@dataclass(frozen=True)
class Mounts:
    """What :meth:`grader.sandbox.process.Sandbox._command` binds.

    ``links``: ``(target, path)`` symbolic links on the way to a bound path (``/lib64 ->
    usr/lib64``); ``binds``: real paths bound read-only at the same path, parents before
    children; ``hidden_folders`` / ``hidden_files``: paths inside them that an empty
    folder or file is mounted over."""

    links: tuple[tuple[str, str], ...]
    binds: tuple[str, ...]
    hidden_folders: tuple[str, ...]
    hidden_files: tuple[str, ...]
    programs: dict


def imported_names(package: Path) -> frozenset[str]:
    """First parts of the module names the ``.py`` files under ``package`` import
    (``from numpy.linalg import norm`` -> ``numpy``), relative imports left out.

    Read by a regular expression, not parsed: a name in a string or comment only adds a
    distribution to what is mounted, and a file that does not parse is still read."""
    names: set[str] = set()
    for path in Path(package).rglob("*.py"):
        try:
            text = path.read_text(encoding="utf-8", errors="replace")
        except OSError:
            continue
        for match in IMPORT_LINE.finditer(text):
            if match.group(1):
                names.add(match.group(1))
                continue
            for part in match.group(2).split(","):
                words = part.strip().strip("()").split()
                if words and re.fullmatch(r"[A-Za-z_][\w.]*", words[0]):
                    names.add(words[0].split(".")[0])
    return frozenset(names)


def _site_packages() -> list[str]:
    paths = sysconfig.get_paths()
    return sorted({os.path.realpath(paths[k]) for k in ("purelib", "platlib") if os.path.isdir(paths[k])})


@functools.lru_cache(maxsize=1)
def _site_entries() -> dict[str, frozenset[str]]:
    """``{site-packages folder: names in it}``."""
    return {site: frozenset(os.listdir(site)) for site in _site_packages()}


def _normal(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


@functools.lru_cache(maxsize=1)
def _metadata_folders() -> dict[str, str]:
    """``{distribution (normalised name): its .dist-info or .egg-info folder}``."""
    found: dict[str, str] = {}
    for site, entries in _site_entries().items():
        for entry in sorted(entries):
            if entry.endswith((".dist-info", ".egg-info")):
                found.setdefault(_normal(entry.rsplit(".", 1)[0].split("-", 1)[0]), os.path.join(site, entry))
    return found


@functools.lru_cache(maxsize=256)
def _distribution(name: str):
    """The installed distribution called ``name`` (normalised), or None."""
    folder = _metadata_folders().get(name)
    return None if folder is None else importlib.metadata.PathDistribution(Path(folder))


def _top_levels(dist) -> set[str]:
    """Names in site-packages a distribution installed (packages, modules, their
    ``.libs`` folder, its ``.dist-info``)."""
    tops = {f.parts[0] for f in (dist.files or []) if f.parts and f.parts[0] not in ("..", "__pycache__")}
    return {t for t in tops if not t.endswith(".pth")}


def _installed(module: str) -> bool:
    """True if ``module`` is a package or module of the worker's site-packages."""
    return any(module in entries or f"{module}.py" in entries
               or any(e.startswith(f"{module}.") and e.endswith(".so") for e in entries)
               for entries in _site_entries().values())


@functools.lru_cache(maxsize=1)
def _providers() -> dict[str, set[str]]:
    """``{top-level name: {distribution}}`` of every installed distribution (read only
    when a module's distribution is not named like it: ``yaml`` of ``PyYAML``)."""
    by_name: dict[str, set[str]] = {}
    for name in _metadata_folders():
        for top in _top_levels(_distribution(name)):
            by_name.setdefault(Path(top).stem if top.endswith(".py") else top.split(".")[0], set()).add(name)
    return by_name


def distributions_for(names: frozenset[str]) -> frozenset[str]:
    """The installed distributions providing the modules ``names`` and, recursively, what
    they require (normalised names)."""
    todo: list[str] = []
    for module in sorted(names):
        if not _installed(module):
            continue   # the standard library's, or not installed
        dist = _distribution(_normal(module))
        if dist is not None and module in {t.split(".")[0] for t in _top_levels(dist)}:
            todo.append(_normal(module))
        else:
            todo += sorted(_providers().get(module, ()))
    chosen: set[str] = set()
    while todo:
        name = todo.pop()
        dist = _distribution(name)
        if name in chosen or dist is None:
            continue
        chosen.add(name)
        for requirement in dist.requires or []:
            if re.search(r"\bextra\s*==", requirement):
                continue
            match = REQUIREMENT_NAME.match(requirement)
            if match:
                todo.append(_normal(match.group()))
    return frozenset(chosen)


# Paths and symbolic links --------------------------------------------------------------------
def _resolved(path: str, links: dict[str, str]) -> str:
    """The real path of ``path``; each symbolic link met on the way is added to
    ``links`` (``{link path: target}``), so the path works inside the sandbox too."""
    parts = list(Path(os.path.abspath(path)).parts[1:])
    current = "/"
    hops = 0
    while parts:
        candidate = os.path.join(current, parts.pop(0))
        if os.path.islink(candidate) and hops < SYMLINK_HOPS:
            hops += 1
            target = os.readlink(candidate)
            links[candidate] = target
            parts = list(Path(os.path.normpath(os.path.join(current, target))).parts[1:]) + parts
            current = "/"
        else:
            current = candidate
    return current


# ELF -------------------------------------------------------------------------------------------
PT_INTERP, PT_DYNAMIC, PT_LOAD = 3, 2, 1
DT_NEEDED, DT_STRTAB, DT_RPATH, DT_RUNPATH = 1, 5, 15, 29


class NotReadable(Exception):
    """Not an ELF file this module reads (64-bit little-endian)."""


def elf_dependencies(path: str) -> tuple[list[str], list[str], str | None] | None:
    """``(needed sonames, run paths, program interpreter)`` of an ELF file; None if
    ``path`` is no ELF file, NotReadable if it is one of another kind."""
    with open(path, "rb") as handle:
        header = handle.read(64)
        if header[:4] != b"\x7fELF":
            return None
        if header[4] != 2 or header[5] != 1:
            raise NotReadable(f"{path}: not a 64-bit little-endian ELF file")
        phoff, = struct.unpack_from("<Q", header, 0x20)
        phentsize, phnum = struct.unpack_from("<HH", header, 0x36)
        handle.seek(phoff)
        table = handle.read(phentsize * phnum)
        segments = [struct.unpack_from("<IIQQQQQQ", table, i * phentsize) for i in range(phnum)]
        interpreter = None
        dynamic = []
        for kind, _, offset, vaddr, _, filesz, _, _ in segments:
            if kind == PT_INTERP:
                handle.seek(offset)
                interpreter = handle.read(filesz).split(b"\0")[0].decode()
            elif kind == PT_DYNAMIC:
                handle.seek(offset)
                data = handle.read(filesz)
                dynamic = [struct.unpack_from("<qQ", data, i) for i in range(0, len(data) - 15, 16)]
        strtab = next((value for tag, value in dynamic if tag == DT_STRTAB), None)
        if strtab is None:
            return [], [], interpreter
        base = next((offset + strtab - vaddr for kind, _, offset, vaddr, _, filesz, _, _ in segments
                     if kind == PT_LOAD and vaddr <= strtab < vaddr + filesz), None)
        if base is None:
            return [], [], interpreter

        def string(at: int) -> str:
            handle.seek(base + at)
            return handle.read(4096).split(b"\0")[0].decode("utf-8", "replace")

        needed = [string(value) for tag, value in dynamic if tag == DT_NEEDED]
        origin = os.path.dirname(os.path.realpath(path))
        runpaths = [folder.replace("$ORIGIN", origin).replace("${ORIGIN}", origin)
                    for tag, value in dynamic if tag in (DT_RPATH, DT_RUNPATH)
                    for folder in string(value).split(":") if folder]
        return needed, runpaths, interpreter


@functools.lru_cache(maxsize=1)
def library_folders() -> tuple[str, ...]:
    """The loader's folders: those of /etc/ld.so.conf (and what it includes), then the
    default ones."""
    folders: list[str] = []

    def read(conf: str, depth: int = 0) -> None:
        try:
            lines = Path(conf).read_text().splitlines()
        except OSError:
            return
        for line in lines:
            line = line.split("#", 1)[0].strip()
            if line.startswith("include ") and depth < 4:
                for included in sorted(glob.glob(line.split(None, 1)[1])):
                    read(included, depth + 1)
            elif line.startswith("/"):
                folders.append(line)

    read("/etc/ld.so.conf")
    arch = getattr(sys.implementation, "_multiarch", "") or ""
    folders += [f"/lib/{arch}", f"/usr/lib/{arch}"] if arch else []
    folders += ["/lib64", "/usr/lib64", "/lib", "/usr/lib"]
    return tuple(dict.fromkeys(f for f in folders if os.path.isdir(f)))


def elf_closure(programs: list[str], files: list[str], links: dict[str, str]) -> set[str]:
    """Real paths of the shared libraries ``programs`` and ``files`` load, directly or
    not (and their program interpreter); links on the way are added to ``links``.

    NotReadable if a program is no ELF file this module reads; a file of ``files`` that
    is none (a data file named like a library, another architecture's) is skipped."""
    seen: set[str] = set()
    todo = [os.path.realpath(f) for f in files]
    for program in programs:
        if elf_dependencies(program) is None:
            raise NotReadable(program)
        todo.append(os.path.realpath(program))
    libraries: set[str] = set()
    while todo:
        path = todo.pop()
        if path in seen:
            continue
        seen.add(path)
        try:
            found_here = elf_dependencies(path)
        except NotReadable:
            if path in programs:
                raise
            continue
        if found_here is None:
            continue
        needed, runpaths, interpreter = found_here
        wanted = [(name, runpaths) for name in needed]
        if interpreter:
            found = _resolved(interpreter, links)
            libraries.add(found)
            todo.append(found)
        for name, folders in wanted:
            candidates = [name] if "/" in name else [os.path.join(f, name) for f in [*folders, *library_folders()]]
            for candidate in candidates:
                if os.path.isfile(candidate):
                    found = _resolved(candidate, links)
                    libraries.add(found)
                    todo.append(found)
                    break
    return libraries


# The mount list --------------------------------------------------------------------------------
def _hidden_inside(root: str) -> tuple[list[str], list[str], list[str], list[str]]:
    """``(folders, files, ELF files, outside)`` under ``root``: the folders and files left
    out, the shared objects kept (extension modules, bundled libraries) and the targets
    of symbolic links leading out of ``root`` (Debian's ``sitecustomize.py``)."""
    folders, files, shared, outside = [], [], [], []
    prefix = root.rstrip("/") + "/"
    for top, dirs, names in os.walk(root):
        for name in [*dirs, *names]:
            path = os.path.join(top, name)
            if os.path.islink(path) and not os.path.realpath(path).startswith(prefix) and os.path.exists(path):
                outside.append(path)
        for name in list(dirs):
            if name in LEFT_OUT_FOLDERS or name.startswith(LEFT_OUT_FOLDER_PREFIXES):
                folders.append(os.path.join(top, name))
                dirs.remove(name)
        for name in names:
            path = os.path.join(top, name)
            if name.endswith(LEFT_OUT_SUFFIXES) or (name.endswith(".so") and name.startswith(LEFT_OUT_MODULES)):
                files.append(path)
            elif (".so" in name or name.endswith(".dylib")) and not os.path.islink(path):
                shared.append(path)
    return folders, files, shared, outside


@functools.lru_cache(maxsize=64)
def _tree(root: str) -> tuple[tuple[str, ...], ...]:
    return tuple(map(tuple, _hidden_inside(root)))


def standard_library() -> list[str]:
    """The folders of the standard library and its extension modules (real paths)."""
    folders = [os.path.dirname(os.path.realpath(os.__file__))]
    dynload = sysconfig.get_config_var("DESTSHARED") or ""
    folders += [p for p in sys.path if p.endswith("lib-dynload")] + ([dynload] if dynload else [])
    return list(dict.fromkeys(os.path.realpath(f) for f in folders if os.path.isdir(f)))


@functools.lru_cache(maxsize=32)
def worker_mounts(distributions: frozenset[str]) -> Mounts | None:
    """What a worker whose package uses ``distributions`` (:func:`distributions_for`)
    needs mounted; None where the ELF files cannot be read (the caller binds the system
    folders whole)."""
    links: dict[str, str] = {}
    binds: list[str] = []
    executable = _resolved(sys.executable, links)
    binds.append(executable)
    config = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(sys.executable))), "pyvenv.cfg")
    if os.path.isfile(config):
        binds.append(_resolved(config, links))
    trees = standard_library()
    for name in sorted(distributions):
        dist = _distribution(name)
        if dist is None:
            continue
        site = os.path.realpath(str(dist.locate_file("")))
        trees += [os.path.join(site, top) for top in sorted(_top_levels(dist))
                  if os.path.exists(os.path.join(site, top))]
    trees = [t for t in dict.fromkeys(trees) if not any(t.startswith(o.rstrip("/") + "/") for o in trees)]
    hidden_folders: list[str] = []
    hidden_files: list[str] = []
    shared: list[str] = []
    outside: list[str] = []
    for tree in trees:
        if os.path.isdir(tree):
            folders, files, objects, leaving = _tree(tree)
            hidden_folders += folders
            hidden_files += files
            shared += objects
            outside += [_resolved(os.path.realpath(link), links) for link in leaving]
        elif tree.endswith(".so"):
            shared.append(tree)
    programs = {name: shutil.which(name, path="/usr/bin:/bin:/usr/sbin:/sbin") for name in PROGRAMS}
    programs = {name: _resolved(path, links) for name, path in programs.items() if path}
    try:
        libraries = elf_closure([executable, *programs.values()], shared, links)
    except (NotReadable, OSError, struct.error, ValueError):
        return None
    inside = tuple(t.rstrip("/") + "/" for t in trees)
    binds += trees + outside + sorted(programs.values()) + sorted(lib for lib in libraries if not lib.startswith(inside))
    for name in (*ETC_FILES, *LOCALES):
        if os.path.exists(name):
            binds.append(_resolved(name, links) if name.startswith("/usr/") else name)
    # Parents first, then by path, each once; a path inside a bound folder needs no bind.
    ordered: list[str] = []
    for path in sorted(dict.fromkeys(binds), key=lambda p: (p.count("/"), p)):
        if not any(path.startswith(done.rstrip("/") + "/") for done in ordered if os.path.isdir(done)):
            ordered.append(path)
    kept_links = tuple(sorted((target, link) for link, target in links.items()
                              if not any(link.startswith(b.rstrip("/") + "/") for b in ordered)))
    return Mounts(kept_links, tuple(ordered), tuple(hidden_folders), tuple(hidden_files), programs)
