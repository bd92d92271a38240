"""The speed tests keep the reference's run per grading process
(grader.harness.reference_runs): the same answer for every submission, its time measured
again side by side every few submissions and whenever the student's time is well over
the kept figure."""
from pathlib import Path
from types import SimpleNamespace

from grader.harness import reference_runs


def test_a_reference_run_is_served_again_until_stale_or_until_the_student_looks_slow(monkeypatch, tmp_path):
    monkeypatch.setattr(reference_runs, "_KEPT", {})
    runs = []

    def run():
        runs.append(len(runs) + 1)
        return f"answer {len(runs)}", 1.0

    reference = SimpleNamespace(sandbox=SimpleNamespace(package_dir=Path(tmp_path)))
    kept = reference_runs.REFERENCE_RUNS_KEPT
    seen = [reference_runs.kept_reference_run(reference, "scene", 1.0, run) for _ in range(kept + 1)]
    assert seen == [("answer 1", 1.0)] * kept + [("answer 2", 1.0)]   # run again after `kept` submissions
    slow = 1.0 * reference_runs.SLOWER_THAN_KEPT + 0.01
    assert reference_runs.kept_reference_run(reference, "scene", slow, run) == ("answer 3", 1.0)
    assert reference_runs.kept_reference_run(reference, "other test", 1.0, run) == ("answer 4", 1.0)
    other = SimpleNamespace(sandbox=SimpleNamespace(package_dir=Path(tmp_path) / "other"))
    assert reference_runs.kept_reference_run(other, "scene", None, run) == ("answer 5", 1.0)
    assert len(runs) == 5


def test_a_reference_run_without_a_time_is_not_kept(monkeypatch, tmp_path):
    monkeypatch.setattr(reference_runs, "_KEPT", {})
    reference = SimpleNamespace(sandbox=SimpleNamespace(package_dir=Path(tmp_path)))
    runs = []
    for _ in range(2):
        assert reference_runs.kept_reference_run(reference, "scene", 1.0, lambda: runs.append(1) or (None, None)) == (
            None, None)
    assert len(runs) == 2
