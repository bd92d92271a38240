"""Sample submissions the grader is tested with (instructor's side only).

- :mod:`.example_class`: the reference, the stubs and realistic buggy submissions,
  each with exactly the graded tests it must fail (``grader example-class``).
- :mod:`.hostile_cases`: broken and hostile submissions (hangs, bombs, forged answers,
  links to the reference...) that must be graded safely.
"""
