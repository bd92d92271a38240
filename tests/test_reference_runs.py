"""impulse.scene keeps the reference's run of its ball scene per grading process
(grader/tests/hidden/test_impulse.py, reference_run): the same trajectory for every
submission, its time measured again side by side every few submissions and whenever the
student's time is well over the kept figure."""
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from grader.tests.hidden import test_impulse


def test_the_reference_scene_is_run_again_only_when_stale_or_when_the_student_looks_slow(monkeypatch, tmp_path):
    runs = []

    def run_scene(code, who):
        runs.append(who)
        return np.full((2, 3), len(runs), dtype=float), 0.1, 1.0   # trajectory, radius, seconds

    monkeypatch.setattr(test_impulse, "run_scene", run_scene)
    monkeypatch.setattr(test_impulse, "_REFERENCE_RUNS", {})
    reference = SimpleNamespace(sandbox=SimpleNamespace(package_dir=Path(tmp_path)))
    kept = test_impulse.REFERENCE_RUNS_KEPT
    seen = [test_impulse.reference_run(reference, 1.0) for _ in range(kept + 1)]
    assert len(runs) == 2                                   # the first submission and the one after `kept`
    assert all(trajectory[0, 0] == 1 for trajectory, _ in seen[:kept]) and seen[kept][0][0, 0] == 2
    slow = test_impulse.reference_run(reference, 1.0 * test_impulse.SLOWER_THAN_KEPT + 0.01)
    assert len(runs) == 3 and slow[0][0, 0] == 3 and slow[1] == 1.0
    other = SimpleNamespace(sandbox=SimpleNamespace(package_dir=Path(tmp_path) / "other"))
    test_impulse.reference_run(other, 0.5)
    assert len(runs) == 4                                   # another reference folder has its own run
