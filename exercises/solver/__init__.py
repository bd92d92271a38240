# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/solver/__init__.py on the instructor's side.
"""The solver core: constraint rows, the one solver kernel that solves them (sequential
impulses, rigid or soft) and its compiled twin, and the order in which it visits them.

- :mod:`.constraint_rows`: what the kernel needs of each contact point and joint.
- :mod:`.kernel`: :func:`~.kernel.solve_constraints`, the readable loop (the teaching text).
- ``kernel_numba``: the same loop compiled by numba (imported only when asked for; on
  the instructor's side only, :mod:`exercises.twins`).
- :mod:`.sweep_order`: the Gauss-Seidel order of the groups.
"""
