# Generated from solutions/__init__.py by tools/generate_exercises.py: edit solutions/, then run `python -m tools.generate_exercises`.
"""Reference engine of the course: real-time 2D collision detection and response.

Conventions (stated once here and on the book's conventions page):

- 2D, y points up, angles in radians, counter-clockwise positive, SI units
  (metres, kilograms, seconds).
- A contact's ``normal`` is a unit vector pointing from shape A to shape B.
- ``depth`` >= 0 is how far the shapes overlap along the normal; touching shapes
  (depth 0) count as colliding.  pymunk's ``distance`` is ``-depth``.
- Polygon vertices are counter-clockwise, so ``perp(edge) = (y, -x)`` points outwards.
- A broad phase returns the set of candidate pairs ``(i, j)`` with ``i < j``.
"""
