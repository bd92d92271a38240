"""The graded-test format: the spec (which tests exist, their points and visibility), the
pytest plugin and fixtures that run them on a student's package through the sandbox,
outcomes and credit, comparisons, replay and shrinking of random cases, failure
pictures.  Ships to students (with the public tests); imports only :mod:`grader.sandbox`
and :mod:`grader.oracles`."""
