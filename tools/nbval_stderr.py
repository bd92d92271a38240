"""A pytest plugin for the book's nbval run (``tools.book.nbval`` loads it with ``-p``): a
chapter cell whose fresh run writes to stderr fails, its outputs compared or not
(``nbval-ignore-output``).

The book's build fails on stderr in a cell's outputs (``stderr_output: warn`` under -W,
``book/_config.yml``).  The test suite's build shows the outputs stored in each ``.ipynb``
(``tools.book.build(stored_outputs=True)``) rather than running every chapter a second
time, so the fresh run's stderr is checked here: nbval alone would let it through in a
cell whose outputs it does not compare.  A cell tagged ``remove-stderr`` (myst-nb drops
its stderr) is let through, as the build does.
"""
from __future__ import annotations

import pytest


def stderr_text(outputs) -> str:
    """The stderr stream outputs of a cell's run, joined.

    >>> stderr_text([{"output_type": "stream", "name": "stdout", "text": "ok"},
    ...              {"output_type": "stream", "name": "stderr", "text": "DeprecationWarning"}])
    'DeprecationWarning'
    """
    return "".join(out.get("text", "") for out in outputs
                   if out.get("output_type") == "stream" and out.get("name") == "stderr")


@pytest.hookimpl(wrapper=True)
def pytest_runtest_call(item):
    result = yield
    cell = getattr(item, "cell", None)
    if cell is not None and "remove-stderr" not in cell.get("metadata", {}).get("tags", []):
        written = stderr_text(getattr(item, "test_outputs", None) or [])
        if written:
            pytest.fail(f"{item.name} wrote to stderr (the book's build fails on it):\n{written[-2000:]}",
                        pytrace=False)
    return result
