"""The book of the student edition: chapter notebooks on the student's package, and the
reading pages as plain Markdown (instructor side; used by :mod:`grader.release.edition`).

Each ``book/chapters/NN_name.ipynb`` (executed, outputs stored) becomes
``NN_name.ipynb`` of the student edition:

- every ``solutions`` import and module path of a code cell names ``exercises``
  instead, and :func:`check_code` proves that no cell imports ``solutions``;
- a first code cell ``%load_ext grader.student.notebook`` is inserted, and every other code
  cell starts with ``%%reference_fallback NN_name:CELL_ID`` (see
  :mod:`grader.student.notebook`): it runs on the student's package, and shows the reference
  output stored with it in the notebook (the cell's metadata keeps their digest, by
  which the fallback knows them from the student's own) until the functions it needs
  are written;
- a cell tagged ``reference-output-only`` (:data:`~grader.release.chapter_imports.REFERENCE_OUTPUT_TAG`:
  it uses what only the instructor has, such as the ``bench/`` scripts) starts with
  ``%%reference_output NN_name:CELL_ID NEEDS`` instead: it never runs, and shows the stored
  output under a line saying why; an untagged cell that imports a module the student
  edition neither ships nor installs, or that changes ``sys.path``, is refused
  (:mod:`grader.release.chapter_imports`);
- ``from myst_nb import glue`` imports :func:`grader.student.notebook.glue` instead, which shows
  nothing (the student edition needs neither myst-nb nor Sphinx), and the glued values,
  stored as outputs no viewer renders, are left out;
- the cells that call ``check(...)`` are left as they are, without outputs (the stored
  ones were the reference's full marks): they run the student's public tests;
- MyST markup (roles such as ``{term}``, ``{ref}``, ``{numref}``; directives such as
  ``{admonition}``, ``{exercise}``, ``{solution}``, ``{glossary}``) becomes Markdown
  that JupyterLab renders, cross references becoming links between the notebooks, and
  each figure's caption (cell metadata the notebook does not show) a line under it;
- a ``{glue:text}`key:format``` role becomes the value the chapter glued under ``key``
  (formatted as myst-nb formats it), and a paragraph that quotes such values ends with
  :data:`GLUED_NOTE`: they are the reference engine's, whatever the student's code
  computes.

``book/intro.md``, ``conventions.md`` and ``glossary.md`` become plain Markdown pages
beside the notebooks.
"""
from __future__ import annotations

import ast
import copy
import functools
import html
import re
from dataclasses import dataclass
from pathlib import Path

from ..student.notebook import METADATA_KEY, outputs_digest

from .chapter_imports import REFERENCE_OUTPUT_TAG, ChapterGuard, StudentModules
from .module_graph import imported_modules as imported_modules_of_python

SOURCE_PACKAGE = "solutions"
TARGET_PACKAGE = "exercises"
MAGIC = "reference_fallback"
SHOWN_ONLY_MAGIC = "reference_output"   # a cell tagged REFERENCE_OUTPUT_TAG: shown, never run
READING_PAGES = ("intro", "conventions", "glossary")
SETUP_CELL_ID = "student-edition-setup"
#: myst-nb tags under which the built book hides a cell's source (a set-up cell of
#: imports and helpers, a figure's drawing code).  The student notebook collapses those
#: sources instead (JupyterLab's ``jupyter.source_hidden``; a click shows them).
HIDDEN_SOURCE_TAGS = ("hide-input", "remove-input")
SETUP_SOURCE = (
    "# Student edition: the cells below run on your exercises package.  A cell that needs a\n"
    "# function you have not written yet says so and shows the reference engine's output.\n"
    "%load_ext grader.student.notebook"
)
INTRO_NOTE = (
    "> **Your copy of the course.**  The chapters are the notebooks in this folder, and\n"
    "> their cells run on *your* `exercises` package.  A cell that needs a function you have\n"
    "> not written yet prints one line saying which, then shows the output the reference\n"
    "> engine gave (stored with the notebook); once you have written it, the cell shows what\n"
    "> your code computes.  The `check(...)` cells run the public tests on your code.\n"
    "> After you change a file in `exercises/`, restart the kernel (Kernel > Restart Kernel\n"
    "> and Run All Cells) so that the chapter's cells use the new code.\n"
)
#: Sentences of the book that describe the instructor's edition, as the student edition
#: words them (spaces match any run of whitespace, so line breaks do not matter).
STUDENT_WORDING = (
    ("runs the course's reference engine (the `solutions` package)",
     "runs your `exercises` package (showing the reference engine's output until you have written what a cell "
     "needs)"),
    ("On these pages the checks run against the reference engine, so they show a passing run.",
     "In your copy they run on your own code."),
)
#: The end of a paragraph that quotes values the chapter glued (the reference engine's).
GLUED_NOTE = "*(The numbers quoted here come from the reference engine's run of this chapter.)*"
#: Glue: the instructor's import, and the student edition's (a function that shows nothing).
GLUE_IMPORT = re.compile(r"^(\s*)from\s+myst_nb\s+import\s+glue\s*$", re.M)
STUDENT_GLUE_IMPORT = r"\1from grader.student.notebook import glue"
GLUE_PREFIX = "application/papermill.record/"   # myst_nb's GLUE_PREFIX: a glued value, not shown
TEXT_MIMES = ("text/plain", "text/html", "text/markdown", "text/latex")
ADMONITIONS = ("note", "warning", "tip", "important", "hint", "caution", "attention", "danger", "error",
               "seealso")


class BookConversionError(ValueError):
    """A chapter cannot be made into a student notebook; the message says which cell."""


# Code ----------------------------------------------------------------------------------------
_IMPORT = re.compile(rf"^(\s*)(from|import)(\s+){SOURCE_PACKAGE}\b", re.M)
_MODULE_PATH = re.compile(rf"\b{SOURCE_PACKAGE}(?=\.[A-Za-z_]|/)")
_BACKTICKED = re.compile(rf"`{SOURCE_PACKAGE}`")


def rewrite_code(source: str) -> str:
    """``source`` with every ``solutions`` import and module path naming ``exercises``."""
    return _MODULE_PATH.sub(TARGET_PACKAGE, _IMPORT.sub(rf"\1\2\3{TARGET_PACKAGE}", source))


def rewrite_prose(text: str) -> str:
    """The sentences of :data:`STUDENT_WORDING`, then module paths (``solutions.x``,
    ``solutions/x.py``, `` `solutions` ``) in prose."""
    for old, new in STUDENT_WORDING:
        pattern = r"\s+".join(re.escape(word) for word in old.split())
        text = re.sub(pattern, new.replace("\\", "\\\\"), text)
    return _BACKTICKED.sub(f"`{TARGET_PACKAGE}`", _MODULE_PATH.sub(TARGET_PACKAGE, text))


def cell_body(source: str) -> str:
    """A cell's source without its ``%%reference_fallback`` (or ``%%reference_output``) line."""
    first, _, rest = source.partition("\n")
    return rest if first.split(" ")[0] in (f"%%{MAGIC}", f"%%{SHOWN_ONLY_MAGIC}") else source


def is_shown_only(source: str) -> bool:
    """True for a student notebook's cell that shows its stored output and never runs."""
    return source.startswith(f"%%{SHOWN_ONLY_MAGIC} ")


@functools.lru_cache(maxsize=4096)
def python_of(source: str) -> str:
    """A cell's source as Python (IPython magics and shell escapes transformed; the
    body of a ``%%reference_fallback`` cell, which runs as Python)."""
    from IPython.core.inputtransformer2 import TransformerManager

    return TransformerManager().transform_cell(cell_body(source))


def imported_modules(source: str) -> list[str]:
    """Absolute module names a cell imports (its magics transformed first)."""
    return imported_modules_of_python(python_of(source))


def check_code(source: str, where: str) -> None:
    """BookConversionError unless the cell neither imports nor names ``solutions``."""
    try:
        tree = ast.parse(python_of(source))
    except SyntaxError as exc:
        raise BookConversionError(f"{where}: the cell does not parse ({exc.msg}, line {exc.lineno})") from None
    for node in ast.walk(tree):
        if isinstance(node, ast.Import) and any(a.name.split(".")[0] == SOURCE_PACKAGE for a in node.names):
            raise BookConversionError(f"{where}: the cell still imports {SOURCE_PACKAGE}")
        if (isinstance(node, ast.ImportFrom) and node.level == 0 and node.module
                and node.module.split(".")[0] == SOURCE_PACKAGE):
            raise BookConversionError(f"{where}: the cell still imports from {SOURCE_PACKAGE}")
        if isinstance(node, ast.Name) and node.id == SOURCE_PACKAGE:
            raise BookConversionError(f"{where}: the cell uses the name {SOURCE_PACKAGE!r}; rename the variable "
                                      "in the chapter (the student edition rewrites that name)")
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and re.fullmatch(
                rf"{SOURCE_PACKAGE}(\.\w+)*", node.value):
            raise BookConversionError(f"{where}: the cell names the module {node.value!r} in a string")


def is_check_cell(source: str) -> bool:
    """True for a cell that calls ``check(...)`` (``from grader import check``)."""
    try:
        tree = ast.parse(python_of(source))
    except SyntaxError:
        return bool(re.search(r"\bcheck\(", source))
    for node in ast.walk(tree):
        if isinstance(node, ast.Call):
            func = node.func
            if (isinstance(func, ast.Name) and func.id == "check") or (
                    isinstance(func, ast.Attribute) and func.attr == "check" and isinstance(func.value, ast.Name)
                    and func.value.id == "grader"):
                return True
    return False


# Labels and MyST -------------------------------------------------------------------------------
@dataclass(frozen=True)
class Label:
    """A target of ``{ref}``/``{numref}``: the page (file name in the student book), the
    text a reference shows, and the JupyterLab anchor of its heading (None: the page)."""

    page: str
    title: str
    anchor: str | None = None


_LABEL_LINE = re.compile(r"^\(([\w:.-]+)\)=\s*$")
_HEADING = re.compile(r"^(#{1,6})\s+(.*?)\s*#*\s*$")
_ROLE = re.compile(r"\{([A-Za-z][\w:-]*)\}`([^`]*)`")
_DIRECTIVE = re.compile(r"^(\s*)(`{3,}|:{3,})\{([A-Za-z][\w:-]*)\}\s*(.*?)\s*$")
_FENCE = re.compile(r"^(\s*)(`{3,}|~{3,})")
_OPTION = re.compile(r"^:([\w-]+):\s*(.*)$")


def plain_title(text: str) -> str:
    """A heading's text without Markdown markup and MyST roles."""
    text = _ROLE.sub(lambda m: _explicit(m.group(2))[0] or m.group(2), text)
    return re.sub(r"[`*_]", "", text).strip()


def heading_anchor(title: str) -> str:
    """The id JupyterLab gives a heading: its text, spaces as dashes."""
    return plain_title(title).replace(" ", "-")


def _explicit(content: str) -> tuple[str | None, str]:
    """``text <target>`` -> (text, target); ``target`` -> (None, target)."""
    match = re.fullmatch(r"(.*?)\s*<([^<>]+)>", content.strip(), re.S)
    if match and match.group(1):
        return match.group(1), match.group(2).strip()
    return None, content.strip()


def labels_of_markdown(text: str, page: str, top_level_is_page: bool = True) -> dict[str, Label]:
    """``(label)=`` lines before headings, and ``:label:`` options of exercises."""
    labels: dict[str, Label] = {}
    lines = text.split("\n")
    pending: list[str] = []
    for index, line in enumerate(lines):
        match = _LABEL_LINE.match(line)
        if match:
            pending.append(match.group(1))
            continue
        heading = _HEADING.match(line)
        if heading and pending:
            level, title = len(heading.group(1)), heading.group(2)
            anchor = None if (level == 1 and top_level_is_page) else heading_anchor(title)
            for name in pending:
                labels[name] = Label(page, plain_title(title), anchor)
            pending = []
        elif line.strip() and not heading:
            pending = []
        directive = _DIRECTIVE.match(line)
        if directive and directive.group(3) == "exercise":
            for option in lines[index + 1:index + 6]:
                found = _OPTION.match(option.strip())
                if found and found.group(1) == "label":
                    title = directive.group(4).strip()
                    labels[found.group(2).strip()] = Label(page, f"Exercise: {title}" if title else "the exercise")
    return labels


class MystToMarkdown:
    """MyST markdown -> Markdown that JupyterLab (and any Markdown viewer) renders."""

    def __init__(self, labels: dict[str, Label], page: str, contents: list[tuple[str, str]] = (),
                 glued: dict[str, str] | None = None):
        self.labels = labels
        self.page = page
        self.contents = list(contents)   # (file, title) of every page, for {tableofcontents}
        self.glued = dict(glued or {})   # glue key -> its text/plain, as the chapter glued it

    # Inline -----------------------------------------------------------------------------------
    def _link(self, text: str, label: Label | None) -> str:
        if label is None:
            return text
        if label.page == self.page:
            return f"[{text}](#{label.anchor})" if label.anchor else text
        return f"[{text}]({label.page}{'#' + label.anchor if label.anchor else ''})"

    def glue_role(self, name: str, content: str) -> str:
        """The value of ``{glue:text}`key:format``` (``{glue}``, ``{glue:}`` alike), as
        myst-nb formats its text/plain."""
        from myst_nb.core.variables import format_plain_text

        key, _, spec = content.strip().split("::")[-1].partition(":")   # [document::]key[:format]
        if key not in self.glued:
            raise BookConversionError(f"{self.page}: {{{name}}}`{content}` names {key!r}, which the chapter does "
                                      f"not glue (glued: {', '.join(sorted(self.glued)) or 'nothing'})")
        try:
            return format_plain_text(self.glued[key], spec)
        except (ValueError, TypeError) as exc:
            raise BookConversionError(f"{self.page}: {{{name}}}`{content}`: cannot format {self.glued[key]!r} "
                                      f"with {spec!r} ({exc})") from None

    def role(self, match: re.Match) -> str:
        name, content = match.group(1), match.group(2)
        if name in ("glue", "glue:", "glue:text", "glue:any"):
            return self.glue_role(name, content)
        if name.startswith("glue:"):
            raise BookConversionError(f"{self.page}: the student edition renders no {{{name}}} role "
                                      "(only {glue:text})")
        text, target = _explicit(content)
        if name == "term":
            shown = text or target
            return shown if self.page == "glossary.md" else f"[{shown}](glossary.md)"
        if name == "ref":
            label = self.labels.get(target)
            return self._link(text or (label.title if label else target), label)
        if name == "numref":
            label = self.labels.get(target)
            number = label.title if label else target
            shown = text.replace("%s", number.split()[-1]).replace("{number}", number.split()[-1]) if text else number
            return self._link(shown, label)
        if name == "math":
            return f"${content}$"
        if name == "eq":
            return f"({target})"
        if name == "doc":
            return text or target
        if name == "abbr":
            return re.sub(r"\s*\(.*\)\s*$", "", content)
        return f"`{content}`" if name in ("code", "kbd", "file", "samp") else (text or content)

    def inline(self, line: str) -> str:
        # Roles outside inline code spans only.
        parts = re.split(r"(`[^`]*`)", line)
        out, index = [], 0
        while index < len(parts):
            part = parts[index]
            if index % 2 == 0 and re.search(r"\{[A-Za-z][\w:-]*\}$", part) and index + 1 < len(parts):
                role = re.search(r"\{[A-Za-z][\w:-]*\}$", part)
                out.append(part[:role.start()])
                out.append(self.role(_ROLE.match(role.group(0) + parts[index + 1])))
                index += 2
                continue
            out.append(part)
            index += 1
        return "".join(out)

    # Blocks -----------------------------------------------------------------------------------
    def convert(self, text: str) -> str:
        lines = text.split("\n")
        out: list[str] = []
        plain: list[str] = []   # lines of ordinary text, converted together (a role may wrap)

        def flush() -> None:
            if plain:
                out.extend(self.inline("\n".join(plain)).split("\n"))
                plain.clear()

        index = 0
        while index < len(lines):
            line = lines[index]
            directive = _DIRECTIVE.match(line)
            fence = _FENCE.match(line)
            if directive or fence or _LABEL_LINE.match(line):
                flush()
            if directive:
                indent, fence, name, argument = directive.groups()
                end = index + 1
                closing = re.compile(rf"^\s*{re.escape(fence[0])}{{{len(fence)},}}\s*$")
                while end < len(lines) and not closing.match(lines[end]):
                    end += 1
                body = lines[index + 1:end]
                options = {}
                while body and _OPTION.match(body[0].strip()):
                    key, value = _OPTION.match(body[0].strip()).groups()
                    options[key] = value
                    body = body[1:]
                rendered = self.directive(name, argument, options, "\n".join(b[len(indent):] if b.startswith(indent)
                                                                             else b for b in body).strip("\n"))
                out += [indent + r if r else r for r in rendered.split("\n")]
                index = end + 1
                continue
            if fence:
                marker = fence.group(2)
                out.append(line)
                index += 1
                while index < len(lines):
                    out.append(lines[index])
                    if re.match(rf"^\s*{re.escape(marker[0])}{{{len(marker)},}}\s*$", lines[index]):
                        break
                    index += 1
                index += 1
                continue
            if _LABEL_LINE.match(line):
                index += 1
                continue
            plain.append(line)
            index += 1
        flush()
        return rewrite_prose("\n".join(out))

    @staticmethod
    def quoted(head: str, body: str) -> str:
        lines = [f"**{head}**", ""] + body.split("\n")
        return "\n".join(f"> {line}".rstrip() for line in lines)

    def directive(self, name: str, argument: str, options: dict, body: str) -> str:
        if name == "glue" or name.startswith("glue:"):
            raise BookConversionError(f"{self.page}: the student edition renders no {{{name}}} directive "
                                      "(only the {glue:text} role)")
        inner = self.convert(body) if body else ""
        if name == "admonition":
            return self.quoted(self.inline(argument) or "Note", inner)
        if name in ADMONITIONS:
            head = "See also" if name == "seealso" else name.capitalize()
            return self.quoted(head + (f": {self.inline(argument)}" if argument else ""), inner)
        if name == "exercise":
            return self.quoted("Exercise" + (f": {self.inline(argument)}" if argument else ""), inner)
        if name == "solution":
            return f"<details>\n<summary>Answer (click to show)</summary>\n\n{inner}\n\n</details>"
        if name == "tableofcontents":
            return "\n".join(f"- [{title}]({file})" for file, title in self.contents)
        if name == "glossary":
            return self.glossary(body)
        if name == "math":
            return f"$$\n{body}\n$$"
        if name in ("code-block", "code", "code-cell", "sourcecode"):
            return f"```{argument.split()[0] if argument else ''}\n{body}\n```"
        if name in ("figure", "image"):
            return f"![{inner or argument}]({argument})"
        return self.quoted(name.capitalize() + (f": {argument}" if argument else ""), inner)

    def glossary(self, body: str) -> str:
        entries: list[tuple[str, list[str]]] = []
        for line in body.split("\n"):
            if line.strip() and not line[0].isspace():
                entries.append((line.strip(), []))
            elif entries:
                entries[-1][1].append(line.strip())
        out = []
        for term, definition in entries:
            text = " ".join(d for d in definition if d)
            out.append(f"**{term}**: {self.inline(text)}")
        return "\n\n".join(out)


# Notebooks -----------------------------------------------------------------------------------------
def chapter_title(nb) -> str:
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            for line in cell.source.split("\n"):
                heading = _HEADING.match(line)
                if heading and len(heading.group(1)) == 1:
                    return plain_title(heading.group(2))
    return "Untitled chapter"


def figure_labels(nb, page: str, chapter_number: int) -> dict[str, Label]:
    """Figures named in cell metadata (``mystnb.figure.name``), numbered as Sphinx does."""
    labels = {}
    count = 0
    for cell in nb.cells:
        figure = cell.get("metadata", {}).get("mystnb", {}).get("figure")
        if cell.cell_type == "code" and isinstance(figure, dict) and (figure.get("name") or figure.get("caption")):
            count += 1
            if figure.get("name"):
                labels[figure["name"]] = Label(page, f"Fig. {chapter_number}.{count}")
    return labels


def book_labels(chapters: list[tuple[str, object]], pages: dict[str, str]) -> dict[str, Label]:
    """Every label of the book: chapters as (stem, notebook), pages as {stem: MyST text}."""
    labels: dict[str, Label] = {}
    for stem, text in pages.items():
        labels.update(labels_of_markdown(text, f"{stem}.md"))
    for stem, nb in chapters:
        page = f"{stem}.ipynb"
        for cell in nb.cells:
            if cell.cell_type == "markdown":
                labels.update(labels_of_markdown(cell.source, page))
        labels.update(figure_labels(nb, page, int(stem[:2]) if stem[:2].isdigit() else 0))
    return labels


#: An image inlined in HTML (the frames of matplotlib's ``to_jshtml`` animations), whose
#: base64 is cut into lines by JavaScript line continuations (backslash, newline).
INLINE_IMAGE = re.compile(r"(data:image/[\w+.-]+;base64,)((?:[A-Za-z0-9+/=]|\\\n)+)")


def join_inline_images(html_text: str) -> str:
    """``html_text`` with each inlined image's base64 on one line: the same JavaScript
    strings (a line continuation adds nothing to a string), about 15 % fewer bytes in a
    notebook, which stores each line of an output as a JSON string of its own."""
    return INLINE_IMAGE.sub(lambda m: m.group(1) + m.group(2).replace("\\\n", ""), html_text)


def _rewrite_output(output: dict) -> dict:
    output = copy.deepcopy(output)
    if output.get("output_type") == "stream":
        text = output.get("text", "")
        output["text"] = rewrite_code("".join(text) if isinstance(text, list) else text)
    for mime in TEXT_MIMES:
        if mime in output.get("data", {}):
            value = output["data"][mime]
            output["data"][mime] = rewrite_code("".join(value) if isinstance(value, list) else value)
    if "text/html" in output.get("data", {}):
        output["data"]["text/html"] = join_inline_images(output["data"]["text/html"])
    return output


def glued_values(nb) -> dict[str, str]:
    """The values an executed chapter glued (``glue(key, value)`` of myst-nb): key -> the
    value's text/plain."""
    values = {}
    for cell in nb.cells:
        for output in cell.get("outputs", []) if cell.cell_type == "code" else []:
            record = output.get("metadata", {}).get("scrapbook")
            if isinstance(record, dict) and record.get("name"):
                prefix = record.get("mime_prefix", "")
                text = output.get("data", {}).get(f"{prefix}text/plain")
                if text is not None:
                    values[record["name"]] = "".join(text) if isinstance(text, list) else text
    return values


def _is_hidden_glue(output: dict) -> bool:
    """A value glued with ``display=False``: data no notebook viewer renders."""
    data = output.get("data", {})
    return bool(data) and all(mime.startswith(GLUE_PREFIX) for mime in data)


_GLUE_ROLE = re.compile(r"\{glue(:\w*)?\}`")


_CLOSING_FENCE = re.compile(r"\n[ \t]*(`{3,}|:{3,})[ \t]*$")


def _with_glued_note(paragraph: str) -> str:
    """``paragraph`` ending with :data:`GLUED_NOTE`, inside a directive whose closing fence
    ends the paragraph (a ``{solution}`` becomes a ``<details>`` block: the note stays in it)."""
    text = paragraph.rstrip()
    fence = _CLOSING_FENCE.search(text)
    body, closing = (text[:fence.start()], text[fence.start():]) if fence else (text, "")
    return f"{body}\n{GLUED_NOTE}{closing}{paragraph[len(text):]}"


def mark_glued_paragraphs(source: str) -> str:
    """MyST ``source`` with :data:`GLUED_NOTE` ending each paragraph that quotes a glued value."""
    parts = re.split(r"(\n[ \t]*\n)", source)   # paragraphs, and the blank lines between them
    return "".join(_with_glued_note(part) if index % 2 == 0 and _GLUE_ROLE.search(part) else part
                   for index, part in enumerate(parts))


def student_notebook(nb, stem: str, converter: MystToMarkdown, modules: StudentModules | None = None):
    """The student edition of the executed chapter ``nb``; ``modules``: what a student's
    kernel can import (by default the repository's ``exercises``, ``grader`` and ``tools``)."""
    import nbformat
    nb = copy.deepcopy(nb)
    cells = []
    figure_number = 0
    chapter_number = int(stem[:2]) if stem[:2].isdigit() else 0
    repository = Path(__file__).resolve().parents[2]
    modules = modules or StudentModules({name: repository / name for name in (TARGET_PACKAGE, "grader", "tools")})
    guard = ChapterGuard(modules)
    for index, cell in enumerate(nb.cells):
        cell_id = cell.get("id") or f"cell-{index:03d}"
        cell["id"] = cell_id
        where = f"{stem}.ipynb, cell {index} ({cell_id})"
        if cell.cell_type == "markdown":
            cell.source = converter.convert(mark_glued_paragraphs(cell.source))
            cells.append(cell)
            continue
        if cell.cell_type != "code":
            cells.append(cell)
            continue
        source = GLUE_IMPORT.sub(STUDENT_GLUE_IMPORT, rewrite_code(cell.source))
        check_code(source, where)
        cell.outputs = [_rewrite_output(o) for o in cell.get("outputs", []) if not _is_hidden_glue(o)]
        shown_only = REFERENCE_OUTPUT_TAG in cell.get("metadata", {}).get("tags", [])
        if shown_only and (is_check_cell(source) or source.lstrip().startswith("%%")):
            raise BookConversionError(f"{where}: a check cell or a cell magic cannot be {REFERENCE_OUTPUT_TAG} "
                                      "(the student runs it)")
        needs = guard.cell(where, python_of(source), shown_only)
        if shown_only:
            cell.metadata[METADATA_KEY] = {"digest": outputs_digest(cell.outputs)}
            source = f"%%{SHOWN_ONLY_MAGIC} {stem}:{cell_id} {','.join(needs)}".rstrip() + f"\n{source}"
        elif is_check_cell(source):
            cell.outputs = []
            cell.execution_count = None
        elif not source.lstrip().startswith("%%"):
            cell.metadata[METADATA_KEY] = {"digest": outputs_digest(cell.outputs)}
            source = f"%%{MAGIC} {stem}:{cell_id}\n{source}"
        cell.source = source
        if any(tag in HIDDEN_SOURCE_TAGS for tag in cell.get("metadata", {}).get("tags", [])):
            cell.metadata.setdefault("jupyter", {})["source_hidden"] = True
        cells.append(cell)
        figure = cell.get("metadata", {}).get("mystnb", {}).get("figure")
        if isinstance(figure, dict) and (figure.get("name") or figure.get("caption")):
            figure_number += 1
            caption = converter.convert(mark_glued_paragraphs(str(figure.get("caption", "")))).strip()
            caption_cell = nbformat.v4.new_markdown_cell(
                f"*Fig. {chapter_number}.{figure_number}.*" + (f" {caption}" if caption else ""))
            caption_cell["id"] = f"{cell_id}-caption"
            cells.append(caption_cell)
    first_code = next((i for i, c in enumerate(cells) if c.cell_type == "code"), len(cells))
    setup = nbformat.v4.new_code_cell(SETUP_SOURCE)
    setup["id"] = SETUP_CELL_ID
    cells.insert(first_code, setup)
    nb.cells = cells
    nb.metadata.pop("jupytext", None)
    nbformat.validate(nb)
    return nb


def convert_page(text: str, stem: str, converter: MystToMarkdown) -> str:
    """A reading page (intro, conventions, glossary) as Markdown."""
    text = re.sub(r"\A---\n.*?\n---\n", "", text, flags=re.S)   # front matter, if any
    out = converter.convert(text).strip() + "\n"
    if stem == "intro":
        lines = out.split("\n")
        first = next((i for i, line in enumerate(lines) if line.startswith("# ")), -1)
        lines[first + 1:first + 1] = ["", *INTRO_NOTE.rstrip("\n").split("\n")]
        out = "\n".join(lines)
    return out


def write_book(chapters_dir: Path, pages_dir: Path, target: Path, modules: StudentModules | None = None) -> dict:
    """Write the student book into ``target`` (``modules``: what a student's kernel can
    import, see :func:`student_notebook`); return what was written
    (``notebooks``: [(file, title)], ``pages``, ``tools_modules``: modules of ``tools``
    the chapters import)."""
    import nbformat

    chapters = []
    for path in sorted(Path(chapters_dir).glob("*.ipynb")):
        chapters.append((path.stem, nbformat.read(path, as_version=4)))
    pages = {stem: (Path(pages_dir) / f"{stem}.md").read_text(encoding="utf-8") for stem in READING_PAGES
             if (Path(pages_dir) / f"{stem}.md").is_file()}
    labels = book_labels(chapters, pages)
    contents = [(f"{stem}.md", plain_title(next((m.group(2) for m in map(_HEADING.match, text.split("\n")) if m),
                                                stem))) for stem, text in pages.items() if stem == "conventions"]
    contents += [(f"{stem}.ipynb", chapter_title(nb)) for stem, nb in chapters]
    contents += [("glossary.md", "Glossary")] if "glossary" in pages else []
    target.mkdir(parents=True, exist_ok=True)
    written = {"notebooks": [], "pages": [], "tools_modules": set()}
    for stem, nb in chapters:
        converter = MystToMarkdown(labels, f"{stem}.ipynb", contents, glued_values(nb))
        student = student_notebook(nb, stem, converter, modules)
        with open(target / f"{stem}.ipynb", "w", encoding="utf-8") as handle:
            nbformat.write(student, handle)
        written["notebooks"].append((f"{stem}.ipynb", chapter_title(nb)))
        for cell in student.cells:
            if cell.cell_type == "code":
                written["tools_modules"].update(m for m in imported_modules(cell.source) if m.split(".")[0] == "tools")
    for stem, text in pages.items():
        converter = MystToMarkdown(labels, f"{stem}.md", contents)
        (target / f"{stem}.md").write_text(convert_page(text, stem, converter), encoding="utf-8")
        written["pages"].append(f"{stem}.md")
    written["tools_modules"] = sorted(written["tools_modules"])
    return written


def notebook_texts(nb: dict) -> list[str]:
    """Every text of a notebook (its JSON) a person could read: cell sources, and each
    output's text (HTML unescaped as well), for the leak scan; images left out."""
    texts = []
    for cell in nb.get("cells", []):
        source = cell.get("source", "")
        texts.append("".join(source) if isinstance(source, list) else source)
        for output in cell.get("outputs", []):
            data = [v for mime, v in output.get("data", {}).items() if not mime.startswith("image/")]
            for value in [output.get("text", "")] + data:
                value = "".join(value) if isinstance(value, list) else value
                if isinstance(value, str) and value:
                    texts += [value, html.unescape(value)]
    return texts
