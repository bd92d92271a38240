# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/narrowphase/__init__.py on the instructor's
# side.
"""Narrow phase: boolean SAT tests and contact generation for pairs of world shapes.

One concept per module: :mod:`.projection` (projecting onto a candidate axis),
:mod:`.aabb_aabb`, :mod:`.polygon_polygon` (SAT, OBB-OBB and clipping into a 2-point
manifold), :mod:`.circle_polygon` (box normals plus Arvo's nearest-vertex axis),
:mod:`.circle_circle` and :mod:`.dispatch` (any pair, either order).  On the
instructor's side (:mod:`exercises.twins`) numpy and numba twins test and clip many
box pairs at once (``batch_sat``, ``speculative_batch``, ``box_pairs_numba``).

Conventions (see :mod:`exercises`): a contact's normal points from shape A to shape B,
``depth >= 0`` and touching shapes (depth 0) count as colliding.
"""
