"""The leak scan of a release: every ``### BEGIN SOLUTION`` block of the reference
engine as a stream of Python tokens, looked for in every text a folder holds (files, zip
members, notebook cells and outputs, JSON strings), whatever its layout and comments.

Instructors only (never ships).  :func:`grader.release.edition.verify_student` runs it on
the student edition before anything is moved into place; ``grader update``'s tests run it
on a merged folder.
"""
from __future__ import annotations

import io
import json
import re
import textwrap
import tokenize
import zipfile
from dataclasses import dataclass
from pathlib import Path

from .exercises import BEGIN_MARKER, END_MARKER

#: A block shorter than this many tokens (``return a``) is too common to mean a leak.
MIN_BLOCK_TOKENS = 8

_SKIPPED_TOKENS = {tokenize.COMMENT, tokenize.NL, tokenize.NEWLINE, tokenize.INDENT, tokenize.DEDENT,
                   tokenize.ENDMARKER}
_ATOM = re.compile(r"\w+|[^\w\s]")


@dataclass(frozen=True)
class SolutionBlock:
    """One ``### BEGIN/END SOLUTION`` block: where, and its normalised tokens."""

    where: str
    tokens: tuple[str, ...]
    key: str = ""    # the joined atoms looked for


def _block(where: str, tokens) -> SolutionBlock:
    return SolutionBlock(where, tuple(tokens), _joined(atoms_of_tokens(tokens)))


def python_tokens(text: str) -> list[str] | None:
    """The tokens of Python ``text`` without comments, newlines and indentation (None if
    it does not tokenize)."""
    try:
        return [t.string for t in tokenize.generate_tokens(io.StringIO(text).readline) if t.type not in _SKIPPED_TOKENS]
    except (tokenize.TokenError, IndentationError, SyntaxError):
        return None


def atoms_of_tokens(tokens) -> list[str]:
    """Tokens split into words and single punctuation marks: the same atoms whether the
    text was Python (tokenized) or anything else (split directly)."""
    return [atom for token in tokens for atom in _ATOM.findall(token)]


def _joined(atoms: list[str]) -> str:
    return "\x1f" + "\x1f".join(atoms) + "\x1f"


def solution_blocks(solutions_dir: Path) -> list[SolutionBlock]:
    """Every solution block of the reference engine, tokenized."""
    blocks = []
    for path in sorted(Path(solutions_dir).rglob("*.py")):
        if "__pycache__" in path.parts:
            continue
        lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
        start = None
        for number, line in enumerate(lines):
            if line.strip() == BEGIN_MARKER:
                start = number
            elif line.strip() == END_MARKER and start is not None:
                text = textwrap.dedent("".join(lines[start + 1:number]))
                tokens = python_tokens(text) or _ATOM.findall(text)
                where = f"{path.relative_to(Path(solutions_dir).parent).as_posix()}:{start + 1}"
                blocks.append(_block(where, tokens))
                start = None
    return blocks


def text_keys(text: str) -> list[str]:
    """The joined atoms of ``text``: as Python tokens (comments dropped) when it
    tokenizes, and as raw atoms (covers prose, HTML, broken code) always."""
    keys = [_joined(_ATOM.findall(text))]
    tokens = python_tokens(text)
    if tokens is not None:
        keys.append(_joined(atoms_of_tokens(tokens)))
    without_magics = "\n".join(line for line in text.split("\n") if not line.lstrip().startswith(("%", "!")))
    if without_magics != text:
        tokens = python_tokens(without_magics)
        if tokens is not None:
            keys.append(_joined(atoms_of_tokens(tokens)))
    return keys


def texts_of_file(name: str, data: bytes) -> list[str]:
    """Every text a file holds: zip members (recursively), a notebook's cells and
    outputs, a JSON file's strings, or the decoded file."""
    from .book import notebook_texts  # deferred: nbformat, only when the student edition is written

    if name.endswith(".zip") or data[:4] == b"PK\x03\x04":
        texts = []
        try:
            with zipfile.ZipFile(io.BytesIO(data)) as archive:
                for member in archive.infolist():
                    if not member.is_dir():
                        texts += texts_of_file(member.filename, archive.read(member))
        except zipfile.BadZipFile:
            texts.append(data.decode("latin-1"))
        return texts
    if name.endswith(".pyc"):
        return [data.decode("latin-1")]
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        return [] if b"\0" in data else [data.decode("latin-1")]
    texts = [text]
    if name.endswith(".ipynb"):
        try:
            texts += notebook_texts(json.loads(text))
        except (ValueError, AttributeError, TypeError):
            pass
    elif name.endswith(".json"):
        try:
            texts += [s for s in _strings_of(json.loads(text)) if s]
        except ValueError:
            pass
    return texts


def _strings_of(value):
    """The strings in JSON data (a list of strings joined, as nbformat splits text),
    images left out."""
    if isinstance(value, str):
        yield value
    elif isinstance(value, dict):
        for key, item in value.items():
            if not str(key).startswith("image/"):
                yield from _strings_of(item)
    elif isinstance(value, list):
        if value and all(isinstance(v, str) for v in value):
            yield "".join(value)
        for item in value:
            yield from _strings_of(item)


def scan_for_solutions(folder: Path, blocks: list[SolutionBlock]) -> list[str]:
    """Where a solution block (of at least MIN_BLOCK_TOKENS tokens) shows in ``folder``."""
    checked = [b for b in blocks if len(b.tokens) >= MIN_BLOCK_TOKENS]
    found = []
    for path in sorted(p for p in Path(folder).rglob("*") if p.is_file()):
        relative = path.relative_to(folder).as_posix()
        for text in texts_of_file(path.name, path.read_bytes()):
            keys = text_keys(text)
            for block in checked:
                if any(block.key in key for key in keys):
                    found.append(f"{relative} holds the solution block of {block.where}")
    return sorted(set(found))
