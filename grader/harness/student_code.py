"""Calls into a student's package, from the trusted side.

:class:`StudentCode` encodes reference-engine values (shapes, bodies, contacts) as
plain data, calls the worker, and turns every way a call can go wrong into a
:class:`~grader.harness.outcome.StudentCallFailed` whose outcome explains it.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import re
import weakref
from typing import Any

import numpy as np

from ..sandbox import codec
from ..sandbox.kept import KeptArgument, kept_array
from .outcome import OUTPUT_LIMIT, Outcome, StudentCallFailed, StudentCallStopped, capped_output
from ..sandbox.process import CallResult, Sandbox
from .compare import call_text

#: The marker the worker puts after a call's printed output when it cut some (worker.CappedText).
WORKER_CUT = re.compile(r"\n\[\.\.\. (\d+) more characters not shown\]$")
#: The line the worker puts before the message of a batch call that raised: the index of
#: the case that raised (worker.BATCH_CASE).
BATCH_CASE = re.compile(r"^\[batch case (\d+)\]\n")
#: Every StudentCode alive, so that a search for a small failing case can set aside
#: what the examples it tried printed (:func:`output_of_the_case_found`).
_LIVE: "weakref.WeakSet[StudentCode]" = weakref.WeakSet()

#: The key of a program argument that names a register (worker.Worker.run_program).
REGISTER = "$register"

#: How a call that returned no value ends its test: the call's status
#: (grader.sandbox.process.CALL_STATUSES) -> (the test's status, one of
#: grader.harness.outcome.STATUSES; what happened to the call, said to the student).
CALL_FAILURES = {
    "not_implemented": ("not_implemented", "not implemented yet"),
    "import_error": ("error", "your module could not be imported"),
    "missing": ("error", "the function is missing"),
    "error": ("error", "your code raised an exception"),
    "unreadable": ("error", "your function returned something the grader cannot read"),
    "timeout": ("timeout", "your code took too long"),
    "crashed": ("crashed", "your code crashed the worker process"),
}


def register(name: str) -> dict:
    """An argument of a program call (:meth:`StudentCode.run_program`): the value held in
    register ``name`` (a body there stays one object from call to call)."""
    return {REGISTER: name}


def encode(value: Any) -> Any:
    """Reference values as plain data for the worker."""
    kind = type(value)
    if kind in codec.EXACT_SCALARS:
        return value
    if kind is list or kind is tuple:   # builtin scalars kept without a call each
        return [v if type(v) in codec.EXACT_SCALARS else encode(v) for v in value]
    if isinstance(value, np.ndarray):
        return {codec.ARRAY_TAG: value.tolist()}
    if isinstance(value, (list, tuple)):
        return [encode(v) for v in value]
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if kind is KeptArgument:   # encoded when sent (grader.sandbox.kept)
        return value
    if value is None or isinstance(value, (bool, int, float, str, dict)):
        return value
    return codec.encode_value(value)


def raised_case(result: CallResult, count: int, describe) -> str:
    """Which of ``count`` calls raised, as ``describe(index)`` says it, when the worker's
    message starts by naming it (the name is taken off the message); else ``""``."""
    raised = BATCH_CASE.match(result.message or "")
    if not raised:
        return ""
    result.message = result.message[raised.end():]
    index = int(raised[1])
    return describe(index) if index < count else ""


class StudentCode:
    """The student's ``exercises`` package, reached through a sandboxed worker.

    ``module`` names are relative to the package: ``"narrowphase.circle_circle"``.
    """

    def __init__(self, sandbox: Sandbox, package: str = "exercises"):
        self.sandbox = sandbox
        self.package = package
        self.calls = 0
        self._printed: list[str] = []
        self._printed_size = 0
        self._dropped = 0  # characters printed and not kept
        self._once: dict[tuple, CallResult] = {}  # see call_once
        _LIVE.add(self)

    def __repr__(self) -> str:  # how Hypothesis's "falsifying example" names this argument
        return f"<the {self.package} package under test>"

    def take_output(self) -> str:
        """What the student's code printed since the last call of this, capped
        (:func:`grader.harness.outcome.capped_output`: a marker says how much was left out)."""
        text, dropped = "".join(self._printed), self._dropped
        self._printed.clear()
        self._printed_size = self._dropped = 0
        return capped_output(text, dropped)

    def _keep_output(self, output: str) -> None:
        cut = WORKER_CUT.search(output or "")
        if cut:
            output = output[:cut.start()]
            self._dropped += int(cut[1])
        room = OUTPUT_LIMIT + 1 - self._printed_size  # one more: capped_output then knows it cut
        if output and room > 0:
            self._printed.append(output[:room])
            self._printed_size += min(room, len(output))
        self._dropped += max(0, len(output or "") - max(room, 0))

    def raw(self, module: str, function: str, *args, timeout: float | None = None, repeat: int = 1,
            batch: bool = False) -> CallResult:
        """The call's result whatever its status."""
        self.calls += 1
        encoded = [[encode(a) for a in one] for one in args[0]] if batch else [encode(a) for a in args]
        result = self.sandbox.call(f"{self.package}.{module}", function, encoded, timeout=timeout,
                                   repeat=repeat, batch=batch)
        self._keep_output(result.output)
        return result

    def call(self, module: str, function: str, *args, timeout: float | None = None) -> Any:
        """The returned value (plain data), or StudentCallFailed explaining what went wrong."""
        return self.value_of(self.raw(module, function, *args, timeout=timeout), f"{module}.{function}")

    @staticmethod
    def kept(array: np.ndarray) -> KeptArgument:
        """``array`` as an argument each worker process receives once and keeps: later calls
        with an equal array send only its key (:mod:`grader.sandbox.kept`).  For the large
        scenes several calls read."""
        return kept_array(array, encode)

    def call_once(self, module: str, function: str, *args, timeout: float | None = None) -> Any:
        """As :meth:`call`, but a call identical to one made before on this package (same
        function, same arguments) is not run again: the first one's result stands, whatever
        it was (a value, an exception, a timeout).  For a check several tests make on the
        same input (the dynamic tree's counted searches), which costs the sandbox seconds
        each time and would only tell a function that answers differently for the same
        input -- a test of the same input then judges the same answer."""
        encoded = json.dumps([encode(a) for a in args], allow_nan=True).encode()
        key = (module, function, hashlib.sha256(encoded).hexdigest())
        if key not in self._once:
            self._once[key] = self.raw(module, function, *args, timeout=timeout)
        return self.value_of(self._once[key], f"{module}.{function}")

    def call_many(self, module: str, function: str, cases: list[tuple], timeout: float | None = None) -> list:
        """One value per argument tuple in ``cases``, in one round trip.  A case that
        raises is named in the failure, with its input."""
        result = self.raw(module, function, cases, timeout=timeout, batch=True)
        case = raised_case(result, len(cases),
                           lambda index: f"on the case {call_text(function, *(encode(a) for a in cases[index]))}")
        values = self.value_of(result, f"{module}.{function}", case)
        if not isinstance(values, list) or len(values) != len(cases):
            got = f"{len(values)} results" if isinstance(values, list) else "no list of results"
            raise StudentCallFailed(Outcome("error", message=f"{module}.{function}: the worker returned {got} "
                                                             f"for {len(cases)} calls"))
        return values

    def call_with_state(self, module: str, function: str, *args, timeout: float | None = None) -> tuple[Any, list]:
        """The returned value and the arguments after the call (bodies changed in place)."""
        result = self.raw(module, function, *args, timeout=timeout)
        value = self.value_of(result, f"{module}.{function}")
        if len(result.args_after) != len(args):
            raise StudentCallFailed(Outcome("error", message=f"{module}.{function}: the worker did not send back "
                                                             "the state of the arguments after the call"))
        return value, result.args_after

    def run_program(self, functions: list[tuple[str, str]], registers: dict[str, Any], calls: list[tuple],
                    results: list[str], name: str, timeout: float | None = None) -> tuple[dict[str, Any], float]:
        """Many calls of the student's functions in one round trip, the trusted side
        deciding every argument (:meth:`grader.sandbox.worker.Worker.run_program`).

        ``functions``: ``(module, function)`` pairs; ``registers``: initial values
        (reference values, encoded here); ``calls``: ``(function index, args, outputs)``,
        an argument made by :func:`register` or a value, ``outputs`` None, a register
        name, or a list of names to unpack the value into.  Returns the plain values of
        the ``results`` registers after the last call, and the round trip's seconds; a
        failing call fails the test naming ``name`` and the call."""
        self.calls += 1
        program = {"functions": [[f"{self.package}.{module}", function] for module, function in functions],
                   "registers": {key: encode(value) for key, value in registers.items()},
                   "calls": [[index, [a if isinstance(a, dict) and REGISTER in a else encode(a) for a in args],
                              outputs] for index, args, outputs in calls],
                   "results": list(results)}
        result = self.sandbox.call("", "", program=program, timeout=timeout)
        self._keep_output(result.output)
        case = raised_case(result, len(calls),
                           lambda index: f"at call {index + 1} of {len(calls)} ({functions[calls[index][0]][1]})")
        values = self.value_of(result, name, case)
        if not isinstance(values, dict) or sorted(values) != sorted(results):
            raise StudentCallFailed(Outcome("error", message=f"{name}: the worker did not send back the values "
                                                             "the grader asked for"))
        return values, result.elapsed

    @staticmethod
    def value_of(result: CallResult, name: str, case: str = "") -> Any:
        """The value of a call; a not-implemented, timed-out or crashed call stops the
        test (StudentCallStopped), any other failure fails it (StudentCallFailed).
        ``case`` names the input that failed, after what happened."""
        if result.ok:
            return result.value
        status, words = CALL_FAILURES.get(result.status, ("error", result.status))
        if result.status == "not_implemented":
            stub = result.message.partition("not implemented yet: ")[2].strip()
            detail = f": {stub}" if stub else ""
        else:
            detail = f"\n{result.message}".rstrip()
        outcome = Outcome(status, message=f"{name}: {words}{' ' + case if case else ''}{detail}")
        if status in ("not_implemented", "timeout", "crashed"):
            raise StudentCallStopped(outcome)
        raise StudentCallFailed(outcome)


@contextlib.contextmanager
def output_of_the_case_found():
    """Around a search for a small failing case (:func:`grader.harness.shrink.smallest_failure`):
    what the examples tried printed is set aside, so that a test's output is what its
    code printed for the case the test shows.  The context's value is a dict: set
    ``found`` true when a case was found (the output then starts empty, and the test
    runs that case again); else the output printed before the search is put back.  An
    exception (a stub, a timeout) leaves everything printed in place."""
    saved = {code: (list(code._printed), code._printed_size, code._dropped) for code in list(_LIVE)}
    for code in saved:
        code.take_output()
    search = {"found": False}
    try:
        yield search
    except BaseException:
        for code, (printed, size, dropped) in saved.items():
            code._printed[:0] = printed
            code._printed_size += size
            code._dropped += dropped
        raise
    for code in list(_LIVE):
        code.take_output()
        if not search["found"] and code in saved:
            code._printed, code._printed_size, code._dropped = saved[code]


def forget_output() -> None:
    """Forget what every StudentCode kept of the printed output (a new example starts)."""
    for code in list(_LIVE):
        code.take_output()
