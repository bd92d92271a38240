"""Similar submissions: code that is nearly the same once names and layout are normalised.

    grader similarity SUBMISSIONS... --out DIR [--reference PATH] [--threshold 0.8]

Compares every pair of submissions, and every submission with the reference solutions,
and writes ``DIR/similarity.csv`` (one row per pair, with its scores) and
``DIR/similarity.html`` (the flagged pairs, their matching code side by side with the
matching lines highlighted), for an instructor to read: a high score is a reason to
look, not a verdict.

How code is compared
--------------------
Only what students write counts: the functions of every ``.py`` file of the package
(the exercise modules, and library files, ``__init__.py`` and files a student added:
code hidden there is compared too), top-level functions and methods, and each
module's top-level code (what runs at import) as one more.  A function whose
normalised code is that of the distributed stub (``exercises/``) is left out, and so
is every fingerprint the stubs hold (boilerplate removal, as copydetect's
``boilerplate_dirs`` does): untouched stubs, identical in every submission, never
count.

Each function is parsed with :mod:`ast` and turned into a sequence of tokens, one per
syntax node in source order: the node's kind, with operators, attribute names,
keyword names, numbers and the names of Python's builtins kept, and every other name
(variables, parameters, imported modules, helper functions) replaced by one token
``N``; docstrings, comments, type annotations of the signature and layout vanish.
Renaming variables and reformatting therefore change nothing.  The sequence is cut
into overlapping k-grams (``k`` tokens), each hashed, and *winnowing* (Schleimer,
Wilkerson and Aiken, SIGMOD 2003) keeps the smallest hash of every window of ``w``
consecutive ones: the submission's fingerprints.  Any run of ``k + w - 1`` tokens two
submissions share is then sure to share a fingerprint, and runs shorter than ``k``
tokens never match.

The similarity of a pair is the share of the *smaller* submission's fingerprints found
in the other one (so a student who copied three functions and wrote nothing else
scores high).  A pair is flagged when it reaches ``--threshold`` and shares at least
``--min-shared`` fingerprints (a few short, common functions are not evidence).

Why not copydetect: it tokenises with Pygments (renamed names and reordered layout
survive, but not the structure ``ast`` gives), compares file with file rather than a
student's functions with another's, and its fixed report cannot show which exercise
matched; the winnowing itself is a few dozen lines here, with no new dependency.
"""
from __future__ import annotations

import argparse
import ast
import builtins
import csv
import hashlib
import html
import io
import itertools
import os
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from ..harness.results_model import STYLE_SHEET
from ..reports.results import write_text_atomic
from .submissions import (SubmissionPathError, SubmissionRefused, discover, submitted_package, opened)

REPO_ROOT = Path(__file__).resolve().parents[2]
REFERENCE_DIR = REPO_ROOT / "solutions"
STUBS_DIR = REPO_ROOT / "exercises"
MARKER = "### BEGIN SOLUTION"
REFERENCE_ID = "reference"
CSV_NAME = "similarity.csv"
HTML_NAME = "similarity.html"
#: Tokens per k-gram, and k-grams per winnowing window.
K = 10
WINDOW = 5
DEFAULT_THRESHOLD = 0.8
DEFAULT_MIN_SHARED = 8
#: Flagged pairs shown in full in the HTML report (the others are listed only).
DETAILED_PAIRS = 60
BUILTIN_NAMES = frozenset(dir(builtins))


# Tokens ---------------------------------------------------------------------------------------
def _is_docstring(node: ast.AST) -> bool:
    return (isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)
            and isinstance(node.value.value, str))


def _label(node: ast.AST) -> str | None:
    """The token of one syntax node, or None for nodes that carry nothing."""
    if isinstance(node, (ast.expr_context, ast.operator, ast.unaryop, ast.cmpop, ast.boolop)):
        return None
    kind = type(node).__name__
    if isinstance(node, ast.Name):
        return node.id if node.id in BUILTIN_NAMES else "N"
    if isinstance(node, ast.arg):
        return "A"
    if isinstance(node, ast.Attribute):
        return "." + node.attr
    if isinstance(node, ast.Constant):
        value = node.value
        if isinstance(value, (bool, int, float, complex)) or value is None:
            return f"C:{value!r}"
        return f"C:{type(value).__name__}"
    if isinstance(node, (ast.BinOp, ast.AugAssign)):
        return f"{kind}:{type(node.op).__name__}"
    if isinstance(node, (ast.UnaryOp, ast.BoolOp)):
        return f"{kind}:{type(node.op).__name__}"
    if isinstance(node, ast.Compare):
        return "Compare:" + ",".join(type(op).__name__ for op in node.ops)
    if isinstance(node, ast.keyword):
        return f"kw:{node.arg or '**'}"
    if isinstance(node, ast.alias):
        return f"alias:{node.name}"
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
        return "Def"
    return kind


def _walk(node: ast.AST, out: list[tuple[str, int]], line: int) -> None:
    line = getattr(node, "lineno", line)
    label = _label(node)
    if label is None:
        return
    out.append((label, line))
    if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):  # a nested function: its body only
        _body(node.body, out, line)
        return
    if isinstance(node, ast.ClassDef):
        _body(node.body, out, line)
        return
    for child in ast.iter_child_nodes(node):
        _walk(child, out, line)


def _body(statements: list[ast.stmt], out: list[tuple[str, int]], line: int) -> None:
    for number, statement in enumerate(statements):
        if number == 0 and _is_docstring(statement):
            continue
        _walk(statement, out, line)


def function_tokens(function: ast.FunctionDef | ast.AsyncFunctionDef) -> list[tuple[str, int]]:
    """``(token, source line)`` of a function's body (signature and docstring left out)."""
    out: list[tuple[str, int]] = []
    _body(function.body, out, function.lineno)
    return out


# Fingerprints -----------------------------------------------------------------------------------
def _hash(text: str) -> int:
    return int.from_bytes(hashlib.blake2b(text.encode(), digest_size=8).digest(), "big")


def winnow(tokens: list[tuple[str, int]], k: int = K, window: int = WINDOW) -> dict[int, tuple[int, int]]:
    """Fingerprints of a token sequence: ``{hash: (first line, last line)}`` of the k-grams
    that winnowing keeps (the rightmost smallest hash of each window of ``window``)."""
    if not tokens:
        return {}
    if len(tokens) < k:
        grams = [(0, len(tokens))]
    else:
        grams = [(i, i + k) for i in range(len(tokens) - k + 1)]
    hashes = [_hash("\x1f".join(t for t, _ in tokens[a:b])) for a, b in grams]
    chosen: dict[int, tuple[int, int]] = {}
    last = -1
    for start in range(max(1, len(hashes) - window + 1)):
        span = hashes[start:start + window]
        smallest = min(span)
        position = start + max(i for i, h in enumerate(span) if h == smallest)
        if position != last:
            a, b = grams[position]
            lines = [line for _, line in tokens[a:b]]
            chosen.setdefault(hashes[position], (min(lines), max(lines)))
            last = position
    return chosen


@dataclass
class Function:
    """One function of a submission, normalised and fingerprinted."""

    module: str
    qualname: str
    first_line: int
    lines: list[str]  # its source lines
    tokens: list[tuple[str, int]]
    prints: dict[int, tuple[int, int]] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return f"{self.module}.{self.qualname}"


@dataclass
class Code:
    """What one submission (or the reference) wrote: its functions and their fingerprints."""

    id: str
    source: str
    functions: list[Function] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    #: Every fingerprint of its functions (set by :func:`fingerprint_code`).
    prints: frozenset[int] = frozenset()


def exercise_modules(reference_dir: Path = REFERENCE_DIR) -> list[str]:
    """Dotted names (inside the package) of the modules that hold exercises."""
    modules = []
    for path in sorted(Path(reference_dir).rglob("*.py")):
        if "__pycache__" in path.parts:
            continue
        try:
            if MARKER in path.read_text(encoding="utf-8"):
                relative = path.relative_to(reference_dir).with_suffix("")
                modules.append(".".join(relative.parts))
        except (OSError, UnicodeDecodeError):
            continue
    return modules


def package_modules(package: Path) -> list[str]:
    """Dotted names (inside the package) of every ``.py`` file of ``package``, its
    ``__init__`` files included (``broadphase.__init__``), ``__pycache__`` and links left out."""
    modules = []
    for path in sorted(Path(package).rglob("*.py")):
        relative = path.relative_to(package)
        if "__pycache__" in relative.parts or any(p.is_symlink() for p in (path, *path.parents)):
            continue
        modules.append(".".join(relative.with_suffix("").parts))
    return modules


#: The name of a module's top-level code (everything but its imports, functions, classes
#: and docstring), compared as one more function: code run at import counts too.
MODULE_CODE = "<module code>"


def _module_code(tree: ast.Module) -> list[ast.stmt]:
    body = list(tree.body)
    if body and isinstance(body[0], ast.Expr) and isinstance(getattr(body[0], "value", None), ast.Constant):
        body = body[1:]
    return [node for node in body if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef,
                                                            ast.Import, ast.ImportFrom))]


def _functions(tree: ast.Module) -> list[tuple[str, ast.FunctionDef]]:
    found = []
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            found.append((node.name, node))
        elif isinstance(node, ast.ClassDef):
            for inner in node.body:
                if isinstance(inner, (ast.FunctionDef, ast.AsyncFunctionDef)):
                    found.append((f"{node.name}.{inner.name}", inner))
    return found


def read_package(package: Path | None, modules: list[str], code: Code,
                 stubs: dict[str, list[str]] | None = None) -> Code:
    """Add to ``code`` the functions of ``modules`` in ``package`` whose tokens differ from
    the stub's (``stubs``: ``{module.qualname: tokens}``); unreadable files become notes."""
    if package is None:
        return code
    for module in modules:
        path = Path(package).joinpath(*module.split(".")).with_suffix(".py")
        if any(p.is_symlink() for p in (path, *path.parents[:len(module.split("."))])):
            code.notes.append(f"{module}: not compared (a symbolic link)")
            continue
        if not path.is_file():
            continue
        try:
            text = path.read_bytes().decode("utf-8")
            tree = ast.parse(text)
        except (UnicodeDecodeError, SyntaxError, ValueError, RecursionError) as exc:
            code.notes.append(f"{module}: not compared ({type(exc).__name__})")
            continue
        lines = text.splitlines()
        for qualname, node in _functions(tree):
            tokens = function_tokens(node)
            key = f"{module}.{qualname}"
            if stubs is not None and [t for t, _ in tokens] == stubs.get(key):
                continue  # the distributed stub, untouched
            first = min([node.lineno, *(d.lineno for d in node.decorator_list)])
            code.functions.append(Function(module, qualname, first, lines[first - 1:node.end_lineno], tokens))
        statements = _module_code(tree)
        if statements:
            tokens: list[tuple[str, int]] = []
            _body(statements, tokens, statements[0].lineno)
            if stubs is None or [t for t, _ in tokens] != stubs.get(f"{module}.{MODULE_CODE}"):
                first, last = statements[0].lineno, max(n.end_lineno or n.lineno for n in statements)
                code.functions.append(Function(module, MODULE_CODE, first, lines[first - 1:last], tokens))
    return code


def stub_tokens(stubs_dir: Path, modules: list[str], k: int = K,
                window: int = WINDOW) -> tuple[dict[str, list[str]], set[int]]:
    """The stubs' functions as token lists, and every fingerprint the stubs hold."""
    code = read_package(stubs_dir, modules, Code("stubs", str(stubs_dir)))
    tokens = {f.name: [t for t, _ in f.tokens] for f in code.functions}
    prints: set[int] = set()
    for function in code.functions:
        prints |= set(winnow(function.tokens, k, window))
    return tokens, prints


def fingerprint_code(code: Code, boilerplate: set[int], k: int = K, window: int = WINDOW) -> Code:
    for function in code.functions:
        function.prints = {h: lines for h, lines in winnow(function.tokens, k, window).items() if h not in boilerplate}
    code.functions = [f for f in code.functions if f.prints]
    code.prints = frozenset(h for f in code.functions for h in f.prints)
    return code


# Comparing ---------------------------------------------------------------------------------------
@dataclass
class Pair:
    """Two submissions (``b`` may be the reference) and how much code they share."""

    a: Code
    b: Code
    shared: set[int]
    a_in_b: float  # share of a's fingerprints found in b
    b_in_a: float

    @property
    def similarity(self) -> float:
        return max(self.a_in_b, self.b_in_a)


def compare(a: Code, b: Code) -> Pair:
    prints_a, prints_b = a.prints, b.prints
    shared = set(prints_a & prints_b)
    return Pair(a, b, shared, len(shared) / len(prints_a) if prints_a else 0.0,
                len(shared) / len(prints_b) if prints_b else 0.0)


def flagged(pair: Pair, threshold: float, min_shared: int) -> bool:
    return pair.similarity >= threshold and len(pair.shared) >= min_shared


# Report -------------------------------------------------------------------------------------------
def _matched_lines(function: Function, shared: set[int]) -> set[int]:
    lines: set[int] = set()
    for digest, (first, last) in function.prints.items():
        if digest in shared:
            lines.update(range(first, last + 1))
    return lines


def _code_html(function: Function | None, shared: set[int]) -> str:
    if function is None:
        return "<td class='code'><em>no matching function</em></td>"
    marked = _matched_lines(function, shared)
    rows = []
    for number, text in enumerate(function.lines, start=function.first_line):
        body = html.escape(text) or " "
        if number in marked:
            body = f"<mark>{body}</mark>"
        rows.append(f"<span class='n'>{number:4d}</span> {body}")
    return (f"<td class='code'><div class='where'>{html.escape(function.name)}</div>"
            f"<pre>{chr(10).join(rows)}</pre></td>")


def _pair_section(number: int, pair: Pair) -> str:
    parts = [f"<h2 id='pair-{number}'>{number}. {html.escape(pair.a.id)} and {html.escape(pair.b.id)}: "
             f"{pair.similarity:.0%}</h2>",
             f"<p>{pair.a_in_b:.0%} of {html.escape(pair.a.id)}'s fingerprints are in "
             f"{html.escape(pair.b.id)}; {pair.b_in_a:.0%} of {html.escape(pair.b.id)}'s are in "
             f"{html.escape(pair.a.id)} ({len(pair.shared)} shared). Highlighted lines hold shared code.</p>",
             "<table class='side'>",
             f"<tr><th>{html.escape(pair.a.id)}</th><th>{html.escape(pair.b.id)}</th></tr>"]
    matches = []
    for function in pair.a.functions:
        common = set(function.prints) & pair.shared
        if not common:
            continue
        best = max(pair.b.functions, key=lambda g: len(set(g.prints) & common), default=None)
        if best is not None and not set(best.prints) & common:
            best = None
        matches.append((len(common), function, best))
    for _, function, best in sorted(matches, key=lambda m: (-m[0], m[1].name)):
        parts.append(f"<tr>{_code_html(function, pair.shared)}{_code_html(best, pair.shared)}</tr>")
    parts.append("</table>")
    return "\n".join(parts)


def write_report(out_dir: Path, codes: list[Code], pairs: list[Pair], threshold: float, min_shared: int,
                 k: int, window: int) -> tuple[Path, Path]:
    """``similarity.csv`` (every pair) and ``similarity.html`` (the flagged ones), atomically."""
    out_dir.mkdir(parents=True, exist_ok=True)
    ordered = sorted(pairs, key=lambda p: (-p.similarity, p.a.id, p.b.id))
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(["a", "b", "similarity", "a_in_b", "b_in_a", "shared_fingerprints", "a_fingerprints",
                     "b_fingerprints", "flagged"])
    for pair in ordered:
        writer.writerow([pair.a.id, pair.b.id, f"{pair.similarity:.4f}", f"{pair.a_in_b:.4f}", f"{pair.b_in_a:.4f}",
                         len(pair.shared), len(pair.a.prints), len(pair.b.prints),
                         "yes" if flagged(pair, threshold, min_shared) else "no"])
    csv_path = out_dir / CSV_NAME
    write_text_atomic(csv_path, buffer.getvalue())

    flags = [p for p in ordered if flagged(p, threshold, min_shared)]
    rows = "\n".join(
        f"<tr><td><a href='#pair-{i}'>{i}</a></td><td>{html.escape(p.a.id)}</td><td>{html.escape(p.b.id)}</td>"
        f"<td>{p.similarity:.0%}</td><td>{p.a_in_b:.0%}</td><td>{p.b_in_a:.0%}</td><td>{len(p.shared)}</td></tr>"
        for i, p in enumerate(flags, start=1))
    notes = [f"<li>{html.escape(c.id)}: {html.escape(n)}</li>" for c in codes for n in c.notes]
    empty = [c.id for c in codes if not c.functions and not c.notes]
    sections = [_pair_section(i, p) for i, p in enumerate(flags[:DETAILED_PAIRS], start=1)]
    more = (f"<p>{len(flags) - DETAILED_PAIRS} more flagged pairs are listed above but not shown side by side.</p>"
            if len(flags) > DETAILED_PAIRS else "")
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>Similar submissions</title><style>{STYLE_SHEET}</style></head>
<body class="report">
<h1>Similar submissions</h1>
<p>{len(codes)} submissions{' and the reference' if any(c.id == REFERENCE_ID for c in codes) else ''},
{len(pairs)} pairs compared, <strong>{len(flags)} flagged</strong> (similarity at least {threshold:.0%} and at
least {min_shared} shared fingerprints), {time.strftime('%Y-%m-%d %H:%M')}.</p>
<p>Compared: the functions of the exercise modules, less the untouched stubs and the code the stubs hold,
with names replaced and layout dropped (k = {k} syntax tokens, winnowing window {window}). The similarity of
a pair is the share of the smaller one's fingerprints found in the other. A high score is a reason to read the
code, not a verdict: short functions can be alike by chance.</p>
<table><tr><th>#</th><th>a</th><th>b</th><th>similarity</th><th>a in b</th><th>b in a</th><th>shared</th></tr>
{rows or "<tr><td colspan='7'>no pair flagged</td></tr>"}</table>
{"<h3>Not compared</h3><ul>" + "".join(notes) + "</ul>" if notes else ""}
{"<p>No code of their own (untouched stubs): " + html.escape(", ".join(empty)) + ".</p>" if empty else ""}
{"".join(sections)}
{more}
</body></html>
"""
    html_path = out_dir / HTML_NAME
    write_text_atomic(html_path, page)
    return csv_path, html_path


# Running ----------------------------------------------------------------------------------------
def load_codes(paths: list[str | os.PathLike], modules: list[str], stubs: dict[str, list[str]],
               boilerplate: set[int], k: int = K, window: int = WINDOW) -> list[Code]:
    codes = []
    for submission in discover(paths):
        code = Code(submission.id, str(submission.path))
        try:
            with opened(submission, verify=False) as folder:  # tampered or not, the code is compared
                package = submitted_package(folder)
                # Every file: code hidden in a library file or __init__.py is compared too.
                read_package(package, sorted(set(modules) | set(package_modules(package))), code, stubs)
        except SubmissionRefused as exc:
            code.notes.append(f"not read: {exc}")
        except OSError as exc:
            code.notes.append(f"not read: {exc}")
        codes.append(fingerprint_code(code, boilerplate, k, window))
    return codes


def find_similar(paths: list[str | os.PathLike], out_dir: str | os.PathLike,
                 reference: str | os.PathLike | None = REFERENCE_DIR, stubs_dir: str | os.PathLike = STUBS_DIR,
                 threshold: float = DEFAULT_THRESHOLD, min_shared: int = DEFAULT_MIN_SHARED, k: int = K,
                 window: int = WINDOW) -> list[Pair]:
    """Compare the submissions at ``paths`` (and each with ``reference``); write the report.

    Returns the flagged pairs, most similar first.
    """
    modules = exercise_modules(Path(reference) if reference is not None else REFERENCE_DIR)
    # The stubs of every file handed out: untouched library files never count either.
    stubs, boilerplate = stub_tokens(Path(stubs_dir), sorted(set(modules) | set(package_modules(Path(stubs_dir)))),
                                     k, window)
    codes = load_codes(paths, modules, stubs, boilerplate, k, window)
    pairs = [compare(a, b) for a, b in itertools.combinations(codes, 2)]
    everyone = list(codes)
    if reference is not None:
        reference_code = fingerprint_code(read_package(Path(reference), modules, Code(REFERENCE_ID, str(reference)),
                                                       stubs), boilerplate, k, window)
        pairs += [compare(code, reference_code) for code in codes]
        everyone.append(reference_code)
    write_report(Path(out_dir), everyone, pairs, threshold, min_shared, k, window)
    return sorted([p for p in pairs if flagged(p, threshold, min_shared)], key=lambda p: -p.similarity)


# Command line ---------------------------------------------------------------------------------------
def add_similarity_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``grader similarity``."""
    parser.add_argument("submissions", nargs="+", metavar="SUBMISSION",
                        help="a folder or a .zip holding a copy of exercises/ (use class/* for a folder of them)")
    parser.add_argument("--out", required=True, metavar="DIR", help="folder for similarity.csv and similarity.html")
    parser.add_argument("--reference", default=str(REFERENCE_DIR), metavar="PATH",
                        help="the reference package to compare every submission with (default: %(default)s; "
                             "'none' for no reference)")
    parser.add_argument("--stubs", default=str(STUBS_DIR), metavar="PATH",
                        help="the package handed out to students: its code never counts (default: %(default)s)")
    parser.add_argument("--threshold", type=float, default=DEFAULT_THRESHOLD, metavar="SHARE",
                        help="flag pairs at least this similar, 0 to 1 (default %(default)g)")
    parser.add_argument("--min-shared", type=int, default=DEFAULT_MIN_SHARED, metavar="N",
                        help="and sharing at least N fingerprints (default %(default)s)")
    parser.add_argument("-k", type=int, default=K, help="tokens per k-gram (default %(default)s)")
    parser.add_argument("--window", type=int, default=WINDOW, help="winnowing window (default %(default)s)")


def main_similarity(args: argparse.Namespace) -> int:
    """Run ``grader similarity``; 0 on success, 2 for bad arguments."""
    if not 0 <= args.threshold <= 1 or args.k < 1 or args.window < 1:
        print("grader similarity: error: --threshold must be in [0, 1], -k and --window at least 1", file=sys.stderr)
        return 2
    reference = None if str(args.reference).lower() == "none" else Path(args.reference)
    if reference is not None and not reference.is_dir():
        print(f"grader similarity: error: no reference package at {reference}", file=sys.stderr)
        return 2
    try:
        flags = find_similar(args.submissions, args.out, reference, args.stubs, args.threshold, args.min_shared,
                             args.k, args.window)
    except SubmissionPathError as exc:
        print(f"grader similarity: error: {exc}", file=sys.stderr)
        return 2
    print(f"{len(flags)} pairs flagged (similarity >= {args.threshold:g}, >= {args.min_shared} shared fingerprints)")
    for pair in flags[:20]:
        print(f"  {pair.similarity:6.1%}  {pair.a.id}  {pair.b.id}")
    if len(flags) > 20:
        print(f"  ... and {len(flags) - 20} more")
    print(f"report: {Path(args.out) / HTML_NAME}\nscores: {Path(args.out) / CSV_NAME}")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m grader.batch.similarity", description=__doc__.split("\n\n")[0])
    add_similarity_arguments(parser)
    return main_similarity(parser.parse_args(argv))


if __name__ == "__main__":
    sys.exit(main())
