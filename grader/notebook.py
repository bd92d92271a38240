"""The chapters of the student edition: your code where it is written, the reference's
output where it is not yet.

Every chapter notebook of the student edition starts with ``%load_ext grader.notebook``,
and its code cells start with a line such as::

    %%reference_fallback 03_grid_and_quadtree:cell-012

The cell below that line runs as usual, on your ``exercises`` package.  When it stops
at a function you have not written yet (a ``NotImplementedError``), the cell prints one
line naming that function and then shows the output the reference engine gave when the
edition was made, stored in ``reference_outputs/<chapter>.json`` next to the notebooks.
Once an earlier cell of the same kernel session has fallen back like this, any error of
a later cell falls back too (it most likely needs a value the earlier cell did not
compute).  Any other error is shown as usual: it is a bug to fix.

The ``check(...)`` cells carry no such line: they always run the public tests on your
code.
"""
from __future__ import annotations

import ast
import importlib.util
import json
import os
import sys
from pathlib import Path

#: Folder of the stored outputs, next to the chapter notebooks.
OUTPUTS_FOLDER = "reference_outputs"
#: Environment variable naming that folder explicitly.
OUTPUTS_VARIABLE = "COURSE_REFERENCE_OUTPUTS"
#: The line a falling-back cell prints first (``{needs}``: what it needs).
NOTICE = "[reference output] this cell needs {needs}, which you have not written yet; {rest}"

_HERE = os.path.abspath(__file__)
_session: dict = {"missing": []}   # functions found missing in this kernel session, in order
_loaded: dict[Path, dict] = {}


# Where the stored outputs are --------------------------------------------------------------
def _outputs_folders() -> list[Path]:
    folders = []
    if os.environ.get(OUTPUTS_VARIABLE):
        folders.append(Path(os.environ[OUTPUTS_VARIABLE]))
    cwd = Path.cwd()
    folders += [cwd / OUTPUTS_FOLDER, cwd / "book" / OUTPUTS_FOLDER]
    try:
        spec = importlib.util.find_spec("exercises")
    except (ImportError, ValueError):
        spec = None
    if spec is not None and spec.origin:
        folders.append(Path(spec.origin).resolve().parent.parent / "book" / OUTPUTS_FOLDER)
    return folders


def stored_outputs(key: str) -> list[dict] | None:
    """The stored outputs of the cell ``CHAPTER:CELL_ID`` (None when none are found)."""
    chapter, _, cell = key.strip().partition(":")
    for folder in _outputs_folders():
        path = folder / f"{chapter}.json"
        if path not in _loaded:
            try:
                _loaded[path] = json.loads(path.read_text(encoding="utf-8"))
            except (OSError, ValueError):
                continue
        cells = _loaded[path].get("cells", _loaded[path])
        if cell in cells:
            return list(cells[cell])
    return None


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
        outputs = stored_outputs(key)
        if missing is not None:
            if missing not in _session["missing"]:
                _session["missing"].append(missing)
            needs = missing
        else:
            earlier = _session["missing"][-1]
            needs = (f"a result of an earlier cell, which needs {earlier} (here: "
                     f"{type(exc).__name__}: {str(exc)[:120]})")
        if outputs:
            rest = "the output below is the reference engine's."
        elif outputs is None:
            rest = f"no stored output was found for it ({key})."
        else:
            rest = "it shows no output."
        from IPython.display import clear_output

        clear_output()   # what the cell printed before it stopped: the reference output replaces it
        print(NOTICE.format(needs=needs, rest=rest), flush=True)
        show_outputs(outputs or [])
        return None


def load_ipython_extension(ipython) -> None:
    """``%load_ext grader.notebook``: register ``%%reference_fallback``."""
    ipython.register_magic_function(reference_fallback, magic_kind="cell", magic_name="reference_fallback")


def unload_ipython_extension(ipython) -> None:  # nothing to undo beyond the magic
    ipython.magics_manager.magics["cell"].pop("reference_fallback", None)
