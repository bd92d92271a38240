"""The student-side worker: runs exercise functions on request, answers in plain data.

Runs inside the sandbox (see :mod:`grader.sandbox.process`) with the student's ``exercises``
package in its working folder, and nothing of the grader but this file and
``codec.py``.  Protocol: one JSON request per line on standard input::

    {"id": 7, "module": "exercises.narrowphase.circle_circle",
     "function": "collide_circle_circle", "args": [...], "kwargs": {}, "repeat": 1}

(with ``"batch": true``, ``args`` is a list of argument lists and the value is the
list of results, one call each: fewer round trips for many random cases; with
``"program": {...}`` the worker runs a list of calls whose arguments may name
registers that earlier calls' results were stored in, and sends back the registers
asked for, see :meth:`Worker.run_program`: the grader's scenes step bodies in the trusted
process and call the student's functions many times in one round trip, while nothing
of the grader's own logic runs here)

and one JSON response per line on the file descriptor given as the first argument
(standard output is the student's, for their prints)::

    {"id": 7, "nonce": "...", "status": "ok", "value": ..., "args_after": [...], "output": "..."}

Before any student code runs, the worker writes a first line ``{"hello": true, "pid":
...}``: the parent learns the worker's process id from it (to kill every other process
of the sandbox's user after a call), not from answers student code could forge.  Each
request carries a random ``nonce`` that the answer must echo (see
:meth:`grader.sandbox.process.Sandbox.call` for what this does and does not protect).

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
#: The first line of the message of a batch call that raised: which case raised.
BATCH_CASE = "[batch case {}]\n"
MESSAGE_LIMIT = 8_000  # characters of an error message kept


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
        text = str.__str__(text) if isinstance(text, str) else repr(text)
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
    """The last frames of the student's traceback, without the worker's own (capped).

    Never raises: an exception whose ``__str__`` fails is named by its type alone.
    """
    try:
        frames = [f for f in traceback.extract_tb(exc.__traceback__)
                  if os.path.abspath(f.filename) != os.path.abspath(__file__)]
        lines = "".join(traceback.format_list(frames[-4:]))
    except BaseException:
        lines = ""
    try:
        text = f"{type(exc).__name__}: {exc}"
    except BaseException:
        text = f"{type(exc).__name__} (its message could not be shown)"
    return capped(lines + text)


def stub_named(exc: BaseException) -> str:
    """Where a NotImplementedError was raised, as ``"Quadtree.insert in broadphase/quadtree.py"``:
    the stub to write, which may be a method the called function uses."""
    frame = None
    tb = exc.__traceback__
    while tb is not None:
        frame = tb.tb_frame
        tb = tb.tb_next
    if frame is None:
        return "not implemented yet"
    code = frame.f_code
    name = getattr(code, "co_qualname", code.co_name)
    parts = os.path.normpath(code.co_filename).split(os.sep)
    where = "/".join(parts[parts.index("exercises") + 1:]) if "exercises" in parts else os.path.basename(
        code.co_filename)
    return f"not implemented yet: {name} in {where}"


def capped(text: str, limit: int = MESSAGE_LIMIT) -> str:
    text = str.__str__(text) if isinstance(text, str) else "(not a text)"
    if len(text) <= limit:
        return text
    return text[:limit] + f"\n[... {len(text) - limit} more characters not shown]"


class Worker:
    """Loads the student's modules once and answers requests one at a time."""

    def __init__(self, codec):
        self.codec = codec
        self.modules: dict[str, object] = {}
        self.program_call = 0  # index of the program call running (run_program)
        self.kept: dict[str, object] = {}  # plain values by key (grader.sandbox.kept)

    def load(self, name: str):
        if name not in self.modules:
            self.modules[name] = importlib.import_module(name)
        return self.modules[name]

    def keep(self, request: dict) -> None:
        """Store the arguments ``request`` asks the worker to keep, before anything else
        runs (so a request that fails early still leaves them held, as the parent counts)."""
        if request.get("batch") or request.get("program") is not None:
            return
        for value in [*request.get("args", []), *request.get("kwargs", {}).values()]:
            if type(value) is dict and self.codec.KEEP_TAG in value:
                self.kept[value[self.codec.KEEP_TAG]] = value["value"]

    def decode(self, value):
        codec = self.codec
        if isinstance(value, dict):
            if codec.KEPT_TAG in value:     # a fresh copy of what an earlier request sent
                return self.decode(self.kept[value[codec.KEPT_TAG]])
            if codec.KEEP_TAG in value:
                return self.decode(value["value"])
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

    def run_program(self, program: dict) -> dict:
        """Run ``program``'s calls in order; the values of its ``results`` registers after.

        ``program``: ``{"functions": [function, ...], "registers": {name: value},
        "calls": [[function index, args, outputs], ...], "results": [name, ...]}``.  An
        argument ``{"$register": name}`` is that register's value (a body stays the same
        object from call to call, changed in place); any other argument is a value.
        ``outputs`` stores the returned value: ``null`` nowhere, a name in that register,
        a list of names (or nulls) unpacks it.  The trusted side decided every call and
        reads only these final values, which the student's functions could have made
        anything by returning it: changing this loop from student code gains nothing.
        """
        functions = program["functions"]
        registers = {name: self.decode(value) for name, value in program["registers"].items()}
        for number, (index, arguments, outputs) in enumerate(program["calls"]):
            self.program_call = number
            values = [registers[a["$register"]] if type(a) is dict and "$register" in a else self.decode(a)
                      for a in arguments]
            value = functions[index](*values)
            if type(outputs) is str:
                registers[outputs] = value
            elif type(outputs) is list:
                parts = tuple(value) if isinstance(value, (tuple, list)) else ()
                if len(parts) != len(outputs):
                    raise ValueError(f"returned {capped(repr(value), 200)}, expected {len(outputs)} values")
                for name, part in zip(outputs, parts):
                    if name is not None:
                        registers[name] = part
        self.program_call = len(program["calls"])
        return {name: self.codec.encode_value(registers[name]) for name in program["results"]}

    def handle(self, request: dict, captured: CappedText) -> dict:
        """Run one request; the response's ``status`` says how it went."""
        self.keep(request)
        if request.get("program") is not None:
            return self.handle_program(request["program"], captured)
        try:
            target = self.load(request["module"])
        except BaseException as exc:  # a broken module must not stop the worker
            return {"status": "import_error", "message": short_traceback(exc)}
        try:
            for part in request["function"].split("."):
                target = getattr(target, part)
        except AttributeError:
            return {"status": "missing", "message": capped(f"{request['module']} has no {request['function']}")}
        except BaseException as exc:  # a module __getattr__ of the student's
            return {"status": "error", "message": short_traceback(exc)}
        try:
            args = [self.decode(a) for a in request.get("args", [])]
            kwargs = {k: self.decode(v) for k, v in request.get("kwargs", {}).items()}
        except BaseException as exc:
            return {"status": "import_error",
                    "message": f"could not build the inputs with your exercises package: {short_traceback(exc)}"}
        real = sys.stdout, sys.stderr
        sys.stdout = sys.stderr = captured
        value = []
        try:
            if request.get("batch"):
                # args is a list of argument lists: one call each, values in order.
                for one in args:
                    value.append(target(*one, **kwargs))
            else:
                for _ in range(int(request.get("repeat", 1))):
                    value = target(*args, **kwargs)
        except NotImplementedError as exc:
            return {"status": "not_implemented", "message": capped(stub_named(exc))}
        except RecursionError as exc:
            case = BATCH_CASE.format(len(value)) if request.get("batch") else ""
            return {"status": "error", "message": case + "recursion limit reached: " + short_traceback(exc)}
        except MemoryError:
            return {"status": "error", "message": "ran out of memory (MemoryError)"}
        except SystemExit as exc:
            return {"status": "error", "message": capped(f"called sys.exit({exc.code!r}) inside an exercise")}
        except BaseException as exc:
            case = BATCH_CASE.format(len(value)) if request.get("batch") else ""
            return {"status": "error", "message": case + short_traceback(exc)}
        finally:
            sys.stdout, sys.stderr = real
        try:
            return {"status": "ok", "value": self.codec.encode_value(value),
                    "args_after": [] if request.get("batch") else
                    [self.codec.encode_body(a) if type(a).__name__ == "Body" else None for a in args]}
        except BaseException as exc:
            return {"status": "unreadable", "message": short_traceback(exc).rsplit("\n", 1)[-1]}

    def handle_program(self, program: dict, captured: CappedText) -> dict:
        """Run a program (:meth:`run_program`): the status of its first failing call, whose
        message starts with ``[batch case N]`` (N its index), or ok with the registers asked for."""
        functions = []
        for module, name in program["functions"]:
            try:
                target = self.load(module)
            except BaseException as exc:
                return {"status": "import_error", "message": short_traceback(exc)}
            try:
                for part in name.split("."):
                    target = getattr(target, part)
            except BaseException:
                return {"status": "missing", "message": capped(f"{module} has no {name}")}
            functions.append(target)
        real = sys.stdout, sys.stderr
        sys.stdout = sys.stderr = captured
        try:
            registers = self.run_program({**program, "functions": functions})
        except NotImplementedError as exc:
            return {"status": "not_implemented", "message": capped(stub_named(exc))}
        except RecursionError as exc:
            return {"status": "error", "message": BATCH_CASE.format(self.program_call) + "recursion limit reached: "
                    + short_traceback(exc)}
        except MemoryError:
            return {"status": "error", "message": "ran out of memory (MemoryError)"}
        except SystemExit as exc:
            return {"status": "error", "message": capped(f"called sys.exit({exc.code!r}) inside an exercise")}
        except BaseException as exc:
            return {"status": "error", "message": BATCH_CASE.format(self.program_call) + short_traceback(exc)}
        finally:
            sys.stdout, sys.stderr = real
        return {"status": "ok", "value": registers, "args_after": []}


def main() -> None:
    sys.path.insert(0, os.getcwd())
    sys.path.insert(0, HERE)
    import codec  # the copy next to this file

    # Everything the loop needs is bound to local names before student code runs, so
    # that replacing json.dumps or the worker's functions from student code does not
    # change what this loop does.  (Student code can still reach these objects, e.g.
    # through gc or frames: the parent trusts nothing it receives, see Sandbox.call.)
    dumps, loads, getpid, leave = json.dumps, json.loads, os.getpid, os._exit
    channel = os.fdopen(int(sys.argv[1]), "w", encoding="utf-8", errors="backslashreplace")
    write, flush = channel.write, channel.flush
    requests = sys.stdin
    me = getpid()
    write(dumps({"hello": True, "pid": me}) + "\n")
    flush()
    worker = Worker(codec)
    for line in requests:
        if getpid() != me:
            leave(0)  # a copy made by os.fork in student code: only the worker reads requests
        try:
            request = loads(line)
            nonce, number = str(request.get("nonce")), request.get("id")
        except Exception:
            continue  # not a request of the parent's
        captured = CappedText(OUTPUT_LIMIT)
        response = {"id": number, "nonce": nonce, "status": "ok", "value": None, "message": ""}
        try:
            response.update(worker.handle(request, captured))
            response["output"] = captured.getvalue()
            text = dumps(response, allow_nan=True)
        except BaseException as exc:
            try:
                text = dumps({"id": number, "nonce": nonce, "status": "unreadable", "value": None,
                              "message": short_traceback(exc).rsplit("\n", 1)[-1], "output": ""})
            except BaseException:  # json itself broken by student code: no json needed
                text = ('{"id": %d, "nonce": "%s", "status": "unreadable", "value": null, "output": "", '
                        '"message": "the answer could not be encoded (was json patched?)"}'
                        % (number if type(number) is int else 0, nonce if nonce.isalnum() else ""))
        if getpid() != me:
            leave(0)  # a forked copy returning from student code never answers
        # The leading newline ends any partial line student code wrote on the channel,
        # so that the answer is a line of its own.
        write("\n" + text + "\n")
        flush()


if __name__ == "__main__":
    main()
