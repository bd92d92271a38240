"""grader.oracles.derivation_cache: a derivation kept once per version of its module."""
import pytest

from grader.oracles.derivation_cache import cache_path, cached, sympy_versions


@pytest.fixture
def module(tmp_path):
    path = tmp_path / "oracle.py"
    path.write_text("FORMULA = 'x + 1'\n")
    return path


class Derivation:
    """A derivation that counts its runs."""

    def __init__(self, value):
        self.value, self.runs = value, 0

    def __call__(self):
        self.runs += 1
        return self.value


def test_a_derivation_runs_once_per_version_of_its_module(module):
    derive = Derivation({"k": (1, 2.5)})
    assert cached(module, "forms", derive, ("3.11",)) == {"k": (1, 2.5)}
    assert cached(module, "forms", derive, ("3.11",)) == {"k": (1, 2.5)} and derive.runs == 1
    kept = cache_path(module, "forms", ("3.11",))
    assert kept.parent == module.parent / "__pycache__" and kept.exists()
    assert cached(module, "forms", derive, ("3.12",)) == {"k": (1, 2.5)} and derive.runs == 2   # another library
    module.write_text("FORMULA = 'x + 2'\n")
    assert cached(module, "forms", Derivation("edited"), ("3.12",)) == "edited"
    assert [p.name for p in kept.parent.iterdir()] == [cache_path(module, "forms", ("3.12",)).name]  # the stale ones gone


def test_a_broken_file_is_derived_again(module):
    cached(module, "forms", Derivation("first"), ())
    cache_path(module, "forms", ()).write_bytes(b"\x80\x05not a pickle")
    derive = Derivation("again")
    assert cached(module, "forms", derive, ()) == "again" and derive.runs == 1
    assert cached(module, "forms", Derivation("unused"), ()) == "again"


def test_a_folder_that_cannot_be_written_only_costs_the_derivation(module):
    (module.parent / "__pycache__").write_text("a file where the folder would go\n")
    derive = Derivation("value")
    assert cached(module, "forms", derive, ()) == "value"
    assert cached(module, "forms", derive, ()) == "value" and derive.runs == 2
    assert sorted(p.name for p in module.parent.iterdir()) == ["__pycache__", "oracle.py"]


def test_the_impulse_oracle_keeps_its_derivation():
    from grader.oracles import impulse_sympy

    impulse_sympy.derived()
    assert cache_path(impulse_sympy.__file__, "derived", sympy_versions()).exists()


def test_the_momentum_tests_keep_their_closed_forms():
    from grader.tests.public import test_momentum

    general, common = test_momentum.wall_forms()
    assert cache_path(test_momentum.__file__, "wall_forms", sympy_versions()).exists()
    assert general(0.0, 0.0, 1.0, -2.0, 1.0) == (0.0, 2.0) and common(1.0, 3.0, 1.0, 1.0) == 2.0   # a wall; equal masses
