"""What a student runs: ``check`` (the public tests), ``submit`` (the hand-in zip and its
manifest), ``update`` (a corrected release merged into the course folder) and the
notebooks' ``%%reference_fallback``.  Ships to students; imports only
:mod:`grader.harness` and below."""
