r"""What the trusted side reads in a submission's source before it is graded.

Grading runs the student's package in a sandbox, and the package decides there what
it does: it may ship the stubs and still answer well, from a payload it unlocks only
when it sees the grader (an encrypted copy of working code and a meta-path finder,
switched on by the sandbox's cwd, argv or pid).  Behaviour must come from the source
handed in, so before a test runs this module parses the submitted files (never
imports them) and gives:

- :func:`withheld_functions`: the exercise functions whose submitted source is still
  the stub handed out (a body of a docstring and ``raise NotImplementedError``), or
  that no statement of the submitted module defines at all.  The sandbox answers a
  call of one "not implemented" without asking the worker
  (:class:`grader.sandbox.process.Sandbox` ``withheld``): its tests score zero
  whatever the package does at run time.
- :func:`suspicious_lines`: every line of the submitted files (those that differ from
  the course's) that runs code the source does not show (``exec``, ``eval``,
  ``compile``, ``__import__``, ``marshal``, ``pickle``, code objects), installs import
  machinery (``sys.meta_path``, ``sys.path_hooks``, ``sys.path``, ``sys.modules``,
  ``importlib``, ``zipimport``), reaches native code (``ctypes``) or reads its
  environment in a way that can tell grading from a student's own run (``os.environ``,
  ``sys.argv``, ``os.getpid``/``getppid``, ``/proc``, the current folder, the call
  stack).  These are flagged for the instructor with ``file:line`` (results.json's
  top-level ``extra_data["source_flags"]`` and the class report); a flag is a reason to
  read the code, not a verdict, and costs no points by itself.

Both are pure functions of the files: fast (milliseconds for a package) and unaffected
by anything the package does when run.

>>> import ast
>>> is_stub(ast.parse("def f(x):\n    'Doc.'\n    raise NotImplementedError('f')\n").body[0])
True
>>> is_stub(ast.parse("def f(x):\n    return x\n").body[0])
False
"""
from __future__ import annotations

import ast
from pathlib import Path

from .submissions import files_with_header

#: First words of an exercise file (the header tools/generate_exercises.py writes).
EXERCISE_HEADER = "# Exercise file of the collision course"
#: Why a stubbed function earns nothing (shown in the test's message).
STUB_REASON = ("the source you handed in is still the stub (its body raises NotImplementedError): what is "
               "graded must come from your source")
MISSING_REASON = ("no statement of the source you handed in defines it (a function that appears only at run "
                  "time is not graded)")

#: Calls of these builtins run code that is not in the source.
CODE_BUILTINS = {"exec": "exec() runs code that is not in the source",
                 "eval": "eval() runs code that is not in the source",
                 "compile": "compile() builds code that is not in the source",
                 "__import__": "__import__() imports by a computed name",
                 "breakpoint": "breakpoint()"}
#: Modules whose import alone is flagged.
FLAGGED_MODULES = {"marshal": "marshal loads compiled code", "ctypes": "ctypes reaches native code",
                   "importlib": "importlib machinery", "zipimport": "zipimport imports from an archive",
                   "imp": "imp import machinery", "pickle": "pickle can run code while loading",
                   "types": "types builds functions and code objects", "inspect": "inspect reads the call stack",
                   "gc": "gc reaches every object of the process", "builtins": "builtins can replace Python's own",
                   "cffi": "cffi reaches native code", "_imp": "_imp import machinery"}
#: Attributes (module.attribute, after import aliases) flagged where they are used.
FLAGGED_ATTRIBUTES = {
    "sys.meta_path": "sys.meta_path: an import hook", "sys.path_hooks": "sys.path_hooks: an import hook",
    "sys.path": "sys.path: where imports come from", "sys.modules": "sys.modules: replaces imported modules",
    "sys.path_importer_cache": "sys.path_importer_cache: an import hook",
    "sys.argv": "sys.argv: tells how it is run", "sys.orig_argv": "sys.orig_argv: tells how it is run",
    "sys._getframe": "sys._getframe: reads the caller", "sys.executable": "sys.executable: tells how it is run",
    "os.environ": "os.environ: reads its environment", "os.environb": "os.environb: reads its environment",
    "os.getenv": "os.getenv: reads its environment", "os.getpid": "os.getpid: tells which process runs it",
    "os.getppid": "os.getppid: tells which process runs it", "os.getcwd": "os.getcwd: checks the current folder",
    "os.getuid": "os.getuid: tells which user runs it", "os.uname": "os.uname: tells which machine runs it",
    "os.listdir": "os.listdir: reads folders", "os.scandir": "os.scandir: reads folders",
    "Path.cwd": "Path.cwd: checks the current folder", "pathlib.Path.cwd": "Path.cwd: checks the current folder",
    "socket.gethostname": "socket.gethostname: tells which machine runs it",
}
#: Attribute names flagged whatever they are read from (code objects and import state).
FLAGGED_NAMES = {"__code__": "__code__: replaces a function's code", "__loader__": "__loader__: import machinery",
                 "__builtins__": "__builtins__: replaces Python's own functions",
                 "f_back": "f_back: reads the caller's frame", "f_globals": "f_globals: reads the caller's frame"}
#: Text in a string constant that reads the machine's state.
FLAGGED_TEXT = {"/proc": "/proc: reads the process table", "/sys/": "/sys: reads the machine",
                "/sandbox": "/sandbox: looks for the grader's folder", ".grader": ".grader: looks for the grader"}


def is_stub(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    """True when a function's body is only a docstring and ``raise NotImplementedError``
    (called or not): the stub handed out."""
    body = list(node.body)
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
            and isinstance(body[0].value.value, str):
        body = body[1:]
    if len(body) != 1 or not isinstance(body[0], ast.Raise) or body[0].exc is None:
        return False
    raised = body[0].exc.func if isinstance(body[0].exc, ast.Call) else body[0].exc
    return isinstance(raised, ast.Name) and raised.id == "NotImplementedError"


def _parse(path: Path) -> ast.Module | None:
    try:
        return ast.parse(path.read_bytes(), filename=str(path))
    except (OSError, SyntaxError, ValueError, RecursionError, MemoryError):
        return None  # an unreadable module fails to import when graded: nothing to withhold


def _module_level(tree: ast.Module):
    """The statements run at import (into if/try/with blocks, not into functions or classes)."""
    stack = list(tree.body)
    while stack:
        node = stack.pop()
        yield node
        if isinstance(node, (ast.If, ast.Try, ast.With, ast.For, ast.While)):
            for name in ("body", "orelse", "finalbody"):
                stack.extend(getattr(node, name, []) or [])
            for handler in getattr(node, "handlers", []) or []:
                stack.extend(handler.body)


def _bound_names(tree: ast.Module) -> set[str] | None:
    """Names some module-level statement binds; None when a star import can bind any."""
    names: set[str] = set()
    for node in _module_level(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Import, ast.ImportFrom)):
            for alias in node.names:
                if alias.name == "*":
                    return None
                names.add(alias.asname or alias.name.split(".")[0])
        else:
            for inner in ast.walk(node):
                if isinstance(inner, ast.Name) and isinstance(inner.ctx, ast.Store):
                    names.add(inner.id)
    return names


def _last_definition(tree: ast.Module, name: str) -> ast.stmt | None:
    """The last module-level statement binding ``name`` (what the module ends up holding)."""
    found = None
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and node.name == name:
            found = node
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign, ast.Import, ast.ImportFrom, ast.If, ast.Try,
                               ast.With, ast.For)):
            if any(isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store) and n.id == name for n in ast.walk(node)) \
                    or any((a.asname or a.name.split(".")[0]) == name for n in ast.walk(node)
                           if isinstance(n, (ast.Import, ast.ImportFrom)) for a in n.names):
                found = node
    return found


def exercise_files(course_package: Path) -> dict[str, Path]:
    """The exercise files of the course's package: {path relative to it: file}."""
    return files_with_header(course_package, EXERCISE_HEADER)


def withheld_functions(package: str | Path, course_package: str | Path | None,
                       package_name: str = "exercises") -> dict[str, str]:
    """``{"<package>.<module>:<function>": reason}`` for each exercise function of the
    course whose submitted source is still the stub, or that the submitted module
    defines nowhere (see the module docstring).  Empty without ``course_package``."""
    if course_package is None or not Path(course_package).is_dir():
        return {}
    package = Path(package)
    withheld: dict[str, str] = {}
    for relative, course_file in exercise_files(Path(course_package)).items():
        course_tree = _parse(course_file)
        submitted = package / relative
        if course_tree is None or submitted.is_symlink() or not submitted.is_file():
            continue  # a missing module fails to import: the worker says so
        tree = _parse(submitted)
        if tree is None:
            continue
        module = ".".join((package_name, *Path(relative).with_suffix("").parts))
        bound = _bound_names(tree)
        for node in course_tree.body:
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) or not is_stub(node):
                continue
            definition = _last_definition(tree, node.name)
            if isinstance(definition, (ast.FunctionDef, ast.AsyncFunctionDef)) and is_stub(definition):
                withheld[f"{module}:{node.name}"] = STUB_REASON
            elif definition is None and bound is not None and node.name not in bound:
                withheld[f"{module}:{node.name}"] = MISSING_REASON
    return withheld


def _dotted(node: ast.AST, aliases: dict[str, str]) -> str | None:
    parts = []
    while isinstance(node, ast.Attribute):
        parts.append(node.attr)
        node = node.value
    if not isinstance(node, ast.Name):
        return None
    parts.append(aliases.get(node.id, node.id))
    return ".".join(reversed(parts))


def file_flags(tree: ast.Module, shown: str) -> list[dict]:
    """The flagged lines of one parsed file: ``{"file", "line", "what"}``, one per line and kind."""
    aliases: dict[str, str] = {}
    flags: dict[tuple[int, str], dict] = {}

    def flag(node: ast.AST, what: str) -> None:
        line = getattr(node, "lineno", 0)
        flags.setdefault((line, what), {"file": shown, "line": line, "what": what})

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                aliases[alias.asname or alias.name.split(".")[0]] = alias.name if alias.asname else \
                    alias.name.split(".")[0]
                top = alias.name.split(".")[0]
                if top in FLAGGED_MODULES:
                    flag(node, f"import {alias.name}: {FLAGGED_MODULES[top]}")
        elif isinstance(node, ast.ImportFrom):
            top = (node.module or "").split(".")[0]
            if top in FLAGGED_MODULES:
                flag(node, f"from {node.module} import ...: {FLAGGED_MODULES[top]}")
            for alias in node.names:
                if node.module and alias.name != "*":
                    aliases[alias.asname or alias.name] = f"{node.module}.{alias.name}"
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in CODE_BUILTINS:
            flag(node, CODE_BUILTINS[node.func.id])
        elif isinstance(node, (ast.Attribute, ast.Name)) and isinstance(node.ctx, ast.Load):
            name = _dotted(node, aliases)
            if name is not None:
                for known, what in FLAGGED_ATTRIBUTES.items():
                    if name == known or name.endswith("." + known):
                        flag(node, what)
                        break
            if isinstance(node, ast.Attribute) and node.attr in FLAGGED_NAMES:
                flag(node, FLAGGED_NAMES[node.attr])
            if isinstance(node, ast.Name) and node.id in FLAGGED_NAMES:
                flag(node, FLAGGED_NAMES[node.id])
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            for text, what in FLAGGED_TEXT.items():
                if text in node.value:
                    flag(node, what)
    # An attribute chain is walked at every level (sys.path.insert holds sys.path): one flag per line and kind.
    return sorted(flags.values(), key=lambda f: (f["line"], f["what"]))


def suspicious_lines(package: str | Path, course_package: str | Path | None = None,
                     limit: int = 200) -> list[dict]:
    """Flagged lines of every source file of ``package`` that differs from the course's
    copy (a library file graded as the course's is not the student's): ``{"file",
    "line", "what"}`` sorted by file and line, at most ``limit``."""
    package = Path(package)
    course = Path(course_package) if course_package is not None else None
    flags: list[dict] = []
    for path in sorted(package.rglob("*.py")):
        relative = path.relative_to(package)
        if "__pycache__" in relative.parts or path.is_symlink() or not path.is_file():
            continue
        if course is not None and (course / relative).is_file() and not (course / relative).is_symlink():
            try:
                if (course / relative).read_bytes() == path.read_bytes():
                    continue
            except OSError:
                pass
        tree = _parse(path)
        if tree is None:
            continue
        flags.extend(file_flags(tree, f"{package.name}/{relative.as_posix()}"))
        if len(flags) >= limit:
            return flags[:limit]
    return flags


def source_flags(withheld: dict[str, str], lines: list[dict]) -> dict:
    """Both findings as results.json keeps them (``extra_data["source_flags"]``):
    ``{"withheld": ["module:function: reason", ...], "lines": [{"file", "line", "what"}]}``."""
    return {"withheld": [f"{key}: {reason}" for key, reason in sorted(withheld.items())], "lines": list(lines)}
