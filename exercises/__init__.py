# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/__init__.py on the instructor's side.
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
