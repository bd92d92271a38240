"""StudentCode.call_once: a check several tests make on the same input runs once per package;
StudentCode.kept: a large argument several calls read crosses the channel once."""
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


def test_kept_arrays_are_keyed_by_content_and_sent_whole_past_the_limit(monkeypatch):
    """StudentCode.kept: equal arrays share a key (sent once to a worker, then referred to);
    another array has its own; past KEPT_NUMBERS_LIMIT an argument is sent whole each time."""
    from grader.sandbox import kept
    from grader.sandbox.codec import ARRAY_TAG, KEEP_TAG, KEPT_TAG

    boxes = np.arange(8.0).reshape(2, 4)
    held = kept.KeptValues()
    first = held.form(StudentCode.kept(boxes))
    assert first == {KEEP_TAG: first[KEEP_TAG], "value": {ARRAY_TAG: boxes.tolist()}}
    assert held.form(StudentCode.kept(boxes.copy())) == {KEPT_TAG: first[KEEP_TAG]}
    assert held.form(StudentCode.kept(boxes.T.copy()))[KEEP_TAG] != first[KEEP_TAG]
    monkeypatch.setattr(kept, "KEPT_NUMBERS_LIMIT", 20)
    assert held.form(StudentCode.kept(boxes + 1)) == {ARRAY_TAG: (boxes + 1).tolist()}
    assert held.form(0.1) == 0.1
