"""The student-side worker: runs exercise functions on request, answers in plain data.

Runs inside the sandbox (see :mod:`grader.sandbox`) with the student's ``exercises``
package in its working folder, and nothing of the grader but this file and
``codec.py``.  Protocol: one JSON request per line on standard input::

    {"id": 7, "module": "exercises.narrowphase.circle_circle",
     "function": "collide_circle_circle", "args": [...], "kwargs": {}, "repeat": 1}

(with ``"batch": true``, ``args`` is a list of argument lists and the value is the
list of results, one call each: fewer round trips for many random cases)

and one JSON response per line on the file descriptor given as the first argument
(standard output is the student's, for their prints)::

    {"id": 7, "status": "ok", "value": ..., "args_after": [...], "output": "..."}

``status`` is one of ``ok``, ``not_implemented``, ``import_error``, ``missing``,
``error``, ``unreadable`` (a return value the codec cannot encode).  The worker judges
nothing: every comparison and score is computed by the trusted parent.
"""
from __future__ import annotations

import importlib
import io
import json
import os
import sys
import traceback

HERE = os.path.dirname(os.path.abspath(__file__))
OUTPUT_LIMIT = 8_000  # characters of printed output kept per call


class CappedText(io.TextIOBase):
    """A text sink that keeps only the first ``limit`` characters written."""

    def __init__(self, limit: int):
        self.limit = limit
        self.parts: list[str] = []
        self.size = 0
        self.dropped = 0

    def writable(self):
        return True

    def write(self, text):
        text = str(text)
        room = self.limit - self.size
        if room > 0:
            self.parts.append(text[:room])
            self.size += min(room, len(text))
        self.dropped += max(0, len(text) - max(room, 0))
        return len(text)

    def getvalue(self) -> str:
        tail = f"\n[... {self.dropped} more characters not shown]" if self.dropped else ""
        return "".join(self.parts) + tail


def short_traceback(exc: BaseException) -> str:
    """The last frames of the student's traceback, without the worker's own."""
    frames = [f for f in traceback.extract_tb(exc.__traceback__) if os.path.abspath(f.filename) != os.path.abspath(__file__)]
    lines = traceback.format_list(frames[-4:])
    return "".join(lines) + f"{type(exc).__name__}: {exc}"


class Worker:
    """Loads the student's modules once and answers requests one at a time."""

    def __init__(self, codec):
        self.codec = codec
        self.modules: dict[str, object] = {}

    def load(self, name: str):
        if name not in self.modules:
            self.modules[name] = importlib.import_module(name)
        return self.modules[name]

    def decode(self, value):
        codec = self.codec
        if isinstance(value, dict):
            if codec.SHAPE_TAG in value:
                return codec.decode_shape(value, self.load("exercises.shapes"))
            if codec.BODY_TAG in value:
                return codec.decode_body(value, self.load("exercises.shapes"), self.load("exercises.body"))
            if codec.CONTACT_TAG in value:
                return codec.decode_contact(value, self.load("exercises.contact"))
            if codec.ARRAY_TAG in value:
                import numpy
                return numpy.array(value[codec.ARRAY_TAG], dtype=float)
            return {k: self.decode(v) for k, v in value.items()}
        if isinstance(value, list):
            return [self.decode(v) for v in value]
        return value

    def handle(self, request: dict, captured: CappedText) -> dict:
        """Run one request; the response's ``status`` says how it went."""
        try:
            target = self.load(request["module"])
        except BaseException as exc:  # a broken module must not stop the worker
            return {"status": "import_error", "message": short_traceback(exc)}
        try:
            for part in request["function"].split("."):
                target = getattr(target, part)
        except AttributeError:
            return {"status": "missing", "message": f"{request['module']} has no {request['function']}"}
        try:
            args = [self.decode(a) for a in request.get("args", [])]
            kwargs = {k: self.decode(v) for k, v in request.get("kwargs", {}).items()}
        except BaseException as exc:
            return {"status": "import_error",
                    "message": f"could not build the inputs with your exercises package: {short_traceback(exc)}"}
        real = sys.stdout, sys.stderr
        sys.stdout = sys.stderr = captured
        try:
            if request.get("batch"):
                # args is a list of argument lists: one call each, values in order.
                value = [target(*one, **kwargs) for one in args]
            else:
                for _ in range(int(request.get("repeat", 1))):
                    value = target(*args, **kwargs)
        except NotImplementedError:
            return {"status": "not_implemented", "message": "not implemented yet"}
        except RecursionError as exc:
            return {"status": "error", "message": "recursion limit reached: " + short_traceback(exc)}
        except MemoryError:
            return {"status": "error", "message": "ran out of memory (MemoryError)"}
        except SystemExit as exc:
            return {"status": "error", "message": f"called sys.exit({exc.code!r}) inside an exercise"}
        except BaseException as exc:
            return {"status": "error", "message": short_traceback(exc)}
        finally:
            sys.stdout, sys.stderr = real
        try:
            return {"status": "ok", "value": self.codec.encode_value(value),
                    "args_after": [] if request.get("batch") else
                    [self.codec.encode_body(a) if type(a).__name__ == "Body" else None for a in args]}
        except BaseException as exc:
            return {"status": "unreadable", "message": f"{type(exc).__name__}: {exc}"}


def main() -> None:
    sys.path.insert(0, os.getcwd())
    sys.path.insert(0, HERE)
    import codec  # the copy next to this file

    channel = os.fdopen(int(sys.argv[1]), "w", encoding="utf-8")
    worker = Worker(codec)
    for line in sys.stdin:
        request = json.loads(line)
        captured = CappedText(OUTPUT_LIMIT)
        response = {"id": request.get("id"), "status": "ok", "value": None, "message": "", "pid": os.getpid()}
        response.update(worker.handle(request, captured))
        response["output"] = captured.getvalue()
        try:
            text = json.dumps(response, allow_nan=True)
        except BaseException as exc:
            text = json.dumps({"id": request.get("id"), "status": "unreadable", "value": None,
                               "message": f"{type(exc).__name__}: {exc}", "output": ""})
        channel.write(text + "\n")
        channel.flush()


if __name__ == "__main__":
    main()
