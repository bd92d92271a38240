"""The chapters of the student edition: your code where it is written, the reference's
output where it is not yet.

Every chapter notebook of the student edition starts with ``%load_ext grader.student.notebook``,
and its code cells start with a line such as::

    %%reference_fallback 03_grid_and_quadtree:cell-012

The cell below that line runs as usual, on your ``exercises`` package.  When it stops
at a function you have not written yet (a ``NotImplementedError``), the cell prints one
line naming that function and then shows the output the reference engine gave when the
edition was made: the output the notebook file (``<chapter>.ipynb``, as last saved)
holds for that cell, as long as it is still the reference's (the cell's metadata keeps
its digest; once your own run of the cell has been saved over it, the line says so).
Once an earlier cell of the same kernel session has fallen back like this, any error of
a later cell falls back too (it most likely needs a value the earlier cell did not
compute).  Any other error is shown as usual: it is a bug to fix.

A cell that uses what only the instructor's edition of the course holds (the
instructor's benchmark scripts, a compiled engine) starts with a line such as::

    %%reference_output 04_dynamic_aabb_tree:cell-014 bench_dynamic_tree,sys.path

Its code is there to read, but it never runs: it prints one line saying what it needs
and shows the reference output stored with it, found as above.

The ``check(...)`` cells carry no such line: they always run the public tests on your
code.

``from grader.student.notebook import glue`` stands in for myst-nb's ``glue`` (which files a
value for the printed book to quote): here it shows the value if asked to, and files
nothing.
"""
from __future__ import annotations

import ast
import hashlib
import importlib.util
import json
import os
import sys
from pathlib import Path

#: Environment variable naming the folder of the chapter notebooks explicitly.
NOTEBOOKS_VARIABLE = "COURSE_NOTEBOOKS"
#: Cell metadata of the student edition: ``{"digest": outputs_digest(reference outputs)}``.
METADATA_KEY = "reference_fallback"
#: The line a falling-back cell shows first (``{needs}``: what it needs), as display data
#: whose metadata holds ``{METADATA_KEY: NOTICE_MARK}``.
NOTICE = "[reference output] this cell needs {needs}, which you have not written yet; {rest}"
NOTICE_MARK = "notice"
#: The line a ``%%reference_output`` cell shows first (``{needs}``: what it uses).
SHOWN_ONLY_NOTICE = ("[reference output] this cell is not run here: it uses {needs}, which only the instructor's "
                     "edition of the course has; {rest}")

_HERE = os.path.abspath(__file__)
_session: dict = {"missing": []}   # functions found missing in this kernel session, in order
_loaded: dict[Path, tuple[int, dict]] = {}   # notebook -> (mtime in ns, its JSON)


# Where the stored outputs are --------------------------------------------------------------
def _text(value) -> str:
    return "".join(value) if isinstance(value, list) else str(value)


def is_notice(output: dict) -> bool:
    """The fallback's own line, not an output of the cell."""
    return output.get("metadata", {}).get(METADATA_KEY) == NOTICE_MARK


def outputs_digest(outputs: list[dict]) -> str:
    """SHA-256 of the outputs as a person sees them, the same after JupyterLab saved
    them again: consecutive streams of one name joined, results as display data,
    text without its trailing whitespace, output metadata and the notice left out."""
    items: list = []
    for output in outputs:
        kind = output.get("output_type")
        if kind == "stream":
            text = _text(output.get("text", ""))
            if items and items[-1][:2] == ["stream", output.get("name")]:
                items[-1][2] += text
            else:
                items.append(["stream", output.get("name"), text])
        elif kind in ("display_data", "execute_result") and not is_notice(output):
            items.append(["data", {mime: value if isinstance(value, dict) else _text(value).rstrip()
                                   for mime, value in output.get("data", {}).items()}])
        elif kind == "error":
            items.append(["error", output.get("ename"), output.get("evalue")])
    for item in items:
        if item[0] == "stream":
            item[2] = item[2].rstrip()
    return hashlib.sha256(json.dumps(items, sort_keys=True).encode("utf-8")).hexdigest()


def _notebook_folders() -> list[Path]:
    folders = []
    if os.environ.get(NOTEBOOKS_VARIABLE):
        folders.append(Path(os.environ[NOTEBOOKS_VARIABLE]))
    cwd = Path.cwd()
    folders += [cwd, cwd / "book"]
    try:
        spec = importlib.util.find_spec("exercises")
    except (ImportError, ValueError):
        spec = None
    if spec is not None and spec.origin:
        folders.append(Path(spec.origin).resolve().parent.parent / "book")
    return folders


def _read_notebook(path: Path) -> dict | None:
    try:
        mtime = path.stat().st_mtime_ns
        if path not in _loaded or _loaded[path][0] != mtime:
            _loaded[path] = (mtime, json.loads(path.read_text(encoding="utf-8")))
    except (OSError, ValueError):
        return None
    return _loaded[path][1]


def stored_outputs(key: str) -> tuple[list[dict] | None, str]:
    """The reference outputs of the cell ``CHAPTER:CELL_ID`` as its notebook file holds
    them, and, when there are none (None), why."""
    chapter, _, cell_id = key.strip().partition(":")
    replaced = None
    for folder in _notebook_folders():
        nb = _read_notebook(folder / f"{chapter}.ipynb")
        cell = next((c for c in (nb or {}).get("cells", []) if c.get("id") == cell_id), None)
        if cell is None:
            continue
        outputs = [o for o in cell.get("outputs", []) if not is_notice(o)]
        digest = cell.get("metadata", {}).get(METADATA_KEY, {}).get("digest")
        if digest and outputs_digest(outputs) == digest:
            return outputs, ""
        replaced = folder / f"{chapter}.ipynb"
    if replaced is not None:
        return None, (f"the reference output is no longer in {replaced.name}: a run of the cell on your code was saved "
                      "over it")
    return None, f"no stored output was found for it (cell {cell_id} of {chapter}.ipynb)"


def show_outputs(outputs: list[dict]) -> None:
    """Show nbformat outputs again: streams printed, rich outputs published."""
    from IPython.display import publish_display_data

    for output in outputs:
        kind = output.get("output_type")
        if kind == "stream":
            text = output.get("text", "")
            stream = sys.stderr if output.get("name") == "stderr" else sys.stdout
            stream.write("".join(text) if isinstance(text, list) else text)
            stream.flush()
        elif kind in ("display_data", "execute_result"):
            data = {mime: "".join(value) if isinstance(value, list) and not mime.endswith("json") else value
                    for mime, value in output.get("data", {}).items()}
            publish_display_data(data=data, metadata=output.get("metadata", {}))


# What is missing ---------------------------------------------------------------------------
def _chain(exc: BaseException):
    seen = set()
    stack = [exc]
    while stack:
        item = stack.pop()
        if item is None or id(item) in seen:
            continue
        seen.add(id(item))
        yield item
        if isinstance(item, BaseExceptionGroup):
            stack.extend(item.exceptions)
        stack += [item.__cause__, item.__context__]


def missing_function(exc: BaseException) -> str | None:
    """``name() (exercises/path.py)`` of the stub that raised NotImplementedError in
    ``exc`` (or its causes); "a function" if it was raised elsewhere; None if none was."""
    for item in _chain(exc):
        if isinstance(item, NotImplementedError):
            codes = []
            tb = item.__traceback__
            while tb is not None:
                codes.append(tb.tb_frame.f_code)
                tb = tb.tb_next
            for code in reversed(codes):
                parts = Path(code.co_filename).parts
                if "exercises" in parts:
                    where = "/".join(parts[len(parts) - 1 - parts[::-1].index("exercises"):])
                    return f"{getattr(code, 'co_qualname', code.co_name)}() ({where})"
            return f"{getattr(codes[-1], 'co_qualname', codes[-1].co_name)}()" if codes else "a function"
    return None


# Running a cell ------------------------------------------------------------------------------
def _user_traceback(tb):
    """The traceback without this module's frames."""
    while tb is not None and os.path.abspath(tb.tb_frame.f_code.co_filename) == _HERE:
        tb = tb.tb_next
    return tb


def _ends_quietly(source: str) -> bool:
    from IPython.core.displayhook import DisplayHook

    try:
        return DisplayHook.semicolon_at_end_of_expression(source)
    except Exception:
        return False


def run_body(shell, cell: str, first_line: str = "") -> None:
    """Run ``cell`` in the user's namespace as IPython would: magics inside it work,
    and the value of a last bare expression is displayed (unless it ends with ``;``).
    Tracebacks number the lines as the notebook does, ``first_line`` (the magic's) 1."""
    source = shell.transform_cell(cell)
    filename = shell.compile.cache(f"{first_line}\n{source}", shell.execution_count, raw_code=cell)
    tree = ast.parse(source, filename=filename)
    ast.increment_lineno(tree, 1)
    last = None
    if tree.body and isinstance(tree.body[-1], ast.Expr):
        last = ast.Expression(tree.body.pop().value)
    flags = getattr(shell.compile, "flags", 0)
    exec(compile(tree, filename, "exec", flags, dont_inherit=True), shell.user_global_ns, shell.user_ns)
    if last is not None:
        value = eval(compile(last, filename, "eval", flags, dont_inherit=True), shell.user_global_ns, shell.user_ns)
        if not _ends_quietly(source):
            shell.displayhook(value)


def _open_figures() -> set:
    pyplot = sys.modules.get("matplotlib.pyplot")
    return set(pyplot.get_fignums()) if pyplot is not None else set()


def _close_new_figures(before: set) -> None:
    pyplot = sys.modules.get("matplotlib.pyplot")
    if pyplot is not None:
        for number in set(pyplot.get_fignums()) - before:
            pyplot.close(number)


def _with_short_traceback(shell, exc: BaseException) -> None:
    """Make IPython print ``exc`` with the user's frames only (not this module's)."""
    tb = _user_traceback(exc.__traceback__)
    try:
        lines = shell.InteractiveTB.structured_traceback(type(exc), exc, tb, tb_offset=0)
        exc._render_traceback_ = lambda: lines
    except Exception:   # an exception class that takes no attributes: the long traceback then
        pass


def reference_fallback(line: str, cell: str):
    """``%%reference_fallback CHAPTER:CELL_ID``: run the cell; where it needs a function
    not written yet, say so and show the stored reference output instead."""
    from IPython import get_ipython

    shell = get_ipython()
    key = line.strip()
    figures = _open_figures()
    try:
        run_body(shell, cell, f"%%reference_fallback {line.strip()}")
        return None
    except (KeyboardInterrupt, SystemExit):
        raise
    except BaseException as exc:
        missing = missing_function(exc)
        if missing is None and not _session["missing"]:
            _with_short_traceback(shell, exc)
            raise
        _close_new_figures(figures)
        outputs, why_none = stored_outputs(key)
        if missing is not None:
            if missing not in _session["missing"]:
                _session["missing"].append(missing)
            needs = missing
        else:
            earlier = _session["missing"][-1]
            needs = (f"a result of an earlier cell, which needs {earlier} (here: "
                     f"{type(exc).__name__}: {str(exc)[:120]})")
        from IPython.display import clear_output

        clear_output()   # what the cell printed before it stopped: the reference output replaces it
        _show_reference(NOTICE.format(needs=needs, rest=_what_follows(outputs, why_none)), outputs)
        return None


def _what_follows(outputs: list[dict] | None, why_none: str) -> str:
    """The end of a notice: what the stored outputs shown under it are."""
    if outputs:
        return "the output below is the reference engine's."
    return why_none + "." if outputs is None else "it shows no output."


def _show_reference(notice: str, outputs: list[dict] | None) -> None:
    """The notice line (display data marked as the notice), then the stored outputs."""
    from IPython.display import publish_display_data

    publish_display_data({"text/plain": notice}, metadata={METADATA_KEY: NOTICE_MARK})
    show_outputs(outputs or [])


def _needs_text(needs: str) -> str:
    names = [n for n in needs.split(",") if n]
    words = [("a change of sys.path (files of the instructor's repository)" if n == "sys.path" else n) for n in names]
    return " and ".join(words) or "what the student edition does not include"


def reference_output(line: str, cell: str):
    """``%%reference_output CHAPTER:CELL_ID [NEEDS]``: show the stored reference output
    of a cell that uses what only the instructor has (``NEEDS``, comma-separated), with
    a line saying so; the cell's code is not run."""
    key, _, needs = line.strip().partition(" ")
    outputs, why_none = stored_outputs(key)
    _show_reference(SHOWN_ONLY_NOTICE.format(needs=_needs_text(needs.strip()), rest=_what_follows(outputs, why_none)),
                    outputs)


def glue(name: str, variable, display: bool = True) -> None:
    """myst-nb's ``glue`` in the student edition: files nothing (the chapters' text quotes
    the reference's values), shows ``variable`` when ``display`` is true."""
    if display:
        from IPython.display import display as show

        show(variable)


def load_ipython_extension(ipython) -> None:
    """``%load_ext grader.student.notebook``: register ``%%reference_fallback`` and ``%%reference_output``."""
    ipython.register_magic_function(reference_fallback, magic_kind="cell", magic_name="reference_fallback")
    ipython.register_magic_function(reference_output, magic_kind="cell", magic_name="reference_output")


def unload_ipython_extension(ipython) -> None:  # nothing to undo beyond the magic
    for name in ("reference_fallback", "reference_output"):
        ipython.magics_manager.magics["cell"].pop(name, None)


# The kernel ------------------------------------------------------------------------------------
#: What the course's kernel adds to ``ipykernel install``'s: no debugger warning about
#: frozen modules, kernel logs at ERROR (ipykernel warns on every start that local TCP
#: is unencrypted), as the instructor's kernel (tools/book.py) does.
QUIET_PYTHON_FLAGS = ["-Xfrozen_modules=off"]
QUIET_KERNEL_FLAGS = ["--log-level=ERROR"]
QUIET_KERNEL_ENV = {"PYDEVD_DISABLE_FILE_VALIDATION": "1"}


def quiet_kernel_spec(spec: dict) -> dict:
    """The kernel.json ``spec`` (of ``python -m ipykernel install``) made quiet on start."""
    spec = dict(spec)
    argv = list(spec["argv"])
    argv[1:1] = [flag for flag in QUIET_PYTHON_FLAGS if flag not in argv]
    argv += [flag for flag in QUIET_KERNEL_FLAGS if flag not in argv]
    spec["argv"] = argv
    spec["env"] = {**spec.get("env", {}), **QUIET_KERNEL_ENV}
    return spec


def main(argv: list[str] | None = None) -> int:
    """``python -m grader.student.notebook quiet-kernel KERNEL_JSON``: rewrite that kernel.json."""
    args = sys.argv[1:] if argv is None else argv
    if len(args) != 2 or args[0] != "quiet-kernel":
        print("usage: python -m grader.student.notebook quiet-kernel PATH/kernel.json", file=sys.stderr)
        return 2
    path = Path(args[1])
    try:
        spec = json.loads(path.read_text(encoding="utf-8"))
        path.write_text(json.dumps(quiet_kernel_spec(spec), indent=1) + "\n", encoding="utf-8")
    except (OSError, ValueError, KeyError) as exc:
        print(f"grader.student.notebook: cannot rewrite {path}: {exc}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
