"""Making what leaves the instructor's machine (instructors only): the student edition
(``edition``, with its notebooks from ``book``), Gradescope's archive (``gradescope``),
the files each ships (``module_graph``) and the pins each installs (``pins``); the
templates are in ``files/``."""
