"""Oracles a student may hold: plain-data shapes and bodies, seeded random cases,
brute force, pymunk and sympy.  Nothing here imports the reference engine
(``solutions``): the public graded tests and everything they use ship to students.
"""
