"""StudentCode.call_once: a check several tests make on the same input runs once per package."""
import numpy as np
import pytest

from grader.harness.outcome import StudentCallFailed, StudentCallStopped
from grader.harness.student_code import StudentCode
from grader.sandbox.process import CallResult


class CountingSandbox:
    """Answers every call with the next of ``results`` (the last one again when they run out)."""

    def __init__(self, *results: CallResult):
        self.results = list(results)
        self.requests = []

    def call(self, module, function, args=(), **options):
        self.requests.append((module, function, args))
        return self.results[min(len(self.requests), len(self.results)) - 1]


def test_an_identical_call_is_answered_by_the_first_one_and_other_arguments_run_again():
    sandbox = CountingSandbox(CallResult("ok", {"reads": 7}), CallResult("ok", {"reads": 9}))
    student = StudentCode(sandbox)
    boxes = np.arange(8.0).reshape(2, 4)
    assert student.call_once("broadphase.reads", "pairs_reads", boxes, 0.1) == {"reads": 7}
    assert student.call_once("broadphase.reads", "pairs_reads", boxes.copy(), 0.1) == {"reads": 7}
    assert len(sandbox.requests) == 1
    assert student.call_once("broadphase.reads", "pairs_reads", boxes, 0.2) == {"reads": 9}
    assert student.call_once("broadphase.reads", "sibling_reads", boxes, 0.1) == {"reads": 9}
    assert len(sandbox.requests) == 3


@pytest.mark.parametrize("status, raised", [("error", StudentCallFailed), ("timeout", StudentCallStopped)])
def test_a_failed_call_fails_every_test_asking_for_it_without_running_again(status, raised):
    sandbox = CountingSandbox(CallResult(status, message="it went wrong"), CallResult("ok", 1))
    student = StudentCode(sandbox)
    for _ in range(2):
        with pytest.raises(raised) as caught:
            student.call_once("broadphase.reads", "pairs_reads", [[0.0, 0.0, 1.0, 1.0]])
        assert "broadphase.reads.pairs_reads" in caught.value.outcome.message
    assert len(sandbox.requests) == 1
