# Library file of the collision course (you do not need to edit it).
# Handed out with the course; generated from solutions/response/__init__.py on the instructor's
# side.
"""Collision response: what to do once two bodies are known to touch.

- :mod:`.momentum_1d`: head-on collisions of two point masses (momentum, energy,
  coefficient of restitution e).
- :mod:`.impulse`: one impulse at one contact point between two rigid bodies, with
  its linear and angular parts, and a single-shot response with Coulomb friction.
- :mod:`.positional_correction`: linear projection that removes overlap.
- :mod:`.contact_solver`: sequential impulses over many contacts (the iterative
  solver real engines use), with switches to turn each technique on and off.

Conventions as in :mod:`exercises`: SI units; a contact's normal points from body A to
body B; an impulse ``P`` (N s) is applied as ``+P`` to B and ``-P`` to A.
"""
