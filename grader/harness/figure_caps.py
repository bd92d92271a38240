"""How much of a failing case's picture is kept: the caps of :mod:`grader.harness.figures`'
plain data, applied before anything is drawn, stored or sent.

Apart from the drawing so that a grading process, which only passes the data on, never
imports matplotlib (about two thirds of its start-up imports).
"""
from __future__ import annotations

#: The most of each list a figure keeps: what a student's answer may make large is cut
#: before anything is drawn, stored or sent (drawing is linear in these).
FIGURE_CAPS = {"points": 16, "vertices": 64, "aabbs": 4000, "missed": 400, "extra": 400, "title": 300}


def bounded(figure):
    """A copy of ``figure`` with every list a student's answer can grow cut to
    :data:`FIGURE_CAPS` (and a note of what was cut); anything not a dict is None."""
    if not isinstance(figure, dict):
        return None
    cut: list[str] = []

    def limit(items, name):
        if not isinstance(items, (list, tuple)):
            return items
        if len(items) > FIGURE_CAPS[name]:
            cut.append(f"{len(items)} {name}")
            return list(items[:FIGURE_CAPS[name]])
        return list(items)

    def contact(value):
        if not isinstance(value, dict):
            return value
        value = dict(value)
        for name in ("points", "depths"):
            if name in value:
                value[name] = limit(value[name], "points")
        return value

    def shape(value):
        if isinstance(value, dict) and "vertices" in value:
            value = dict(value)
            value["vertices"] = limit(value["vertices"], "vertices")
        return value

    out = dict(figure)
    if isinstance(out.get("title"), str):
        out["title"] = out["title"][:FIGURE_CAPS["title"]]
    if "shapes" in out:
        out["shapes"] = [shape(v) for v in (limit(out["shapes"], "vertices") or [])][:2]
    for name in ("expected", "got"):
        if name in out:
            out[name] = contact(out[name])
    for name in ("aabbs", "missed", "extra"):
        if name in out:
            out[name] = limit(out[name], name)
    if cut:
        out["cut"] = "only part of the case is drawn: " + ", ".join(cut)
        out["title"] = f"{out.get('title', '')} ({out['cut']})".strip()
    return out
