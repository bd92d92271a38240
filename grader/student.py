"""Calls into a student's package, from the trusted side.

:class:`StudentCode` encodes reference-engine values (shapes, bodies, contacts) as
plain data, calls the worker, and turns every way a call can go wrong into a
:class:`~grader.outcome.StudentCallFailed` whose outcome explains it.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from . import codec
from .outcome import OUTPUT_LIMIT, Outcome, StudentCallFailed, StudentCallStopped
from .sandbox import CallResult, Sandbox

STATUS_WORDS = {
    "not_implemented": ("not_implemented", "not implemented yet"),
    "import_error": ("error", "your module could not be imported"),
    "missing": ("error", "the function is missing"),
    "error": ("error", "your code raised an exception"),
    "unreadable": ("error", "your function returned something the grader cannot read"),
    "timeout": ("timeout", "your code took too long"),
    "crashed": ("crashed", "your code crashed the worker process"),
}


def encode(value: Any) -> Any:
    """Reference values as plain data for the worker."""
    if isinstance(value, np.ndarray):
        return {codec.ARRAY_TAG: value.tolist()}
    if isinstance(value, (list, tuple)):
        return [encode(v) for v in value]
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    if value is None or isinstance(value, (bool, int, float, str, dict)):
        return value
    return codec.encode_value(value)


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

    def __repr__(self) -> str:  # how Hypothesis's "falsifying example" names this argument
        return f"<the {self.package} package under test>"

    def take_output(self) -> str:
        """What the student's code printed since the last call of this (capped)."""
        text = "".join(self._printed)
        self._printed.clear()
        self._printed_size = 0
        return text

    def _keep_output(self, output: str) -> None:
        room = OUTPUT_LIMIT - self._printed_size
        if output and room > 0:
            self._printed.append(output[:room])
            self._printed_size += min(room, len(output))

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

    def call_many(self, module: str, function: str, cases: list[tuple], timeout: float | None = None) -> list:
        """One value per argument tuple in ``cases``, in one round trip."""
        result = self.raw(module, function, cases, timeout=timeout, batch=True)
        values = self.value_of(result, f"{module}.{function}")
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

    @staticmethod
    def value_of(result: CallResult, name: str) -> Any:
        """The value of a call; a not-implemented, timed-out or crashed call stops the
        test (StudentCallStopped), any other failure fails it (StudentCallFailed)."""
        if result.ok:
            return result.value
        status, words = STATUS_WORDS.get(result.status, ("error", result.status))
        if result.status == "not_implemented":
            stub = result.message.partition("not implemented yet: ")[2].strip()
            detail = f": {stub}" if stub else ""
        else:
            detail = f"\n{result.message}".rstrip()
        outcome = Outcome(status, message=f"{name}: {words}{detail}")
        if status in ("not_implemented", "timeout", "crashed"):
            raise StudentCallStopped(outcome)
        raise StudentCallFailed(outcome)
