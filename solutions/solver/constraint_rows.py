"""Constraint rows: what the solver kernel needs of every contact point and joint.

A *row* is one scalar velocity constraint between two bodies A and B along a unit
direction ``n``: a contact point's non-penetration (with its friction along the
tangent ``t = (n_y, -n_x)``) or a distance joint's axis.  Rows are grouped: the one or
two points of a contact manifold share their bodies and normal (a group), a joint is
a group of one row.  The kernel (:mod:`solutions.solver.kernel`) visits the groups in
their stored order, which is the sweep order (:func:`solutions.solver.sweep_order.sweep_order`).

Symbols: ``rn = r x n`` and ``rt = r x t`` for the lever arm ``r`` from a body's
centre of mass to the point (m); ``K_n`` the inverse effective mass along ``n``
(1/kg: the change of the row's relative velocity per unit impulse), and the same
along ``t``; the effective masses ``1 / K`` are what the solver exercise's
:func:`~solutions.solver.contact_sweeps.prestep_point` computes.

One visit of a row (:func:`~solutions.solver.contact_point.apply_normal_impulse`)
aims the row's relative velocity at ``target``, the wanted separating velocity
(m/s): restitution, a position bias, or the push of a spring, with its accumulated
impulse kept in ``[lower, inf)``: ``lower = 0`` for a contact (it only pushes),
``-inf`` for a joint (it pulls too).  The *soft constraint* of Box2D v3 (Erin Catto,
"Solver2D") scales a visit by ``mass_scale`` and ``impulse_scale``; ``mass_scale =
1``, ``impulse_scale = 0`` is the rigid constraint of box2d-lite and Box2D v2.  SI
units throughout.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: The block solver needs cond(K) below about this (dimensionless); above it the two
#: normal rows of a manifold are nearly dependent (points close together, or no
#: rotation), the 2x2 solve would amplify rounding, and the points are solved one
#: after the other instead.  Box2D's ``k_maxConditionNumber``.
MAX_CONDITION_NUMBER = 1000.0


@dataclass
class ConstraintRows:
    """Rows and groups in sweep order, as flat arrays (the kernel's input).

    Groups (length g): ``a``, ``b`` body rows (into the velocity array), the
    direction ``nx``, ``ny``, inverse masses ``ima``, ``imb`` (1/kg) and inertias
    ``iia``, ``iib`` (1/(kg m^2)) of A and B, ``first`` row and ``count`` (1 or 2),
    ``block`` (solve the two normal rows together, :func:`block_normal_impulses`) and
    ``K = (k11, k12, k22)`` of those two rows (1/kg; 0 where not ``block``).

    Rows (length m): ``rn_a``, ``rn_b``, ``rt_a``, ``rt_b`` (m), effective masses
    ``mass_normal``, ``mass_tangent`` (kg; 0 where nothing can move), ``friction``
    (mu; 0 for joints), ``lower`` (the accumulated impulse's lower bound, N s).
    """

    a: np.ndarray
    b: np.ndarray
    nx: np.ndarray
    ny: np.ndarray
    ima: np.ndarray
    imb: np.ndarray
    iia: np.ndarray
    iib: np.ndarray
    first: np.ndarray
    count: np.ndarray
    block: np.ndarray
    k11: np.ndarray
    k12: np.ndarray
    k22: np.ndarray
    rn_a: np.ndarray
    rn_b: np.ndarray
    rt_a: np.ndarray
    rt_b: np.ndarray
    mass_normal: np.ndarray
    mass_tangent: np.ndarray
    friction: np.ndarray
    lower: np.ndarray

    GROUP_FIELDS = ("a", "b", "nx", "ny", "ima", "imb", "iia", "iib", "first", "count", "block", "k11", "k12", "k22")
    ROW_FIELDS = ("rn_a", "rn_b", "rt_a", "rt_b", "mass_normal", "mass_tangent", "friction", "lower")

    @property
    def group_count(self) -> int:
        return len(self.first)

    @property
    def row_count(self) -> int:
        return len(self.rn_a)


def normal_block_matrix(ima, imb, iia, iib, rn_a1, rn_b1, rn_a2, rn_b2):
    """``(k11, k12, k22)`` of ``K = J M^-1 J^T`` for the two normal rows of a two-point
    manifold between bodies A and B (1/kg), from the inverse masses and inertias and
    the points' ``r x n``; floats or arrays.

    >>> normal_block_matrix(0.0, 1.0, 0.0, 6.0, 0.0, -0.5, 0.0, 0.5)
    (2.5, -0.5, 2.5)
    """
    k11 = ima + imb + iia * rn_a1 * rn_a1 + iib * rn_b1 * rn_b1
    k22 = ima + imb + iia * rn_a2 * rn_a2 + iib * rn_b2 * rn_b2
    k12 = ima + imb + iia * rn_a1 * rn_a2 + iib * rn_b1 * rn_b2
    return k11, k12, k22


def block_is_well_conditioned(k11, k12, k22):
    """cond(K) < :data:`MAX_CONDITION_NUMBER`, tested as Box2D does (k11^2 < c det K) but
    with the larger diagonal entry, so that the answer does not depend on the point
    order; floats or arrays.

    >>> bool(block_is_well_conditioned(2.5, -0.5, 2.5)), bool(block_is_well_conditioned(1.0, 1.0, 1.0))
    (True, False)
    """
    return np.maximum(k11, k22) ** 2 < MAX_CONDITION_NUMBER * (k11 * k22 - k12 * k12)
