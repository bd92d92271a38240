"""Graded tests: ``public/`` (students hold them) and ``hidden/`` (instructor only)."""
